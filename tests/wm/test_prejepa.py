"""PreJEPA (DINO-WM) on tiny models: shapes of every verb, the frame-causal predictor, the
per-plan encoding cache, checkpoints (ours and upstream's ``_target_`` names), backbones
loaded from local folders only, training with a frozen encoder, and a planning toy."""

from __future__ import annotations

import json

import numpy as np
import pytest
import torch
from _tiny import ACTION_DIM, IMAGE, assert_close, fit_losses, images, randn
from torch import nn

import stable_worldmodel.wm as wm
from stable_worldmodel import keys
from stable_worldmodel.errors import ConfigError, SpaceError, UnknownNameError

A = ACTION_DIM
#: a width-8 frozen patch CNN (2x2 = 4 patches of 8 features) and a one-layer predictor
NET = dict(
    backbone="cnn",
    image_size=IMAGE,
    embed_dim=8,
    cnn_width=8,
    cnn_grid=2,
    depth=1,
    heads=2,
    dim_head=4,
    mlp_dim=16,
    history_size=2,
    frameskip=1,
    action_emb_dim=4,
    proprio_emb_dim=4,
)
P, DV, DP = 4, 8, 3  # patches, pixel features, proprio numbers
#: a one-layer DINOv2 of width 8 with patch 8 (4 patches at 16x16)
DINO = dict(
    hidden_size=8, num_hidden_layers=1, num_attention_heads=2, intermediate_size=16, patch_size=8, image_size=IMAGE
)


def make(seed: int = 0, **overrides) -> nn.Module:
    torch.manual_seed(seed)
    return wm.make("prejepa", "tiny", action_dim=A, **{**NET, **overrides}).eval()


@pytest.fixture
def model():
    return make()


@pytest.fixture
def proprio_model():
    return make(proprio_dim=DP)


def plan_info(b: int, s: int, t: int = 1, proprio: bool = False) -> dict:
    """What a solver passes: each env's context and goal expanded over its S candidates."""
    ctx, goal = images(b, t), images(b, 1, seed=1)
    info = {
        keys.PIXELS: ctx.unsqueeze(1).expand(b, s, *ctx.shape[1:]),
        keys.GOAL: goal.unsqueeze(1).expand(b, s, *goal.shape[1:]),
    }
    if proprio:
        info[keys.PROPRIO] = randn(b, t, DP, seed=2).unsqueeze(1).expand(b, s, t, DP)
        info[keys.GOAL_PROPRIO] = randn(b, 1, DP, seed=3).unsqueeze(1).expand(b, s, 1, DP)
    return info


@pytest.fixture
def dinov2_dir(tmp_path):
    """A tiny random DINOv2 written by ``save_pretrained`` (config.json + model.safetensors)."""
    transformers = pytest.importorskip("transformers")
    torch.manual_seed(0)
    model = transformers.Dinov2Model(transformers.Dinov2Config(**DINO)).eval()
    folder = tmp_path / "dinov2"
    model.save_pretrained(str(folder))
    return folder, model


# -- construction --------------------------------------------------------------------------------
def test_registry_names_and_aliases():
    from stable_worldmodel.wm import dinowm, prejepa

    assert {"prejepa", "dinowm"} <= set(wm.list_models())
    assert wm.get_config_class("dinowm") is wm.get_config_class("prejepa")
    assert dinowm.DINOWM is prejepa.PreJEPA
    assert prejepa.create_backbone is dinowm.create_backbone
    assert type(wm.make("dinowm", "tiny", action_dim=A, **NET)).__name__ == "PreJEPA"


def test_state_dict_uses_upstream_names_and_the_encoder_is_frozen(proprio_model):
    names = set(proprio_model.state_dict())
    assert {
        "predictor.pos_embedding",
        "predictor.transformer.layers.0.0.bias",
        "predictor.transformer.layers.0.0.to_qkv.weight",
        "predictor.transformer.layers.0.1.net.1.weight",
        "predictor.transformer.norm.weight",
        "extra_encoders.action.patch_embed.weight",
        "extra_encoders.proprio.patch_embed.weight",
    } <= names
    assert any(n.startswith("backbone.backbone.") for n in names)
    assert not any(p.requires_grad for p in proprio_model.backbone.parameters())
    proprio_model.train()
    assert not proprio_model.backbone.backbone.training


def test_presets_render_trees_without_building():
    for preset in ("tiny", "small", "paper"):
        tree = wm.get_config("prejepa", preset).target_tree(2)
        assert json.loads(json.dumps(tree)) == tree
    paper = wm.get_config("prejepa", "paper")
    assert (paper.backbone, paper.image_size, paper.frameskip, paper.history_size, paper.num_patches) == (
        "dinov2_small",
        224,
        5,
        3,
        256,
    )
    assert paper.target_tree(2)["predictor"]["dim"] == 384 + 10
    assert wm.get_config("prejepa", "paper", proprio_dim=4).target_tree(2)["predictor"]["dim"] == 384 + 20


# -- verbs -------------------------------------------------------------------------------------
def test_encode_shapes(proprio_model, model):
    info = {keys.PIXELS: images(3, 2), keys.ACTION: randn(3, 2, A), keys.PROPRIO: randn(3, 2, DP)}
    out = proprio_model.encode(info)
    assert out is info
    assert out["pixels_emb"].shape == (3, 2, P, DV)
    assert out["proprio_emb"].shape == out["action_emb"].shape == (3, 2, 4)
    assert out["emb"].shape == (3, 2, P, DV + 8)
    assert_close(
        out["emb"][..., DV : DV + 4], out["proprio_emb"].unsqueeze(2).expand(3, 2, P, 4)
    )  # tiled on every patch
    assert model.encode({keys.PIXELS: images(3, 2)})["emb"].shape == (3, 2, P, DV)  # pixels only, no action


def test_predict_keeps_the_shape_and_is_causal_across_frames(model):
    emb = randn(2, 2, P, DV + 4)
    with torch.no_grad():
        out = model.predict(emb)
        changed = emb.clone()
        changed[:, 1] += randn(2, P, DV + 4, seed=1)
        again = model.predict(changed)
    assert out.shape == emb.shape
    assert_close(again[:, 0], out[:, 0])  # frame 0 never sees frame 1
    assert not torch.allclose(again[:, 1], out[:, 1])


@pytest.mark.parametrize("context", [1, 2])
def test_rollout_shapes(proprio_model, context):
    b, s, h = 2, 3, 4
    info = plan_info(b, s, context, proprio=True)
    with torch.no_grad():
        out = proprio_model.rollout(info, randn(b, s, h, A))
        assert out["predicted_emb"].shape == (b, s, h + 1, P, DV + 8)
        assert out["predicted_pixels_emb"].shape == (b, s, h + 1, P, DV)
        assert out["predicted_proprio_emb"].shape == out["predicted_action_emb"].shape == (b, s, h + 1, 4)
        expected = proprio_model.encode_pixels(info[keys.PIXELS][:, 0])
    assert_close(out["predicted_pixels_emb"][:, :, :context], expected.unsqueeze(1).expand(b, s, context, P, DV))


def test_rollout_first_prediction_is_predict(model):
    pixels, cand = images(2, 1), randn(2, 3, A)
    with torch.no_grad():
        rolled = model.rollout({keys.PIXELS: pixels}, cand)["predicted_emb"]
        assert rolled.shape == (2, 4, P, DV + 4)
        step = model.predict(model.encode({keys.PIXELS: pixels, keys.ACTION: cand[:, :1]})["emb"])
    assert_close(rolled[:, 1, ..., :DV], step[:, -1, ..., :DV], atol=1e-5)  # its action part is the next action's
    with torch.no_grad():
        next_action = model.embed(keys.ACTION, cand[:, 1:2])[:, 0]
    assert_close(rolled[:, 1, 0, DV:], next_action)


def test_get_cost_shape_and_encodes_once_per_info(proprio_model):
    b, s = 2, 4
    info = plan_info(b, s, proprio=True)
    calls: list = []
    proprio_model.backbone.backbone.register_forward_hook(lambda mod, args, out: calls.append(args[0].shape[0]))
    with torch.no_grad():
        first = proprio_model.get_cost(info, randn(b, s, 3, A))
        assert first.shape == (b, s) and torch.isfinite(first).all() and (first >= 0).all()
        assert calls == [b, b]  # the goal and the context, one copy per env
        second = proprio_model.get_cost(info, randn(b, s, 3, A, seed=1))
        assert calls == [b, b]
        again = proprio_model.get_cost(info, randn(b, s, 3, A))
    assert not torch.equal(first, second)
    assert_close(again, first)


def test_get_cost_of_per_env_infos_equals_per_candidate_infos(model):
    b, s = 2, 3
    per_cand = plan_info(b, s)
    per_env = {k: v[:, 0] for k, v in per_cand.items()}
    cand = randn(b, s, 3, A, seed=4)
    with torch.no_grad():
        assert_close(model.get_cost(per_env, cand), model.get_cost(per_cand, cand), atol=1e-5)
        assert model.get_cost(dict(per_env), cand[:, 0]).shape == (b,)


def test_get_cost_min_variant(model):
    model.goal_cost = "min"
    with torch.no_grad():
        assert model.get_cost(plan_info(2, 3), randn(2, 3, 4, A)).shape == (2, 3)


# -- planning toy --------------------------------------------------------------------------------
class _Position(nn.Module):
    """Backbone of the toy: a 2-pixel 'image' ``(N, 2, 1, 1)`` is its position (one patch)."""

    def forward(self, pixels, **kwargs):
        pos = pixels.flatten(1)[:, None]
        return type("Out", (), {"last_hidden_state": torch.cat([pos, pos], dim=1)})()


class _Integrator(nn.Module):
    """Predictor of the toy: next position = position + action (tokens ``[x, y, ax, ay]``)."""

    def forward(self, x):
        return torch.cat([x[..., :2] + x[..., 2:], x[..., 2:]], dim=-1)


def test_cost_prefers_the_actions_that_reach_the_goal():
    from stable_worldmodel.wm.prejepa import Embedder, PreJEPA

    action = Embedder(in_chans=2, emb_dim=2)
    with torch.no_grad():
        action.patch_embed.weight.copy_(torch.eye(2)[:, :, None])
        action.patch_embed.bias.zero_()
    model = PreJEPA(_Position(), _Integrator(), {"action": action}, history_size=1, interpolate_pos_encoding=False)
    start, goal = torch.tensor([0.0, 0.0]), torch.tensor([2.0, 1.0])
    cand = torch.stack(
        [
            torch.tensor([[1.0, 0.0], [1.0, 1.0], [0.0, 0.0]]),  # reaches (2, 1)
            torch.tensor([[1.0, 0.0], [0.0, 0.0], [0.0, 0.0]]),  # stops short
            torch.tensor([[-1.0, 0.0], [-1.0, -1.0], [0.0, 0.0]]),  # goes the other way
        ]
    )[None]  # (1, 3, 3, 2)
    info = {
        keys.PIXELS: start.view(1, 1, 1, 2, 1, 1).expand(1, 3, 1, 2, 1, 1),
        keys.GOAL: goal.view(1, 1, 1, 2, 1, 1).expand(1, 3, 1, 2, 1, 1),
    }
    cost = model.get_cost(info, cand)
    assert cost.argmin().item() == 0 and cost[0, 0] == 0
    assert cost[0, 1] < cost[0, 2]


# -- training ------------------------------------------------------------------------------------
def test_loss_terms(proprio_model, dot_data):
    batch = {**dot_data(4, 3), keys.PROPRIO: randn(4, 3, DP)}
    proprio_model.train()
    out = proprio_model.loss(batch)
    assert set(out) == {"loss", "pixels_loss", "proprio_loss", "emb"}
    assert out["emb"].shape == (4, 3, P, DV + 8)
    # the total is the MSE over the pixel and proprio features together (not the action part)
    n_pix, n_pro = P * DV, P * 4
    assert_close(out["loss"], (n_pix * out["pixels_loss"] + n_pro * out["proprio_loss"]) / (n_pix + n_pro), rtol=1e-4)
    out["loss"].backward()
    assert all(p.grad is not None for p in proprio_model.predictor.parameters())
    assert all(p.grad is None for p in proprio_model.backbone.parameters())


def test_loss_decreases(dot_data):
    model = make().train()
    batch = dot_data(8, 3)
    losses = fit_losses(model, batch)
    assert losses[-1] < 0.5 * losses[0], losses


def test_loss_needs_the_proprio_column(proprio_model, dot_data):
    with pytest.raises(UnknownNameError, match="'proprio'"):
        proprio_model.loss(dot_data(2, 3))


def test_trains_with_proprio_through_the_trainer(_stablewm_home):
    from stable_worldmodel.data.writer import HDF5Writer
    from stable_worldmodel.train import train

    rng = np.random.default_rng(0)
    _stablewm_home.mkdir(parents=True, exist_ok=True)
    with HDF5Writer(_stablewm_home / "prop.h5") as writer:
        writer.write_episodes(
            [
                {
                    "pixels": rng.integers(0, 256, (6, IMAGE, IMAGE, 3), dtype=np.uint8),
                    "action": rng.normal(size=(6, 2)).astype(np.float32),
                    "proprio": rng.normal(size=(6, DP)).astype(np.float32),
                }
                for _ in range(3)
            ]
        )
    result = train(
        "prejepa",
        "prop",
        steps=3,
        batch_size=4,
        progress=False,
        name="p",
        val_every=0,
        **NET,
        proprio_dim=DP,
        warmup_steps=0,
    )
    protocol = json.loads((result.folder / "protocol.json").read_text())
    assert set(protocol["normalizers"]) == {"action", "proprio"}
    assert np.isfinite(result.train_loss)
    with pytest.raises(ConfigError, match="proprio_dim"):
        train("prejepa", "prop", steps=1, batch_size=4, progress=False, name="q", **NET, proprio_dim=DP + 1)


# -- checkpoints ---------------------------------------------------------------------------------
def test_save_load_round_trip(proprio_model):
    cfg = wm.get_config("prejepa", "tiny", **NET, proprio_dim=DP)
    wm.save_pretrained(proprio_model, "pj", config=cfg.target_tree(A))
    loaded = wm.load_pretrained("pj")
    info = plan_info(2, 3, proprio=True)
    cand = randn(2, 3, 3, A)
    with torch.no_grad():
        assert torch.equal(loaded.get_cost(dict(info), cand), proprio_model.get_cost(dict(info), cand))


def test_upstream_target_names_load(dinov2_dir, _stablewm_home):
    """A config.json as upstream's DINO-WM runs write it: package-level PreJEPA, spt's EvalOnly,
    create_backbone by alias only (found in $STABLEWM_HOME/backbones/), a ModuleDict of Embedders."""
    import shutil

    from stable_worldmodel.wm.backbones import backbone_dir

    folder, _ = dinov2_dir
    shutil.copytree(folder, backbone_dir("dinov2_small"))
    tree = {
        "_target_": "stable_worldmodel.wm.PreJEPA",
        "encoder": {
            "_target_": "stable_pretraining.backbone.EvalOnly",
            "backbone": {"_target_": "stable_worldmodel.wm.prejepa.module.create_backbone", "name": "dinov2_small"},
        },
        "predictor": {
            "_target_": "stable_worldmodel.wm.prejepa.module.CausalPredictor",
            "num_patches": 4,
            "num_frames": 2,
            "dim": 8 + 4,
            "depth": 1,
            "heads": 2,
            "mlp_dim": 16,
            "dim_head": 4,
        },
        "extra_encoders": {
            "_target_": "torch.nn.ModuleDict",
            "modules": {
                "action": {"_target_": "stable_worldmodel.wm.prejepa.module.Embedder", "in_chans": A, "emb_dim": 4}
            },
        },
        "history_size": 2,
        "num_pred": 1,
        "interpolate_pos_encoding": True,
    }
    torch.manual_seed(0)
    built = wm.instantiate(tree).eval()
    wm.save_pretrained(built, "upstream", config=tree)
    loaded = wm.load_pretrained("upstream")
    pixels = images(2, 1)
    with torch.no_grad():
        assert loaded.encode({keys.PIXELS: pixels})["emb"].shape == (2, 1, 4, 8)
        assert torch.equal(
            loaded.rollout({keys.PIXELS: pixels}, randn(2, 2, A))["predicted_emb"],
            built.rollout({keys.PIXELS: pixels}, randn(2, 2, A))["predicted_emb"],
        )


# -- backbones -----------------------------------------------------------------------------------
def test_dinov2_loads_from_a_local_folder_and_file(dinov2_dir):
    from stable_worldmodel.wm.backbones import create_backbone

    folder, reference = dinov2_dir
    x = images(2)
    with torch.no_grad():
        expected = reference(x).last_hidden_state
        for path in (folder, folder / "model.safetensors"):
            loaded = create_backbone("dinov2_small", path=path).eval()
            assert_close(loaded(x, interpolate_pos_encoding=True).last_hidden_state, expected)
    model = make(
        backbone="dinov2_small",
        pretrained=True,
        backbone_path=str(folder),
        backbone_overrides={"hidden_size": 8, "patch_size": 8},
    )
    with torch.no_grad():
        out = model.encode({keys.PIXELS: x[:, None]})
    assert_close(out["pixels_emb"][:, 0], expected[:, 1:])  # the patch tokens, CLS dropped


def test_random_backbones_of_each_family():
    pytest.importorskip("transformers")
    from stable_worldmodel.wm.backbones import create_backbone

    x = images(2)
    small = dict(
        hidden_size=8, num_hidden_layers=1, num_attention_heads=2, intermediate_size=16, patch_size=8, image_size=IMAGE
    )
    assert create_backbone("dinov2_small", pretrained=False, **small)(x).last_hidden_state.shape == (2, 5, 8)
    assert create_backbone("vit_base_patch16", pretrained=False, **small)(x).last_hidden_state.shape == (2, 5, 8)
    resnet = create_backbone(
        "resnet_50", pretrained=False, hidden_sizes=[8, 8, 8, 8], embedding_size=8, depths=[1, 1, 1, 1]
    )
    assert isinstance(resnet.classifier[1], nn.LayerNorm) and resnet(x).logits.shape == (2, 8)
    assert create_backbone("cnn", image_size=IMAGE, width=8, hidden_size=8, grid=2)(x).last_hidden_state.shape == (
        2,
        5,
        8,
    )


def test_blur_backbone_tokens_are_the_blurred_pooled_picture():
    from stable_worldmodel.wm.backbones import create_backbone

    enc = create_backbone("blur", image_size=IMAGE, sigma=0.5, pool=2, grid=2)
    assert not list(enc.parameters())  # nothing to train; standardization is the identity until fitted
    assert torch.equal(enc.mean, torch.zeros_like(enc.mean)) and torch.equal(enc.scale, torch.ones_like(enc.scale))
    x = images(2, 1)[:, 0]
    out = enc(x).last_hidden_state
    assert out.shape == (2, 1 + 4, 3 * 4 * 4)  # 16 px pooled by 2 = 8 x 8, cut in 2 x 2 cells of 3 x 4 x 4
    assert_close(out[:, 0], out[:, 1:].mean(1))
    # token (row 0, col 1) is the top-right 4 x 4 cell of the pooled picture, channel-major
    flat = torch.zeros(1, 3, IMAGE, IMAGE)
    flat[0, 1, :8, 8:] = 1.0  # green in the top-right quarter only
    tokens = create_backbone("blur", image_size=IMAGE, sigma=1e-3, pool=2, grid=2)(flat).last_hidden_state[0, 1:]
    assert torch.count_nonzero(tokens[[0, 2, 3]]) == 0
    assert (
        torch.equal(tokens[1].reshape(3, 4, 4)[1], torch.ones(4, 4))
        and torch.count_nonzero(tokens[1].reshape(3, 4, 4)[[0, 2]]) == 0
    )


def test_blur_features_grow_with_the_distance_between_dots():
    """What the tiny preset needs: the farther the dot from the goal's, the larger the cost (up
    to about 4 sigma, where the blurred dots stop overlapping and the cost levels off)."""
    from stable_worldmodel.wm.backbones import create_backbone

    enc = create_backbone("blur", image_size=32, pool=4, grid=2)  # sigma 32 / 8 = 4 px

    def dot(col: int) -> torch.Tensor:
        img = torch.zeros(1, 3, 32, 32)
        img[0, :, 14:18, col : col + 3] = 1.0
        return enc(img).last_hidden_state[0, 1:]

    goal = dot(4)
    costs = [float((dot(c) - goal).pow(2).mean()) for c in range(4, 21, 2)]
    assert all(a < b for a, b in zip(costs, costs[1:], strict=False)), costs


def _dot_frames(size: int) -> tuple[np.ndarray, torch.Tensor]:
    """A 3 x 3 white dot on black at every third row and column: positions (N, 2), frames (N, 3, size, size)."""
    pos = np.array([(r, c) for r in range(2, size - 5, 3) for c in range(2, size - 5, 3)])
    frames = torch.full((len(pos), 3, size, size), -1.0)
    for i, (r, c) in enumerate(pos):
        frames[i, :, r : r + 3, c : c + 3] = 1.0
    return pos, frames


def _distance_follows_separation(name: str, seed: int, size: int = 32) -> float:
    """Mean over dots of the correlation between the distance to the other dots (within a third
    of the picture) and the feature distance to them, for a random backbone ``name``."""
    from stable_worldmodel.wm.backbones import create_backbone

    torch.manual_seed(seed)  # cnn draws from the global RNG, cnn_aa from its own seed
    enc = create_backbone(
        name, image_size=size, width=8, hidden_size=8, grid=2, **({"seed": seed} if name == "cnn_aa" else {})
    ).eval()
    pos, frames = _dot_frames(size)
    with torch.no_grad():
        feats = enc(frames).last_hidden_state[:, 1:].flatten(1)
    corr = []
    for i in range(len(pos)):
        sep = np.hypot(*(pos - pos[i]).T)
        near = sep <= size / 3
        corr.append(np.corrcoef(sep[near], (feats - feats[i]).pow(2).sum(1).numpy()[near])[0, 1])
    return float(np.mean(corr))


def test_antialiased_cnn_backbone_shapes_and_state():
    from stable_worldmodel.wm.backbones import create_backbone
    from stable_worldmodel.wm.prejepa.module import AntialiasedPatchCNN, binomial_taps

    assert torch.equal(binomial_taps(3), torch.tensor([0.25, 0.5, 0.25])) and torch.equal(
        binomial_taps(1), torch.ones(1)
    )
    assert_close(binomial_taps(5), torch.tensor([1.0, 4, 6, 4, 1]) / 16)
    torch.manual_seed(0)
    enc = create_backbone("cnn_aa", image_size=IMAGE, width=8, hidden_size=8, grid=2, taps=3)
    assert isinstance(enc, AntialiasedPatchCNN) and len(enc.stages) == 3  # 16 -> 8 -> 4 -> 2
    out = enc(images(2, 1)[:, 0]).last_hidden_state
    assert out.shape == (2, 1 + 4, 8)
    assert_close(out[:, 0], out[:, 1:].mean(1))
    state = enc.state_dict()
    assert {"mean", "scale", "head.weight", "stages.0.0.weight"} <= set(state) and "taps" not in state
    with pytest.raises(ConfigError, match="image_size = grid \\* 2\\*\\*k"):
        create_backbone("cnn_aa", image_size=12, grid=8)
    with pytest.raises(ConfigError, match="taps"):
        create_backbone("cnn_aa", image_size=IMAGE, taps=0)
    with pytest.raises(SpaceError, match="16, 16"):
        enc(torch.zeros(1, 3, 8, 8))
    # the weights are a function of the config (seed 0 by default), not of the global RNG
    torch.manual_seed(1)
    again = create_backbone("cnn_aa", image_size=IMAGE, width=8, hidden_size=8, grid=2, taps=3)
    assert all(torch.equal(v, again.state_dict()[k]) for k, v in state.items())
    assert float(torch.rand(1)) == float(
        torch.rand(1, generator=torch.Generator().manual_seed(1))
    )  # caller's RNG untouched
    other = create_backbone("cnn_aa", image_size=IMAGE, width=8, hidden_size=8, grid=2, taps=3, seed=1)
    assert not torch.equal(other.head.weight, enc.head.weight)
    with pytest.raises(ConfigError, match="seed to be an int >= 0 or None"):
        create_backbone("cnn_aa", image_size=IMAGE, seed=-1)


def test_antialiased_cnn_features_follow_how_far_apart_dots_are():
    """Why the tiny preset low-passes its random CNN: the feature distance between two frames of a
    dot tracks the dot's displacement (correlation ~0.8 over 5 seeds), where a plain strided random
    CNN's barely does (~0.2)."""
    for seed in range(3):
        assert _distance_follows_separation("cnn_aa", seed) > 0.65
        assert _distance_follows_separation("cnn", seed) < 0.45


def test_antialiased_cnn_standardizes_once_fitted():
    from stable_worldmodel.wm.backbones import create_backbone

    torch.manual_seed(0)
    enc = create_backbone("cnn_aa", image_size=IMAGE, width=8, hidden_size=8, grid=2)
    frames = images(12, 1)[:, 0]
    raw = enc(frames).last_hidden_state[:, 1:]
    enc.fit_to_frames(frames)
    fitted = enc(frames).last_hidden_state[:, 1:]
    assert_close(fitted.mean(0), torch.zeros_like(fitted[0]), atol=1e-5, rtol=0)
    assert_close(fitted.std(0), torch.ones_like(fitted[0]), atol=1e-4, rtol=0)
    assert_close(fitted * enc.scale + enc.mean, raw, atol=1e-5, rtol=0)
    with pytest.raises(SpaceError, match="AntialiasedPatchCNN.fit_to_frames requires at least 2 frames"):
        enc.fit_to_frames(frames[:1])


def test_blur_backbone_standardizes_each_value_once_fitted():
    from stable_worldmodel.wm.backbones import create_backbone

    enc = create_backbone("blur", image_size=IMAGE, pool=2, grid=2)
    frames = images(12, 1)[:, 0]
    raw = enc(frames).last_hidden_state[:, 1:]
    enc.fit_to_frames(frames)
    assert set(enc.state_dict()) == {"mean", "scale"}  # saved with the model, so planning sees the same features
    fitted = enc(frames).last_hidden_state[:, 1:]
    assert_close(fitted.mean(0), torch.zeros_like(fitted[0]), atol=1e-5, rtol=0)
    assert_close(fitted.std(0), torch.ones_like(fitted[0]), atol=1e-4, rtol=0)
    assert_close(fitted * enc.scale + enc.mean, raw, atol=1e-6, rtol=0)
    static = torch.zeros(4, 3, IMAGE, IMAGE)
    static[1:, 0, :4, :4] = 1.0  # a value no frame changes gets the floor, not a division by zero
    enc.fit_to_frames(static)
    assert torch.isfinite(enc(static).last_hidden_state).all()
    with pytest.raises(SpaceError, match="at least 2 frames"):
        enc.fit_to_frames(frames[:1])


def test_training_fits_the_blur_encoder_to_the_training_split(toy, _stablewm_home):
    from stable_worldmodel.train import train

    net = {**NET, "backbone": "blur", "blur_pool": 2}
    result = train("prejepa", toy, steps=2, progress=False, name="pj-blur", val_every=0, seed=0, **net)
    loaded = wm.load_pretrained("pj-blur")
    enc = loaded.frozen_encoder().backbone
    assert not torch.equal(enc.scale, torch.ones_like(enc.scale)) and result.features.computed
    from stable_worldmodel.data import HDF5Dataset

    protocol = json.loads((result.folder / "protocol.json").read_text())
    data = HDF5Dataset(toy)
    rows = np.concatenate(
        [
            np.arange(o, o + n)
            for o, n in zip(
                np.asarray(data.offsets)[protocol["train_episodes"]],
                np.asarray(data.lengths)[protocol["train_episodes"]],
                strict=False,
            )
        ]
    )
    pixels = torch.from_numpy(np.concatenate([data._read("pixels", int(r), int(r) + 1) for r in rows])).permute(
        0, 3, 1, 2
    )
    with torch.no_grad():
        feats = loaded.encode_pixels(((pixels.float() / 255 - 0.5) / 0.5)[:, None])[:, 0]
    assert_close(feats.mean(0), torch.zeros_like(feats[0]), atol=2e-3, rtol=0)  # standardized over the training frames
    assert 0.9 < float(feats.std(0).max()) < 1.1


def test_tiny_preset_uses_the_random_antialiased_cnn():
    from stable_worldmodel.wm.prejepa.module import AntialiasedPatchCNN

    cfg = wm.get_config("prejepa", "tiny")
    assert (cfg.backbone, cfg.pretrained, cfg.num_patches, cfg.encoder_dim) == ("cnn_aa", False, 4, 64)
    model = wm.instantiate(cfg.target_tree(2)).eval()
    assert isinstance(model.frozen_encoder().backbone, AntialiasedPatchCNN)
    with torch.no_grad():
        emb = model.encode({keys.PIXELS: torch.rand(1, 1, 3, 64, 64), keys.ACTION: torch.zeros(1, 1, 10)})
    assert emb["pixels_emb"].shape == (1, 1, 4, 64)
    with pytest.raises(ConfigError, match="pretrained=False with backbone 'cnn_aa'"):
        wm.get_config("prejepa", "tiny", pretrained=True)


def test_blur_config_errors():
    cfg = wm.get_config("prejepa", "tiny", backbone="blur", blur_pool=8)
    assert (cfg.num_patches, cfg.encoder_dim) == (4, 48)
    with pytest.raises(ConfigError, match="divisible by blur_pool \\* cnn_grid"):
        wm.get_config("prejepa", "tiny", backbone="blur", image_size=60)
    with pytest.raises(ConfigError, match="blur_sigma >= 0"):
        wm.get_config("prejepa", "tiny", blur_sigma=-1.0)
    with pytest.raises(ConfigError, match="pretrained=False with backbone 'blur'"):
        wm.get_config("prejepa", "tiny", backbone="blur", pretrained=True)


def test_missing_weights_name_where_to_put_them():
    pytest.importorskip("transformers")
    from stable_worldmodel.wm.backbones import backbone_dir, create_backbone

    with pytest.raises(ConfigError) as err:
        create_backbone("dinov2_small")
    assert str(backbone_dir("dinov2_small")) in str(err.value) and "facebook/dinov2-small" in str(err.value)
    with pytest.raises(ConfigError, match="nowhere"):
        create_backbone("dinov2_small", path="/nowhere/dinov2")


# -- bad inputs ----------------------------------------------------------------------------------
def test_bad_inputs_raise_typed_errors(model):
    from stable_worldmodel.wm.backbones import create_backbone
    from stable_worldmodel.wm.prejepa import CausalPredictor, Embedder

    with pytest.raises(UnknownNameError, match="dinov2_small"):
        create_backbone("dinov2_smal")
    with pytest.raises(UnknownNameError, match="dinov2_smal"):
        wm.get_config("prejepa", backbone="dinov2_smal")
    with pytest.raises(ConfigError, match="proprio_dim"):
        wm.get_config("prejepa", proprio_dim=-1)
    with pytest.raises(ConfigError, match="pretrained"):
        wm.get_config("prejepa", pretrained=True)  # the CNN has no pretrained weights
    with pytest.raises(ConfigError, match="at least 2 actions"):
        model.rollout({keys.PIXELS: images(2, 2)}, randn(2, 1, A))
    with pytest.raises(UnknownNameError, match="'goal'"):
        model.get_cost({keys.PIXELS: images(2, 1)}, randn(2, 3, 2, A))
    with pytest.raises(SpaceError, match=r"\(B, T, 2\)"):
        Embedder(in_chans=2, emb_dim=4)(randn(2, 3, 5))
    with pytest.raises(SpaceError, match="num_frames=2"):
        CausalPredictor(num_patches=2, num_frames=2, dim=8, depth=1, heads=2, mlp_dim=8, dim_head=4)(randn(1, 6, 8))
    with pytest.raises(ConfigError, match="dim_head"):
        CausalPredictor(num_patches=2, num_frames=2, dim=8, depth=1, heads=2, mlp_dim=8, dim_head=0)
    with pytest.raises(SpaceError, match="16, 16"):
        model.encode({keys.PIXELS: randn(1, 1, 3, 8, 8)})
    with pytest.raises(ConfigError, match="is_video"):
        model.encode({keys.PIXELS: images(1, 1)}, is_video=True)


def test_configs_need_no_torch():
    import subprocess
    import sys

    code = (
        "import sys; sys.modules['torch'] = sys.modules['transformers'] = None  # any import fails fast\n"
        "import stable_worldmodel.wm as wm\n"
        "[wm.get_config('prejepa', p).target_tree(2) for p in ('tiny', 'small', 'paper')]"
    )
    subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True, timeout=120)

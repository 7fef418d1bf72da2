"""Goal-conditioned baselines (``stable_worldmodel.wm.gcrl``, ``stable_worldmodel.wm.gcbc``): shapes of
every method at 16x16 with width-8 nets, upstream 0.1.1's state-dict names, checkpoint round trips,
an upstream-style ``config.json``, hindsight goals, training on recorded toy data, and the errors."""

from __future__ import annotations

import json

import numpy as np
import pytest
import torch
from _tiny import ACTION_DIM, IMAGE, assert_close, images, randn

import stable_worldmodel.wm as wm
from stable_worldmodel import keys
from stable_worldmodel.errors import CheckpointError, ConfigError, DatasetFormatError, SpaceError, UnknownNameError
from stable_worldmodel.wm.gcrl.module import (
    DoublePredictorWrapper,
    Embedder,
    ExpectileLoss,
    MetricValuePredictor,
    Predictor,
    QPredictor,
    TeacherStudentWrapper,
)
from stable_worldmodel.wm.utils import instantiate, load_pretrained, save_pretrained

ALGOS = ("gcbc", "gcivl", "gciql")
#: a width-8 CNN policy at 16x16 (one token per frame), three layers: self, cross (goal), frame aggregation
NET = dict(
    image_size=IMAGE,
    embed_dim=8,
    cnn_width=8,
    depth=3,
    heads=2,
    dim_head=4,
    mlp_dim=16,
    history_size=2,
    q_hidden=8,
    metric_dim=8,
)
#: the ViT variant (patch 8: 4 patches + CLS, width 8)
VIT = dict(
    NET,
    encoder="vit",
    patch_size=8,
    vit_overrides={"hidden_size": 8, "num_hidden_layers": 1, "num_attention_heads": 2, "intermediate_size": 16},
)
B = 3


def config(name: str, **overrides):
    return wm.get_config(name, "tiny", **{**NET, **overrides})


def build(name: str, seed: int = 0, **overrides) -> torch.nn.Module:
    torch.manual_seed(seed)
    return instantiate(config(name, **overrides).target_tree(ACTION_DIM))


def batch(name: str, seed: int = 0, **overrides) -> dict:
    """A batch as TrainData gives it: ``num_steps`` frames, actions, one goal per sample
    (sample 0's goal is its frame 1)."""
    t = config(name, **overrides).num_steps
    out = {
        keys.PIXELS: images(B, t, seed=seed),
        keys.ACTION: randn(B, t, ACTION_DIM, seed=seed + 1),
        "goal_pixels": images(B, 1, seed=seed + 2),
    }
    out["goal_pixels"][0, 0] = out[keys.PIXELS][0, 1]
    return out


def act_info(t: int = 2) -> dict:
    return {keys.PIXELS: images(B, t, seed=5), keys.GOAL: images(B, 1, seed=6)}


# -- shapes --------------------------------------------------------------------------------------
@pytest.mark.parametrize("name", ALGOS)
def test_every_method_has_the_documented_shapes(name):
    model = build(name).eval()
    info = model.encode(act_info(), target="embed")
    assert info["embed"].shape == (B, 2, 1, 8) and info["pixels_embed"].shape == (B, 2, 1, 8)
    goal = model.encode({keys.PIXELS: images(B, 1, seed=6)})["embed"]
    means, stds = model.predict_actions(info["embed"], goal)
    assert means.shape == (B, 2, ACTION_DIM) and stds.shape == (ACTION_DIM,)
    assert model.get_action(act_info()).shape == (B, ACTION_DIM)
    assert model.get_action(act_info(), sample=True).shape == (B, ACTION_DIM)
    if name != "gcbc":
        assert model.predict_values(info["embed"], goal).shape == (B, 2, 1)
    out = model.train().loss(batch(name))
    terms = {
        "gcbc": {"action_loss"},
        "gcivl": {"value_loss", "actor_loss"},
        "gciql": {"value_loss", "critic_loss", "actor_loss"},
    }[name]
    assert terms <= set(out) and out["loss"].ndim == 0 and torch.isfinite(out["loss"])
    assert out["emb"].shape == (B, config(name).num_steps, 1, 8)
    out["loss"].backward()
    assert model.encoder.head.weight.grad is not None  # the encoder learns from the BC / value loss


def test_get_action_uses_the_last_history_frames_and_goal():
    model = build("gcbc").eval()
    base = act_info()
    longer = {
        keys.PIXELS: torch.cat([images(B, 3, seed=9), base[keys.PIXELS]], 1),
        keys.GOAL: torch.cat([images(B, 1, seed=1), base[keys.GOAL]], 1),
    }
    assert_close(model.get_action(longer), model.get_action(act_info()))


def test_vit_encoder_gives_one_token_per_patch():
    pytest.importorskip("transformers")
    model = build("gcivl", **{k: v for k, v in VIT.items() if k not in NET or VIT[k] != NET[k]}).eval()
    info = model.encode(act_info())
    assert info["embed"].shape == (B, 2, 4, 8)  # (16 / 8)^2 patches, CLS dropped
    assert model.get_action(act_info()).shape == (B, ACTION_DIM)
    assert torch.isfinite(model.train().loss(batch("gcivl"))["loss"])


def test_heads_shapes_and_upstream_parameter_names():
    kw = dict(num_patches=4, num_frames=3, dim=8, depth=3, heads=2, mlp_dim=16, dim_head=4)
    x, g, a = randn(2, 12, 8), randn(2, 4, 8, seed=1), randn(2, 3, 5, seed=2)
    policy = Predictor(out_dim=5, **kw)
    assert policy(x, g).shape == (2, 3, 5) and policy(x[:, :8], g).shape == (2, 2, 5)  # fewer frames: causal prefix
    assert Predictor(out_dim=1, pool_type="mean", **kw)(x, g).shape == (2, 3, 1)
    assert QPredictor(action_dim=5, q_hidden_dim=8, **kw)(x, a, g).shape == (2, 3, 1)
    metric = MetricValuePredictor(embed_dim=4, **kw)
    value = metric(x, g)
    assert value.shape == (2, 3, 1) and bool((value < 0).all())
    assert Embedder(in_chans=4, emb_dim=6)(randn(2, 3, 4)).shape == (2, 3, 6)
    first, second = DoublePredictorWrapper(Predictor, out_dim=1, **kw)(x, g)
    assert first.shape == second.shape == (2, 3, 1) and not torch.equal(first, second)
    names = set(policy.state_dict())
    assert {
        "pos_embedding",
        "pos_embedding_goal",
        "out_proj.weight",
        "transformer.norm.weight",
        "transformer.layers.0.0.causal_mask",
        "transformer.layers.0.0.to_q.weight",
        "transformer.layers.0.0.to_kv.weight",
        "transformer.layers.1.0.norm_c.weight",
        "transformer.layers.2.0.frame_tokens",
        "transformer.layers.2.1.net.4.bias",
    } <= names
    assert policy.transformer.layers[0][0].causal_mask.shape == (1, 1, 12, 12)
    assert "q_head.4.weight" in QPredictor(action_dim=5, **kw).state_dict()
    assert "embed_proj.weight" in metric.state_dict()


def test_block_causal_heads_ignore_later_frames():
    p = Predictor(out_dim=2, num_patches=2, num_frames=3, dim=8, depth=3, heads=2, mlp_dim=16, dim_head=4).eval()
    x, g = randn(1, 6, 8), randn(1, 2, 8, seed=1)
    changed = x.clone()
    changed[:, 4:] += randn(1, 2, 8, seed=2)  # the last frame's two tokens
    assert_close(p(changed, g)[:, :2], p(x, g)[:, :2])
    assert not torch.allclose(p(changed, g)[:, 2], p(x, g)[:, 2])


def test_expectile_loss_weights_the_two_sides():
    preds, targets = torch.zeros(3), torch.tensor([1.0, -1.0, 2.0])
    assert float(ExpectileLoss(0.7)(preds, targets)) == pytest.approx((0.7 + 0.3 + 0.7 * 4) / 3)
    assert float(ExpectileLoss(0.9)(preds, targets, adv=-torch.ones(3))) == pytest.approx(0.1 * 6 / 3)
    with pytest.raises(ConfigError, match="0 < tau < 1"):
        ExpectileLoss(1.5)


def test_teacher_is_an_exponential_moving_average():
    student = torch.nn.Linear(2, 1)
    wrapper = TeacherStudentWrapper(student, base_ema_coefficient=0.9, final_ema_coefficient=0.9)
    assert torch.equal(wrapper.teacher.weight, student.weight) and not wrapper.teacher.weight.requires_grad
    before = wrapper.teacher.weight.detach().clone()
    with torch.no_grad():
        student.weight.add_(1.0)
    wrapper.update_teacher()
    assert_close(wrapper.teacher.weight, 0.9 * before + 0.1 * student.weight.detach())
    assert {
        "student.weight",
        "teacher.weight",
        "ema_coefficient",
        "base_ema_coefficient",
        "final_ema_coefficient",
    } <= set(wrapper.state_dict())


def test_training_loss_moves_the_teacher_only_in_training_mode():
    model = build("gcivl")
    teacher = model.value_predictor.teacher.out_proj.weight
    with torch.no_grad():
        model.value_predictor.student.out_proj.weight.add_(1.0)
    before = teacher.detach().clone()
    model.eval().loss(batch("gcivl"))
    assert torch.equal(teacher, before)
    model.train().loss(batch("gcivl"))
    assert not torch.equal(teacher, before)


@pytest.mark.parametrize("name", ["gcivl", "gciql"])
def test_actor_trains_the_encoder_only_when_asked(name):
    """Upstream freezes the encoder for the actor (``actor_encoder_grad=False``); our presets let it learn."""
    assert config(name).actor_encoder_grad is True
    for flag in (False, True):
        model = build(name, actor_encoder_grad=flag).train()
        model.loss(batch(name))["actor_loss"].backward()
        assert (model.encoder.head.weight.grad is not None) is flag
        assert (
            model.action_predictor.out_proj.weight.grad is not None
            and model.value_predictor.student.out_proj.weight.grad is None
        )


def test_extra_encoders_join_every_token():
    model = build("gcbc")
    model.extra_encoders["proprio"] = Embedder(in_chans=2, emb_dim=3)
    info = model.encode({keys.PIXELS: images(B, 2), keys.PROPRIO: randn(B, 2, 2)})
    assert info["embed"].shape == (B, 2, 1, 11) and info["proprio_embed"].shape == (B, 2, 3)
    with pytest.raises(UnknownNameError, match="goal_proprio"):
        model.encode({keys.PIXELS: images(B, 1)}, prefix="goal_")


def test_gcbc_of_release_003():
    tree = {
        "_target_": "stable_worldmodel.wm.gcbc.GCBC",
        "encoder": {
            "_target_": "stable_worldmodel.wm.gcrl.module.ConvLogitsEncoder",
            "image_size": IMAGE,
            "width": 8,
            "hidden_size": 8,
        },
        "predictor": {
            "_target_": "stable_worldmodel.wm.gcbc.Predictor",
            "num_patches": 1,
            "num_frames": 2,
            "dim": 8,
            "depth": 3,
            "heads": 2,
            "mlp_dim": 16,
            "dim_head": 4,
            "action_dim": ACTION_DIM,
        },
        "history_size": 2,
    }
    torch.manual_seed(0)
    model = instantiate(tree)
    assert type(model) is wm.GCBC
    assert {
        "backbone.head.weight",
        "predictor.action_proj.weight",
        "predictor.transformer.layers.2.0.out_token",
    } <= set(model.state_dict())
    assert model.predict(
        model.encode(act_info())["embed"], model.encode({keys.PIXELS: images(B, 1)})["embed"]
    ).shape == (B, 1, ACTION_DIM)
    assert model.get_action(act_info()).shape == (B, ACTION_DIM)
    out = model.train().loss(batch("gcbc"))
    out["loss"].backward()
    assert (
        model.backbone.head.weight.grad is None and model.predictor.action_proj.weight.grad is not None
    )  # frozen backbone


def test_the_two_gcbcs_refuse_each_others_weights_by_name():
    """``make("gcbc")`` (0.1.1's GCRL) and ``swm.wm.GCBC`` (0.0.3) share a name: loading one's
    weights into the other names the right class, not a list of missing keys."""
    gcrl = build("gcbc")
    old = instantiate(
        {
            "_target_": "stable_worldmodel.wm.gcbc.GCBC",
            "encoder": {"_target_": "stable_worldmodel.wm.gcrl.module.ConvLogitsEncoder", "image_size": IMAGE},
            "predictor": {
                "_target_": "stable_worldmodel.wm.gcbc.Predictor",
                **dict(num_patches=1, num_frames=2, dim=8, depth=1, heads=2, mlp_dim=16, dim_head=4),
                "action_dim": ACTION_DIM,
            },
        }
    )
    with pytest.raises(CheckpointError, match=r"GCBC weights \(predictor\.\*\), got the weights of a GCRL.*GCRL$"):
        old.load_state_dict(gcrl.state_dict())
    with pytest.raises(CheckpointError, match=r"GCRL weights .*release 0\.0\.3's GCBC.*swm\.wm\.GCBC"):
        gcrl.load_state_dict(old.state_dict())
    gcrl.load_state_dict(build("gcbc", seed=1).state_dict())  # its own family loads as before
    old.load_state_dict(old.state_dict())


# -- checkpoints ---------------------------------------------------------------------------------
@pytest.mark.parametrize("name", ALGOS)
def test_checkpoint_round_trip_gives_identical_outputs(name, _stablewm_home):
    model = build(name)
    model.train().loss(batch(name))["loss"].backward()  # moves nothing, but exercises the training path first
    tree = config(name).target_tree(ACTION_DIM)
    save_pretrained(model, f"run-{name}", config=tree)
    loaded = load_pretrained(f"run-{name}")
    assert type(loaded) is wm.GCRL and loaded.algorithm == name and not loaded.training
    model.eval()
    assert torch.equal(loaded.get_action(act_info()), model.get_action(act_info()))
    if name != "gcbc":
        assert torch.equal(loaded.loss(batch(name))["loss"], model.loss(batch(name))["loss"])
    state = model.state_dict()
    assert loaded.state_dict().keys() == state.keys() and all(
        torch.equal(v, state[k]) for k, v in loaded.state_dict().items()
    )


def test_upstream_style_config_json_loads(_stablewm_home):
    """A config.json as upstream 0.1.1's gcivl script would build the model (HF ViT through
    stable_pretraining, the value head in stable_pretraining's TeacherStudentWrapper)."""
    pytest.importorskip("transformers")
    head = {
        "num_patches": 4,
        "num_frames": 2,
        "dim": 8,
        "depth": 3,
        "heads": 2,
        "mlp_dim": 16,
        "dim_head": 4,
        "dropout": 0.0,
        "emb_dropout": 0.0,
    }
    tree = {
        "_target_": "stable_worldmodel.wm.gcrl.GCRL",
        "encoder": {
            "_target_": "stable_pretraining.backbone.utils.vit_hf",
            "size": "tiny",
            "patch_size": 8,
            "image_size": IMAGE,
            "pretrained": False,
            "use_mask_token": False,
            **VIT["vit_overrides"],
        },
        "action_predictor": {"_target_": "stable_worldmodel.wm.gcrl.module.Predictor", "out_dim": ACTION_DIM, **head},
        "value_predictor": {
            "_target_": "stable_pretraining.TeacherStudentWrapper",
            "warm_init": True,
            "base_ema_coefficient": 0.995,
            "final_ema_coefficient": 0.995,
            "student": {
                "_target_": "stable_worldmodel.wm.gcrl.module.Predictor",
                "out_dim": 1,
                "pool_type": "mean",
                **head,
            },
        },
        "history_size": 2,
    }
    torch.manual_seed(0)
    model = instantiate(json.loads(json.dumps(tree)))
    assert model.algorithm == "gcivl"  # inferred: a value head and no critic
    names = set(model.state_dict())
    assert {
        "log_stds",
        "action_predictor.transformer.layers.2.0.frame_tokens",
        "value_predictor.student.out_proj.weight",
        "value_predictor.teacher.out_proj.weight",
        "value_predictor.ema_coefficient",
    } <= names
    assert any(n.startswith("encoder.") for n in names)
    folder = _stablewm_home / "checkpoints" / "upstream"
    folder.mkdir(parents=True)
    torch.save(model.state_dict(), folder / "weights_epoch_3.pt")
    (folder / "config.json").write_text(json.dumps(tree))
    loaded = load_pretrained("upstream")
    model.eval()
    assert torch.equal(loaded.get_action(act_info()), model.get_action(act_info()))


def test_upstream_target_paths_resolve_to_ours():
    from stable_worldmodel.wm.gcrl import module
    from stable_worldmodel.wm.utils import _locate

    assert _locate("stable_worldmodel.wm.gcrl.gcrl.GCRL") is _locate("stable_worldmodel.wm.gcrl.GCRL") is wm.GCRL
    assert (
        _locate("stable_worldmodel.wm.gcrl.module.QPredictor")
        is _locate("stable_worldmodel.wm.gcrl.QPredictor")
        is module.QPredictor
    )
    assert _locate("stable_worldmodel.wm.gcbc.GCBC") is wm.GCBC
    assert _locate("stable_pretraining.backbone.utils.TeacherStudentWrapper") is module.TeacherStudentWrapper


def test_upstream_alias_of_eval_only_encoder():
    tree = {
        "_target_": "stable_pretraining.backbone.EvalOnly",
        "backbone": {"_target_": "torch.nn.Linear", "in_features": 2, "out_features": 1},
    }
    frozen = instantiate(tree)
    assert set(frozen.state_dict()) == {"backbone.weight", "backbone.bias"}
    assert not frozen.train().backbone.training and not frozen.backbone.weight.requires_grad


# -- hindsight goals -----------------------------------------------------------------------------
def sampler(probs, lengths=(5, 8, 6), groups=((0, 1), (2,)), **kw):
    from stable_worldmodel.train.goals import GoalSampler

    lengths = np.asarray(lengths)
    offsets = np.concatenate([[0], np.cumsum(lengths)[:-1]])
    return GoalSampler(lengths, offsets, [np.asarray(g) for g in groups], probs, **kw), offsets


def test_goal_sampling_kinds():
    eps, starts = np.array([0, 1, 1, 2] * 50), np.array([1, 0, 6, 2] * 50)
    gen = torch.Generator().manual_seed(0)
    current, offsets = sampler({"current": 1.0}, current_offset=1)
    assert (current.sample(eps, starts, gen) == offsets[eps] + starts + 1).all()
    for kind in ("geometric", "uniform"):
        future, _ = sampler({kind: 1.0}, current_offset=1, gamma=0.5)
        rows = future.sample(eps, starts, gen)
        step = rows - offsets[eps]
        lengths = np.array([5, 8, 6])[eps]
        left = lengths - 1 - (starts + 1)
        assert ((step > starts + 1) | (left == 0)).all() and (step < lengths).all()  # later in the same episode
        assert (step[left == 0] == (starts + 1)[left == 0]).all()  # nothing left: the current frame
    random, _ = sampler({"random": 1.0})
    rows = random.sample(eps, starts, gen)
    in_train = rows < offsets[2]
    assert (in_train == (eps != 2)).all()  # each window's goals stay in its group
    assert len(np.unique(rows[eps != 2])) > 8
    again, _ = sampler({"random": 0.5, "geometric": 0.5})
    first = again.sample(eps, starts, torch.Generator().manual_seed(3))
    assert (first == again.sample(eps, starts, torch.Generator().manual_seed(3))).all()


def test_geometric_offsets_follow_the_discount():
    geo, offsets = sampler({"geometric": 1.0}, lengths=(4000,), groups=((0,),), gamma=0.9)
    k = geo.sample(np.zeros(4000, np.int64), np.zeros(4000, np.int64), torch.Generator().manual_seed(0))
    assert k.min() >= 1 and abs(k.mean() - 10.0) < 0.6  # Geometric(0.1) has mean 10


@pytest.mark.parametrize(
    "probs, error, needle",
    [
        ({"geometrc": 1.0}, UnknownNameError, "Did you mean 'geometric'"),
        ({"random": 0.5, "current": 0.2}, ConfigError, "summing to 1"),
        ({"random": -0.5, "current": 1.5}, ConfigError, ">= 0"),
        ([("random", 1.0)], ConfigError, "mapping"),
    ],
    ids=["unknown", "sum", "negative", "not-a-mapping"],
)
def test_bad_goal_sampling_is_a_typed_error(probs, error, needle):
    with pytest.raises(error, match=needle):
        wm.get_config("gcivl", goal_probabilities=probs)


def test_bad_configs_are_typed_errors():
    with pytest.raises(ConfigError, match="depth >= 3"):
        wm.get_config("gcbc", depth=2)
    assert wm.get_config("gcbc", depth=2, pool_type="mean").depth == 2
    with pytest.raises(ConfigError, match="Did you mean 'metric'"):
        wm.get_config("gcivl", value_head="metrics")
    with pytest.raises(UnknownNameError, match="GCRL algorithm 'gcql'"):
        wm.GCRL(
            torch.nn.Identity(),
            Predictor(out_dim=2, num_patches=1, num_frames=1, dim=8, depth=3, heads=2, mlp_dim=8),
            algorithm="gcql",
        )
    with pytest.raises(ConfigError, match="requires value_predictor"):
        wm.GCRL(
            torch.nn.Identity(),
            Predictor(out_dim=2, num_patches=1, num_frames=1, dim=8, depth=3, heads=2, mlp_dim=8),
            algorithm="gcivl",
        )


def test_missing_inputs_are_typed_errors():
    model = build("gcivl")
    good = batch("gcivl")
    with pytest.raises(UnknownNameError, match="goal_pixels"):
        model.loss({k: v for k, v in good.items() if k != "goal_pixels"})
    with pytest.raises(UnknownNameError, match="'action'"):
        model.loss({k: v for k, v in good.items() if k != keys.ACTION})
    with pytest.raises(ConfigError, match="history_size \\+ 1 = 3 frames"):
        model.loss({**good, keys.PIXELS: good[keys.PIXELS][:, :2]})
    with pytest.raises(SpaceError, match=r"\(B, T, C, h, w\)"):
        model.loss({**good, keys.PIXELS: good[keys.PIXELS][:, 0]})
    with pytest.raises(UnknownNameError, match="info\\['goal'\\]"):
        model.get_action({keys.PIXELS: images(B, 1)})
    with pytest.raises(SpaceError, match="at most num_frames"):
        model.predict_actions(
            model.encode({keys.PIXELS: images(B, 3)})["embed"], model.encode({keys.PIXELS: images(B, 1)})["embed"]
        )


# -- training on recorded data -------------------------------------------------------------------
@pytest.fixture(scope="module")
def toy_root(tmp_path_factory):
    """A cache holding ``toy``: 10 expert episodes of swm/Toy-v0 at 16x16."""
    from stable_worldmodel import World
    from stable_worldmodel.envs import expert_policy

    root = tmp_path_factory.mktemp("gcrl_toy")
    with World("swm/Toy-v0", 1, (16, 16), max_episode_steps=20, verbose=0) as world:
        world.set_policy(expert_policy("swm/Toy-v0"))
        world.record_dataset("toy", episodes=10, seed=0, cache_dir=root)
    return root


def test_train_data_gives_goal_frames(toy_root):
    from stable_worldmodel.train.data import TrainData

    cfg = config("gcivl", goal_probabilities={"current": 1.0}, actor_goal_probabilities={"uniform": 1.0})
    data = TrainData("toy", cfg, seed=0, device=torch.device("cpu"), cache_dir=str(toy_root))
    out = data.train_batch(torch.Generator().manual_seed(0), 4)
    assert out[keys.PIXELS].shape == (4, 3, 3, IMAGE, IMAGE) and out[keys.ACTION].shape == (4, 3, ACTION_DIM)
    assert out["goal_pixels"].shape == out["actor_goal_pixels"].shape == (4, 1, 3, IMAGE, IMAGE)
    assert torch.equal(
        out["goal_pixels"][:, 0], out[keys.PIXELS][:, 1]
    )  # "current": the last history frame, bit for bit
    index = data.val_batches(4, 8)[0]
    assert torch.equal(
        data.batch(index)["actor_goal_pixels"], data.batch(index)["actor_goal_pixels"]
    )  # fixed validation goals


def test_train_data_gives_the_goal_rows_proprio(toy_root):
    """Upstream's gcbc reads proprio (use_proprio_encoder): the goal's proprio is the goal row's, normalized alike."""
    from stable_worldmodel.train.data import TrainData

    cfg = config("gcivl", goal_probabilities={"current": 1.0}, actor_goal_probabilities={"uniform": 1.0}, proprio_dim=2)
    data = TrainData("toy", cfg, seed=0, device=torch.device("cpu"), cache_dir=str(toy_root))
    out = data.train_batch(torch.Generator().manual_seed(0), 4)
    assert out[keys.PROPRIO].shape == (4, 3, 2)
    assert out["goal_proprio"].shape == out["actor_goal_proprio"].shape == (4, 1, 2)
    torch.testing.assert_close(out["goal_proprio"][:, 0], out[keys.PROPRIO][:, 1])  # "current": the last history row
    assert not torch.equal(out["actor_goal_proprio"], out["goal_proprio"])  # uniform: later rows


def test_proprio_joins_every_token_of_frames_and_goal():
    model = wm.make("gcbc", action_dim=ACTION_DIM, preset="tiny", **{**NET, "proprio_dim": 2, "proprio_emb_dim": 4})
    assert set(model.extra_encoders) == {keys.PROPRIO}
    info = {
        keys.PIXELS: images(B, 2),
        keys.GOAL: images(B, 1),
        keys.PROPRIO: torch.randn(B, 2, 2),
        "goal_proprio": torch.randn(B, 1, 2),
    }
    action = model.get_action(dict(info))
    assert action.shape == (B, ACTION_DIM)
    moved = model.get_action({**info, "goal_proprio": info["goal_proprio"] + 1.0})
    assert not torch.allclose(action, moved)  # the goal's proprio steers the action
    with pytest.raises(UnknownNameError, match="goal_proprio"):
        model.get_action({k: v for k, v in info.items() if k != "goal_proprio"})


def test_train_data_needs_pixels(_stablewm_home):
    from stable_worldmodel.data.writer import HDF5Writer
    from stable_worldmodel.train.data import TrainData

    _stablewm_home.mkdir(parents=True, exist_ok=True)
    with HDF5Writer(_stablewm_home / "noimg.h5") as writer:
        writer.write_episodes([{keys.ACTION: np.zeros((6, 2), np.float32), keys.PROPRIO: np.zeros((6, 2), np.float32)}])
    with pytest.raises(DatasetFormatError, match="pixels"):
        TrainData("noimg", config("gcbc"), seed=0, device=torch.device("cpu"))


#: the TD heads bootstrap from a slowly moving target: a short horizon and a fast EMA settle them in a few steps
FAST_TD = dict(discount=0.5, value_ema=0.9)


@pytest.mark.parametrize("name", ALGOS)
def test_loss_falls_on_recorded_toy_data(name, toy_root):
    """The total loss falls; for gcivl / gciql the actor's NLL has an irreducible part (a goal
    drawn at random says little about the data's action), so the fall is smaller."""
    from stable_worldmodel.train import train

    extra = {} if name == "gcbc" else FAST_TD
    result = train(
        name,
        "toy",
        "tiny",
        steps=120,
        name=f"toy-{name}",
        seed=0,
        device="cpu",
        progress=False,
        log_every=20,
        cache_dir=str(toy_root),
        batch_size=32,
        warmup_steps=0,
        **NET,
        **extra,
    )
    losses = [r["train/loss"] for r in result.history if "train/loss" in r]
    later = float(np.mean(losses[len(losses) // 2 :]))
    assert later < (0.8 if name == "gcbc" else 0.92) * losses[0], losses
    protocol = json.loads((result.folder / "protocol.json").read_text())
    assert protocol["model"] == name and protocol["history_size"] == 2
    assert protocol["config"]["goal_probabilities"] == config(name).goal_probabilities
    assert torch.equal(load_pretrained(result.folder).log_stds, torch.load(result.folder / "weights.pt")["log_stds"])


def test_resume_equals_an_uninterrupted_run(toy_root, monkeypatch):
    """The EMA teachers are in the state dict and the goals come from the checkpointed batch generator."""
    from stable_worldmodel.train import train
    from stable_worldmodel.train.data import TrainData

    args = dict(
        steps=8,
        seed=0,
        device="cpu",
        progress=False,
        log_every=2,
        ckpt_every=4,
        cache_dir=str(toy_root),
        batch_size=8,
        warmup_steps=0,
        dropout=0.1,
        **NET,
    )
    whole = train("gciql", "toy", "tiny", name="resume-whole", **args)
    draw, calls = TrainData.train_batch, []

    def killed_at_step_6(self, generator, batch_size):
        calls.append(1)
        if len(calls) > 6:
            raise KeyboardInterrupt
        return draw(self, generator, batch_size)

    with monkeypatch.context() as mp:
        mp.setattr(TrainData, "train_batch", killed_at_step_6)
        with pytest.raises(KeyboardInterrupt):
            train("gciql", "toy", "tiny", name="resume-split", **args)
    resumed = train("gciql", "toy", "tiny", name="resume-split", resume=True, **args)
    a, b = torch.load(whole.folder / "weights.pt"), torch.load(resumed.folder / "weights.pt")
    assert a.keys() == b.keys() and all(torch.equal(a[k], b[k]) for k in a)
    assert resumed.train_loss == whole.train_loss

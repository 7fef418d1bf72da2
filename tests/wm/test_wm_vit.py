"""ViT (Hugging Face ``transformers``) world models: the tiny ViT variant's shapes, and
checkpoints written the way upstream 0.1.1 writes them (its ``_target_`` names, transformers
4.x parameter names) loading into our classes."""

from __future__ import annotations

import json

import pytest
import torch

transformers = pytest.importorskip("transformers")

from _tiny import ACTION_DIM, IMAGE, VIT, condition_on_actions, images, randn  # noqa: E402

from stable_worldmodel import keys  # noqa: E402
from stable_worldmodel.wm.lewm import LeWM  # noqa: E402
from stable_worldmodel.wm.lewm.module import MLP, Embedder, Predictor  # noqa: E402
from stable_worldmodel.wm.utils import load_pretrained  # noqa: E402

pytestmark = pytest.mark.extra

D = 8
VIT_SIZES = dict(hidden_size=8, num_hidden_layers=1, num_attention_heads=2, intermediate_size=16)
FRAMESKIP = 5


def test_vit_world_model_shapes(make_model):
    model = make_model("lewm", **VIT).eval()
    assert isinstance(model.encoder, transformers.ViTModel)
    enc = model.encode({keys.PIXELS: images(3, 2), keys.ACTION: randn(3, 2, ACTION_DIM)})
    assert enc["emb"].shape == enc["act_emb"].shape == (3, 2, D)
    assert model.predict(enc["emb"], enc["act_emb"]).shape == (3, 2, D)
    info = {keys.PIXELS: images(2, 4, 1), keys.GOAL: images(2, 4, 1, seed=1)}
    with torch.no_grad():
        assert model.get_cost(info, randn(2, 4, 3, ACTION_DIM)).shape == (2, 4)
    assert info["predicted_emb"].shape == (2, 4, 4, D)
    with torch.no_grad():
        assert model.rollout({keys.PIXELS: images(2, 1)}, randn(2, 3, ACTION_DIM))["predicted_emb"].shape == (2, 4, D)
    out = model.train().loss({keys.PIXELS: images(4, 3), keys.ACTION: randn(4, 3, ACTION_DIM)})
    assert {"loss", "pred_loss", "sigreg_loss"} <= set(out) and out["loss"].ndim == 0


# -- upstream-style checkpoints --------------------------------------------------------------------
def _mlp(d_in: int, d_out: int) -> dict:
    return {
        "_target_": "stable_worldmodel.wm.lewm.module.MLP",
        "input_dim": d_in,
        "output_dim": d_out,
        "hidden_dim": 16,
        "norm_fn": {"_target_": "torch.nn.BatchNorm1d", "_partial_": True},
    }


UPSTREAM_CONFIG = {
    "_target_": "stable_worldmodel.wm.lewm.LeWM",
    "encoder": {
        "_target_": "stable_pretraining.backbone.utils.vit_hf",
        "size": "tiny",
        "patch_size": 8,
        "image_size": IMAGE,
        "pretrained": False,
        "use_mask_token": False,
        **VIT_SIZES,
    },
    "predictor": {
        "_target_": "stable_worldmodel.wm.lewm.module.Predictor",
        "num_frames": 3,
        "input_dim": D,
        "hidden_dim": D,
        "output_dim": D,
        "depth": 1,
        "heads": 2,
        "mlp_dim": 16,
        "dim_head": 4,
        "dropout": 0.0,
        "emb_dropout": 0.0,
    },
    "action_encoder": {
        "_target_": "stable_worldmodel.wm.lewm.module.Embedder",
        "input_dim": FRAMESKIP * ACTION_DIM,
        "emb_dim": D,
    },
    "projector": _mlp(D, D),
    "pred_proj": _mlp(D, D),
}


def upstream_model() -> LeWM:
    """The model of ``UPSTREAM_CONFIG``, built by hand (no instantiate), with drawn AdaLN modulations."""
    torch.manual_seed(0)
    vit = transformers.ViTModel(
        transformers.ViTConfig(image_size=IMAGE, patch_size=8, **VIT_SIZES),
        add_pooling_layer=False,
        use_mask_token=False,
    )
    predictor = Predictor(
        num_frames=3, input_dim=D, hidden_dim=D, output_dim=D, depth=1, heads=2, mlp_dim=16, dim_head=4
    )
    model = LeWM(
        vit,
        predictor,
        Embedder(input_dim=FRAMESKIP * ACTION_DIM, emb_dim=D),
        MLP(D, 16, D, norm_fn=torch.nn.BatchNorm1d),
        MLP(D, 16, D, norm_fn=torch.nn.BatchNorm1d),
    )
    return condition_on_actions(model).eval()


def to_transformers_4(state: dict) -> dict:
    """Rename transformers 5.x ViT parameters to the 4.x names that published checkpoints use."""
    renames = {
        "attention.q_proj": "attention.attention.query",
        "attention.k_proj": "attention.attention.key",
        "attention.v_proj": "attention.attention.value",
        "attention.o_proj": "attention.output.dense",
        "mlp.fc1": "intermediate.dense",
        "mlp.fc2": "output.dense",
    }
    out = {}
    for key, value in state.items():
        if key.startswith("encoder.layers."):
            _, _, index, *rest = key.split(".")
            rest = ".".join(rest)
            for new, old in renames.items():
                if rest.startswith(new + "."):
                    rest = old + rest[len(new) :]
            key = f"encoder.encoder.layer.{index}.{rest}"
        out[key] = value
    return out


def outputs(model: torch.nn.Module) -> torch.Tensor:
    info = {keys.PIXELS: images(2, 3, 2), keys.GOAL: images(2, 3, 1, seed=1)}
    with torch.no_grad():
        return model.get_cost(info, randn(2, 3, 4, FRAMESKIP * ACTION_DIM, seed=2))


def write_upstream_checkpoint(folder, state: dict) -> None:
    folder.mkdir(parents=True)
    torch.save(state, folder / "weights.pt")
    (folder / "config.json").write_text(json.dumps(UPSTREAM_CONFIG, indent=2))


def test_upstream_checkpoint_loads(_stablewm_home):
    model = upstream_model()
    write_upstream_checkpoint(_stablewm_home / "checkpoints" / "upstream", model.state_dict())
    loaded = load_pretrained("upstream")
    assert isinstance(loaded, LeWM) and isinstance(loaded.encoder, transformers.ViTModel)
    assert isinstance(loaded.projector.net[1], torch.nn.BatchNorm1d)
    assert torch.equal(outputs(loaded), outputs(model))


def test_transformers_4_key_names_load(_stablewm_home):
    model = upstream_model()
    old = to_transformers_4(model.state_dict())
    assert "encoder.encoder.layer.0.attention.attention.query.weight" in old
    assert (
        "encoder.encoder.layer.0.output.dense.weight" in old
        and "encoder.encoder.layer.0.attention.output.dense.bias" in old
    )
    assert not any(k.startswith("encoder.layers.") for k in old)
    write_upstream_checkpoint(_stablewm_home / "checkpoints" / "models--user--lewm-vit", old)
    loaded = load_pretrained("user/lewm-vit")
    assert torch.equal(outputs(loaded), outputs(model))

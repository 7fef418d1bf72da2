"""``rollout_steps`` (LeWM, PLDM): the loss also scores K open-loop predictions from one frame, made
exactly as planning makes them (``rollout`` with one context frame), so a model can be trained for the
multi-step accuracy that CEM relies on (issue 30: the state LeWM's error on random action sequences)."""

from __future__ import annotations

import numpy as np
import pytest
import torch
from _tiny import TINY, assert_close, condition_on_actions, fit_losses

from stable_worldmodel import keys, wm
from stable_worldmodel.errors import ConfigError

#: LeWM's own knob at the tiny size
LEWM = dict(sigreg_num_proj=16)


def make(name: str, **overrides) -> torch.nn.Module:
    torch.manual_seed(0)
    return wm.make(name, action_dim=2, preset="tiny", **TINY, **(LEWM if name == "lewm" else {}), **overrides)


def test_the_config_lengthens_samples_and_passes_the_knob_only_when_set():
    cfg = wm.get_config("lewm", "tiny", **TINY, rollout_steps=4)  # history_size 2
    assert cfg.num_steps == 1 + 4
    assert cfg.target_tree(2)["rollout_steps"] == 4
    plain = wm.get_config("pldm", "tiny", **TINY)
    assert plain.num_steps == TINY["history_size"] + 1 and "rollout_steps" not in plain.target_tree(2)
    assert wm.get_config("lewm", "tiny", **TINY, rollout_steps=1).num_steps == TINY["history_size"] + 1
    with pytest.raises(ConfigError, match="rollout_steps"):
        wm.get_config("lewm", "tiny", **TINY, rollout_steps=-1)


@pytest.mark.parametrize("name", ["lewm", "pldm"])
def test_the_rollout_loss_is_the_error_of_planning_s_rollout(name):
    """Eval mode (the projectors' batch norms on their running statistics, as when planning): the
    loss's ``rollout_loss`` equals the error of ``rollout()`` over the same actions."""
    k = 4  # more than the predictor's window of history_size = 2 frames
    model = make(name, rollout_steps=k).eval()
    gen = torch.Generator().manual_seed(1)
    pixels = torch.randn(4, 1 + k, 3, 16, 16, generator=gen)
    action = torch.randn(4, 1 + k, 2, generator=gen)
    with torch.no_grad():
        out = model.loss({keys.PIXELS: pixels, keys.ACTION: action})
        emb = model.encode({keys.PIXELS: pixels})["emb"]
        info = model.rollout({keys.PIXELS: pixels[:, :1]}, action[:, :k])  # one context frame, as planning has
    planned = info["predicted_emb"][:, 1:]  # (B, K, D): the K predictions after the context
    assert planned.shape[1] == k
    assert_close(out["rollout_loss"], (planned - emb[:, 1:]).square().mean())
    plain = make(name).eval().loss({keys.PIXELS: pixels, keys.ACTION: action})  # the same weights, K = 0
    assert "rollout_loss" not in plain
    assert_close(out["loss"] - out["rollout_loss"], plain["loss"])


@pytest.mark.parametrize("name", ["lewm", "pldm"])
def test_the_rollout_loss_trains_the_predictor_not_the_encoder(name):
    model = condition_on_actions(make(name, rollout_steps=3)).train()  # AdaLN-zero at init ignores the actions
    gen = torch.Generator().manual_seed(2)
    batch = {keys.PIXELS: torch.randn(4, 4, 3, 16, 16, generator=gen), keys.ACTION: torch.randn(4, 4, 2, generator=gen)}
    model.loss(batch)["rollout_loss"].backward()
    assert all(p.grad is None for p in model.encoder.parameters())
    assert all(p.grad is None for p in model.projector.parameters())
    assert any(p.grad is not None and p.grad.abs().sum() > 0 for p in model.predictor.parameters())
    assert any(p.grad is not None and p.grad.abs().sum() > 0 for p in model.action_encoder.parameters())


@pytest.mark.parametrize("name", ["lewm", "pldm"])
def test_too_few_frames_for_the_rollout_is_a_typed_error(name):
    model = make(name, rollout_steps=4)
    batch = {keys.PIXELS: torch.zeros(2, 4, 3, 16, 16), keys.ACTION: torch.zeros(2, 4, 2)}
    with pytest.raises(ConfigError, match=r"rollout_steps=4 and 4 frames"):
        model.loss(batch)


def test_training_with_the_rollout_loss_lowers_the_open_loop_error(dot_data):
    model = make("lewm", rollout_steps=2).train()
    data = dot_data(8, 3)
    before = float(model.loss(data)["rollout_loss"].detach())
    losses = fit_losses(model, data, optimizer=torch.optim.AdamW)
    first, last = np.mean(losses[:3]), np.mean(losses[-5:])
    assert np.isfinite(losses).all() and last < 0.7 * first, f"loss {first:.4f} -> {last:.4f}"
    after = float(model.loss(data)["rollout_loss"].detach())
    assert after < 0.5 * before, f"open-loop error {before:.4f} -> {after:.4f}"


def test_a_checkpoint_keeps_the_knob(tmp_path):
    from stable_worldmodel.wm.utils import load_pretrained, save_pretrained

    cfg = wm.get_config("lewm", "tiny", **TINY, **LEWM, rollout_steps=2)
    model = make("lewm", rollout_steps=2)
    folder = save_pretrained(model, "ro", config=cfg.target_tree(2), cache_dir=tmp_path).parent
    assert load_pretrained(folder).rollout_steps == 2


@pytest.mark.parametrize("name", ["lewm", "pldm"])
def test_a_model_pickled_without_the_knob_trains_with_upstream_s_objective(name):
    import pickle

    model = make(name)
    del model.__dict__["rollout_steps"]  # as upstream 0.1.1 pickles it (``*_object.ckpt``)
    again = pickle.loads(pickle.dumps(model))
    batch = {keys.PIXELS: torch.randn(2, 3, 3, 16, 16), keys.ACTION: torch.randn(2, 3, 2)}
    assert again.rollout_steps == 0 and "rollout_loss" not in again.loss(batch)

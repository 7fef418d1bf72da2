"""A LeWM pickled whole by upstream 0.1.1 (``torch.save(model)``, a ``*_object.ckpt``) unpickles
into our classes: its instances lack attributes ours set in ``__init__`` (``Attention.dim_head``,
``LeWM.goal_cost``, the training knobs), which ``__setstate__`` fills. Observed with a LeWM built
and saved by 0.1.1 itself (``get_cost`` failed on ``Attention.dim_head`` before); simulated here
by removing those attributes before pickling."""

from __future__ import annotations

import io

import torch
from _tiny import condition_on_actions, images, make_tiny, randn

from stable_worldmodel import keys
from stable_worldmodel.wm.lewm.module import Attention

#: the plain attributes our classes add to upstream 0.1.1's
OURS_ONLY = {
    "LeWM": ("goal_cost", "extra_config", "num_preds", "loss_history", "sigreg_weight", "_sigreg"),
    "Attention": ("dim_head",),
}


def as_upstream_pickled(model: torch.nn.Module) -> torch.nn.Module:
    for module in model.modules():
        for name in OURS_ONLY.get(type(module).__name__, ()):
            module.__dict__.pop(name, None)
    buffer = io.BytesIO()
    torch.save(model, buffer)
    buffer.seek(0)
    return torch.load(buffer, weights_only=False)


def test_an_upstream_pickled_lewm_plans_like_ours():
    model = condition_on_actions(make_tiny("lewm")).eval()
    reference = make_tiny("lewm")
    reference.load_state_dict(model.state_dict())
    loaded = as_upstream_pickled(model)
    assert any(isinstance(m, Attention) for m in loaded.modules())
    info = {keys.PIXELS: images(2, 3, 1), keys.GOAL: images(2, 3, 1, seed=1)}
    candidates = randn(2, 3, 3, 2)
    with torch.no_grad():
        got = loaded.get_cost(dict(info), candidates)
        want = reference.eval().get_cost(dict(info), candidates)
    torch.testing.assert_close(got, want)
    assert loaded.goal_cost == "final" and loaded.num_preds == 1
    loaded.train()
    batch = {keys.PIXELS: images(2, 4), keys.ACTION: randn(2, 4, 2)}
    assert torch.isfinite(loaded.loss(batch)["loss"])  # it trains too

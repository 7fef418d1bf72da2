"""LeWM trains on upstream 0.1.1's objective: with the same weights and batch, ``LeWM.loss`` equals
what 0.1.1's ``scripts/train/lewm.py`` (``lejepa_forward``) computes, and one AdamW step gives the same
weights (reference numbers recorded once from the original by ``data/record_lewm_objective.py``)."""

from __future__ import annotations

import numpy as np
import pytest
import torch
from _objective import DATA, adamw_step, check_step, jepa_parts, recorded, tensors

pytest.importorskip("transformers")

REF = np.load(DATA / "lewm_objective_upstream.npz")
SIZES = recorded("record_lewm_objective.py", "SIZES")


def ours():
    from stable_worldmodel.wm.lewm import LeWM

    s = SIZES
    model = LeWM(
        **jepa_parts(s),
        num_preds=s["num_preds"],
        history_size=s["history"],
        sigreg_weight=s["lambd"],
        sigreg_num_proj=s["sigreg_proj"],
    )
    model.load_state_dict(tensors(REF, "init"), strict=True)
    return model.train()


def step():
    batch = {"pixels": torch.from_numpy(REF["pixels"]), "action": torch.from_numpy(REF["action"])}
    return adamw_step(ours(), batch, SIZES["lr"], seed=0)


def test_loss_equals_upstreams_lejepa_forward():
    out, _, _ = step()
    for name in ("pred_loss", "sigreg_loss", "loss"):
        assert abs(float(out[name]) - float(REF[name])) <= 1e-5, (name, float(out[name]), float(REF[name]))


def test_gradients_and_one_adamw_step_give_upstreams_weights():
    _, grads, state = step()
    check_step(REF, grads, state, SIZES["lr"])

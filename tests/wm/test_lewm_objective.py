"""LeWM trains on upstream 0.1.1's objective: with the same weights and batch, ``LeWM.loss`` equals
what 0.1.1's ``scripts/train/lewm.py`` (``lejepa_forward``) computes, and one AdamW step gives the same
weights (reference numbers recorded once from the original by ``data/record_lewm_objective.py``)."""

from __future__ import annotations

import numpy as np
import pytest
import torch
from _objective import DATA, adamw_step, check_step, recorded, tensors, tiny_vit

pytest.importorskip("transformers")

REF = np.load(DATA / "lewm_objective_upstream.npz")
SIZES = recorded("record_lewm_objective.py", "SIZES")


def ours():
    from stable_worldmodel.wm.lewm import LeWM
    from stable_worldmodel.wm.lewm.module import MLP, Embedder, Predictor

    s, d = SIZES, SIZES["hidden"]
    vit = tiny_vit(s)
    predictor = Predictor(
        num_frames=s["history"], input_dim=d, hidden_dim=d, output_dim=d, depth=s["depth"], heads=s["heads"],
        dim_head=s["dim_head"], mlp_dim=s["mlp"],
    )  # fmt: skip
    model = LeWM(
        encoder=vit,
        predictor=predictor,
        action_encoder=Embedder(input_dim=s["action_dim"], emb_dim=d),
        projector=MLP(input_dim=d, output_dim=d, hidden_dim=s["proj_hidden"], norm_fn=torch.nn.BatchNorm1d),
        pred_proj=MLP(input_dim=d, output_dim=d, hidden_dim=s["proj_hidden"], norm_fn=torch.nn.BatchNorm1d),
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

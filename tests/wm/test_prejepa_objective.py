"""PreJEPA (DINO-WM) trains on upstream's objective: with the same weights and batch, ``PreJEPA.loss`` equals what
upstream's ``scripts/train/prejepa.py`` (``dinowm_forward``) computes (the per-part losses and the loss over every
part but the action's), and one AdamW step gives the same weights (reference numbers recorded once from 0.1.1's
classes by ``data/record_prejepa_objective.py``)."""

from __future__ import annotations

import numpy as np
import pytest
import torch
from _objective import DATA, adamw_step, check_step, recorded, tensors, tiny_vit

pytest.importorskip("transformers")

REF = np.load(DATA / "prejepa_objective_upstream.npz")
SIZES, LOSSES = recorded("record_prejepa_objective.py", "SIZES"), recorded("record_prejepa_objective.py", "LOSSES")


def ours():
    from stable_worldmodel.wm.prejepa import PreJEPA
    from stable_worldmodel.wm.prejepa.module import CausalPredictor, Embedder

    s = SIZES
    vit = tiny_vit(s)
    predictor = CausalPredictor(
        num_patches=(s["image"] // s["patch"]) ** 2, num_frames=s["history"],
        dim=s["hidden"] + s["action_emb"] + s["proprio_emb"], depth=s["depth"], heads=s["heads"], mlp_dim=s["mlp"],
        dim_head=s["dim_head"],
    )  # fmt: skip
    extra = {
        "action": Embedder(in_chans=s["action_dim"], emb_dim=s["action_emb"]),
        "proprio": Embedder(in_chans=s["proprio_dim"], emb_dim=s["proprio_emb"]),
    }
    model = PreJEPA(vit, predictor, extra_encoders=extra, history_size=s["history"], num_pred=s["num_preds"])
    model.load_state_dict(tensors(REF, "init"), strict=True)
    return model.train()


def step():
    batch = {k: torch.from_numpy(REF[k]) for k in ("pixels", "action", "proprio")}
    return adamw_step(ours(), batch, SIZES["lr"])


def test_losses_equal_upstreams_dinowm_forward():
    out, _, _ = step()
    for name in LOSSES:
        assert abs(float(out[name]) - float(REF[name])) <= 1e-5, (name, float(out[name]), float(REF[name]))


def test_gradients_and_one_adamw_step_give_upstreams_weights():
    _, grads, state = step()
    assert not any(name.startswith("backbone.") for name in grads)  # the encoder's features are detached
    check_step(REF, grads, state, SIZES["lr"])

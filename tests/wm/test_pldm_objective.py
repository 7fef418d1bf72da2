"""PLDM trains on upstream's objective: with the same weights and batch, ``PLDM.loss`` (with the weights of
upstream's ``config/pldm.yaml``, the ``paper`` preset's) equals what upstream's ``scripts/train/pldm.py``
(``pldm_forward``) computes, term by term, and one AdamW step gives the same weights (reference numbers
recorded once from 0.1.1's classes by ``data/record_pldm_objective.py``)."""

from __future__ import annotations

import ast
from pathlib import Path

import numpy as np
import pytest
import torch

pytest.importorskip("transformers")

DATA = Path(__file__).parent / "data"
REF = np.load(DATA / "pldm_objective_upstream.npz")
RECORDER = ast.parse((DATA / "record_pldm_objective.py").read_text())


def recorded(name: str):
    """The literal ``name = dict(...)`` / tuple of the recording script."""
    node = next(n.value for n in RECORDER.body if isinstance(n, ast.Assign) and n.targets[0].id == name)
    if isinstance(node, ast.Call):
        return {kw.arg: ast.literal_eval(kw.value) for kw in node.keywords}
    return ast.literal_eval(node)


SIZES, WEIGHTS, TERMS = recorded("SIZES"), recorded("WEIGHTS"), recorded("TERMS")


def ours():
    import transformers

    from stable_worldmodel.wm.lewm.module import MLP, Embedder, Predictor
    from stable_worldmodel.wm.pldm import PLDM

    s, d = SIZES, SIZES["hidden"]
    vit = transformers.ViTModel(
        transformers.ViTConfig(
            hidden_size=d,
            num_hidden_layers=s["vit_layers"],
            num_attention_heads=s["vit_heads"],
            intermediate_size=2 * d,
            image_size=s["image"],
            patch_size=s["patch"],
        ),
        add_pooling_layer=False,
        use_mask_token=False,
    )
    predictor = Predictor(
        num_frames=s["history"], input_dim=d, hidden_dim=d, output_dim=d, depth=s["depth"], heads=s["heads"],
        dim_head=s["dim_head"], mlp_dim=s["mlp"],
    )  # fmt: skip
    model = PLDM(
        encoder=vit,
        predictor=predictor,
        action_encoder=Embedder(input_dim=s["action_dim"], emb_dim=d),
        projector=MLP(input_dim=d, output_dim=d, hidden_dim=s["proj_hidden"], norm_fn=torch.nn.BatchNorm1d),
        pred_proj=MLP(input_dim=d, output_dim=d, hidden_dim=s["proj_hidden"], norm_fn=torch.nn.BatchNorm1d),
        idm=MLP(input_dim=2 * d, hidden_dim=s["idm_hidden"], output_dim=s["action_dim"]),
        num_preds=s["num_preds"],
        history_size=s["history"],
        loss_weights={**WEIGHTS, "temp_straight_loss": 0.0},  # disabled upstream
    )
    model.load_state_dict({ours_key(k): torch.from_numpy(REF["init/" + k]) for k in names("init")}, strict=True)
    return model.train()


def names(prefix: str) -> list[str]:
    return [k[len(prefix) + 1 :] for k in REF.files if k.startswith(prefix + "/")]


def ours_key(key: str) -> str:
    """The recording keeps upstream's two trained modules apart (``model.*``, ``idm.*``); ours holds the idm."""
    return key[len("model.") :] if key.startswith("model.") else key


def step(model) -> tuple[dict, dict, dict]:
    opt = torch.optim.AdamW(model.parameters(), lr=SIZES["lr"])
    out = model.loss({"pixels": torch.from_numpy(REF["pixels"]), "action": torch.from_numpy(REF["action"])})
    opt.zero_grad()
    out["loss"].backward()
    grads = {k: v.grad.detach().clone() for k, v in model.named_parameters() if v.grad is not None}
    opt.step()
    return out, grads, model.state_dict()


def test_the_paper_preset_weighs_the_terms_as_upstreams_recipe():
    from stable_worldmodel import wm

    assert wm.get_config("pldm", "paper").loss_weights == {**WEIGHTS, "temp_straight_loss": 0.0}


def test_loss_and_each_term_equal_upstreams_pldm_forward():
    out, _, _ = step(ours())
    for name in (*TERMS, "loss"):
        assert abs(float(out[name]) - float(REF[name])) <= 1e-5, (name, float(out[name]), float(REF[name]))


def test_gradients_and_one_adamw_step_give_upstreams_weights():
    """As the LeWM test: gradients to 1e-5 (the recipe's weights of 18 and 12 scale float32 noise up ~10x from
    LeWM's 1e-6) plus 1e-3 of each tensor's scale; weights after the step to 1e-5 except
    where upstream's gradient is float noise (|g| < 1e-5 here), where AdamW's first step is lr times the noise's sign.
    The idm's gradient is zero (weight 0 in upstream's recipe): AdamW's weight decay still moves it, in both."""
    _, grads, state = step(ours())
    ref = {ours_key(k): torch.from_numpy(REF["grad/" + k]).double() for k in names("grad")}
    assert sorted(ref) == sorted(grads)
    for name, g in ref.items():
        assert float((grads[name].double() - g).abs().max()) <= 1e-5 + 1e-3 * float(g.abs().max()), name
    assert sorted(ours_key(k) for k in names("after")) == sorted(state)
    moved = 0.0
    for key in names("after"):
        name = ours_key(key)
        diff = (state[name].double() - torch.from_numpy(REF["after/" + key]).double()).abs()
        noise = ref[name].abs() < 1e-5 if name in ref else torch.zeros_like(diff, dtype=torch.bool)
        if name.startswith("idm."):
            noise = torch.zeros_like(noise)  # exactly zero gradients: only the weight decay moves them
        assert float(torch.where(noise, 0.0, diff).max()) <= 1e-5, name
        assert float(torch.where(noise, diff, 0.0).max()) <= 2 * SIZES["lr"] + 1e-5, name
        moved = max(moved, float((state[name].double() - torch.from_numpy(REF["init/" + key]).double()).abs().max()))
    assert moved > 1e-4

"""LeWM trains on upstream 0.1.1's objective: with the same weights and batch, ``LeWM.loss`` equals
what 0.1.1's ``scripts/train/lewm.py`` (``lejepa_forward``) computes, and one AdamW step gives the same
weights (reference numbers recorded once from the original by ``data/record_lewm_objective.py``)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import torch

pytest.importorskip("transformers")

DATA = Path(__file__).parent / "data"
REF = np.load(DATA / "lewm_objective_upstream.npz")
SIZES = dict(
    image=16, patch=8, hidden=32, vit_layers=1, vit_heads=2, depth=1, heads=2, dim_head=16, mlp=64,
    proj_hidden=64, action_dim=4, history=1, num_preds=1, sigreg_proj=64, lambd=0.09, lr=1e-3,
)  # fmt: skip


def ours():
    import transformers

    from stable_worldmodel.wm.lewm import LeWM
    from stable_worldmodel.wm.lewm.module import MLP, Embedder, Predictor

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
    init = {k[len("init/") :]: torch.from_numpy(REF[k]) for k in REF.files if k.startswith("init/")}
    model.load_state_dict(init, strict=True)
    return model.train()


def batch() -> dict:
    return {"pixels": torch.from_numpy(REF["pixels"]), "action": torch.from_numpy(REF["action"])}


def test_the_recording_script_builds_the_sizes_the_test_rebuilds():
    import ast

    tree = ast.parse((DATA / "record_lewm_objective.py").read_text())
    sizes = next(n.value for n in tree.body if isinstance(n, ast.Assign) and n.targets[0].id == "SIZES")
    assert {kw.arg: ast.literal_eval(kw.value) for kw in sizes.keywords} == SIZES


def step(model) -> tuple[dict, dict]:
    """One training step as upstream's recipe takes it; returns (gradients, weights after)."""
    opt = torch.optim.AdamW(model.parameters(), lr=SIZES["lr"])
    torch.manual_seed(0)  # SIGReg draws its directions from the global stream, as upstream's
    out = model.loss(batch())
    opt.zero_grad()
    out["loss"].backward()
    grads = {k: v.grad.detach().clone() for k, v in model.named_parameters() if v.grad is not None}
    opt.step()
    return out, grads, model.state_dict()


def test_loss_equals_upstreams_lejepa_forward():
    out, _, _ = step(ours())
    for name in ("pred_loss", "sigreg_loss", "loss"):
        assert abs(float(out[name]) - float(REF[name])) <= 1e-5, (name, float(out[name]), float(REF[name]))


def test_gradients_and_one_adamw_step_give_upstreams_weights():
    """Gradients agree (to 1e-6 plus 1e-3 of each tensor's scale); the weights after the step to
    1e-5, except where upstream's own gradient is float noise (|g| < 1e-6: biases feeding a
    BatchNorm or a LayerNorm, the attention key bias, whose true gradient is 0): AdamW's first
    step there is lr times the noise's sign, in either package (up to 2 lr apart)."""
    _, grads, state = step(ours())
    ref = {k[len("grad/") :]: torch.from_numpy(REF[k]).double() for k in REF.files if k.startswith("grad/")}
    assert sorted(ref) == sorted(grads)
    for name, g in ref.items():  # float32 sums in another order (thread count): relative 1e-3 of the tensor's scale
        assert float((grads[name].double() - g).abs().max()) <= 1e-6 + 1e-3 * float(g.abs().max()), name
    after = [k[len("after/") :] for k in REF.files if k.startswith("after/")]
    assert sorted(after) == sorted(state)
    moved = 0.0
    for name in after:
        diff = (state[name].double() - torch.from_numpy(REF["after/" + name]).double()).abs()
        noise = ref[name].abs() < 1e-6 if name in ref else torch.zeros_like(diff, dtype=torch.bool)
        assert float(torch.where(noise, 0.0, diff).max()) <= 1e-5, name
        assert float(torch.where(noise, diff, 0.0).max()) <= 2 * SIZES["lr"] + 1e-5, name
        moved = max(moved, float((state[name].double() - torch.from_numpy(REF["init/" + name]).double()).abs().max()))
    assert moved > 1e-4  # the step changed the weights: the comparison is not of untouched tensors

"""Shared checks of the "same objective as upstream's recipe" tests: a reference recorded from the original
(``data/record_*_objective.py``: the initial weights, a batch, the losses, gradients and the weights after
one AdamW step) against the same step taken by our model."""

from __future__ import annotations

import ast
from collections.abc import Callable
from pathlib import Path

import numpy as np
import torch

DATA = Path(__file__).parent / "data"


def recorded(script: str, name: str):
    """The literal ``name = dict(...)`` (or tuple) of a recording script, which the test rebuilds from."""
    tree = ast.parse((DATA / script).read_text())
    node = next(n.value for n in tree.body if isinstance(n, ast.Assign) and n.targets[0].id == name)
    if isinstance(node, ast.Call):
        return {kw.arg: ast.literal_eval(kw.value) for kw in node.keywords}
    return ast.literal_eval(node)


def tiny_vit(sizes: dict):
    """The recordings' encoder: a transformers ViT of ``hidden`` width, ``vit_layers`` layers of ``vit_heads`` heads,
    ``image`` pixels in patches of ``patch`` (as ``stable_pretraining.backbone.utils.vit_hf`` builds one)."""
    import transformers

    config = transformers.ViTConfig(
        hidden_size=sizes["hidden"],
        num_hidden_layers=sizes["vit_layers"],
        num_attention_heads=sizes["vit_heads"],
        intermediate_size=2 * sizes["hidden"],
        image_size=sizes["image"],
        patch_size=sizes["patch"],
    )
    return transformers.ViTModel(config, add_pooling_layer=False, use_mask_token=False)


def jepa_parts(sizes: dict) -> dict[str, torch.nn.Module]:
    """The recordings' LeWM / PLDM modules (our classes, upstream's names): ``encoder`` (:func:`tiny_vit`),
    ``predictor``, ``action_encoder``, ``projector`` and ``pred_proj`` (BatchNorm MLPs), ``hidden`` wide."""
    from stable_worldmodel.wm.lewm.module import MLP, Embedder, Predictor

    s, d = sizes, sizes["hidden"]
    predictor = Predictor(
        num_frames=s["history"], input_dim=d, hidden_dim=d, output_dim=d, depth=s["depth"], heads=s["heads"],
        dim_head=s["dim_head"], mlp_dim=s["mlp"],
    )  # fmt: skip

    def projector() -> MLP:
        return MLP(input_dim=d, output_dim=d, hidden_dim=s["proj_hidden"], norm_fn=torch.nn.BatchNorm1d)

    return {
        "encoder": tiny_vit(s),
        "predictor": predictor,
        "action_encoder": Embedder(input_dim=s["action_dim"], emb_dim=d),
        "projector": projector(),
        "pred_proj": projector(),
    }


def tensors(ref: np.lib.npyio.NpzFile, prefix: str, rename: Callable[[str], str] = str) -> dict[str, torch.Tensor]:
    """``{our name: tensor}`` of the reference entries ``prefix/<name>``."""
    return {rename(k[len(prefix) + 1 :]): torch.from_numpy(ref[k]) for k in ref.files if k.startswith(prefix + "/")}


def adamw_step(model: torch.nn.Module, batch: dict, lr: float, seed: int | None = None) -> tuple[dict, dict, dict]:
    """One training step as upstream's recipes take it: ``(loss outputs, gradients, weights after)``;
    ``seed``: torch's global seed just before the loss (SIGReg draws its directions from that stream)."""
    opt = torch.optim.AdamW(model.parameters(), lr=lr)
    if seed is not None:
        torch.manual_seed(seed)
    out = model.loss(batch)
    opt.zero_grad()
    out["loss"].backward()
    grads = {k: v.grad.detach().clone() for k, v in model.named_parameters() if v.grad is not None}
    opt.step()
    return out, grads, model.state_dict()


def check_step(
    ref: np.lib.npyio.NpzFile,
    grads: dict,
    state: dict,
    lr: float,
    rename: Callable[[str], str] = str,
    tol: float = 1e-6,
    exact_zero: Callable[[str], bool] = lambda name: False,
) -> None:
    """Gradients within ``tol`` plus 1e-3 of each tensor's scale (float32 sums in another order); the weights after
    the step within 1e-5, except where upstream's own gradient is float noise (``|g| < tol``: biases feeding a
    BatchNorm or a LayerNorm, whose true gradient is 0), where AdamW's first step is lr times the noise's sign in
    either package (up to 2 lr apart). ``exact_zero(name)``: tensors whose gradient is exactly zero on both sides
    (a term of weight 0), compared strictly: only AdamW's weight decay moves them."""
    want = {k: v.double() for k, v in tensors(ref, "grad", rename).items()}
    assert sorted(want) == sorted(grads)
    for name, g in want.items():
        assert float((grads[name].double() - g).abs().max()) <= tol + 1e-3 * float(g.abs().max()), name
    after, init = tensors(ref, "after", rename), tensors(ref, "init", rename)
    assert sorted(after) == sorted(state)
    moved = 0.0
    for name, value in after.items():
        diff = (state[name].double() - value.double()).abs()
        noise = want[name].abs() < tol if name in want and not exact_zero(name) else torch.zeros_like(diff).bool()
        assert float(torch.where(noise, 0.0, diff).max()) <= 1e-5, name
        assert float(torch.where(noise, diff, 0.0).max()) <= 2 * lr + 1e-5, name
        moved = max(moved, float((state[name].double() - init[name].double()).abs().max()))
    assert moved > 1e-4  # the step changed the weights: the comparison is not of untouched tensors

"""Record upstream's PLDM training objective on a tiny model, for ``test_pldm_objective.py``.

Run once with the original's interpreter (``../shared/bench/setup_peer011_venv.sh``), from a folder that
does not hold this checkout's package:

    cd /tmp && /work/peer011-venv/bin/python /work/main/tests/wm/data/record_pldm_objective.py

It builds a PLDM with 0.1.1's own classes (``stable_worldmodel.wm.pldm``: the model, its predictor,
action embedder and MLPs; ``stable_worldmodel.wm.loss``: ``PLDMLoss`` and ``TemporalStraighteningLoss``;
the encoder a transformers ViT as ``stable_pretraining.backbone.utils.vit_hf`` builds it) at 16x16 with
width-32 modules, from a seeded initialisation, and computes on one batch what upstream's
``scripts/train/pldm.py`` (``pldm_forward``) computes: the prediction loss over ``history`` frames, the
inverse-dynamics MLP on ``cat(emb[:, 1:], emb[:, :-1])`` against ``action[:, :-1]``, the path
straightening and PLDM terms, summed with the weights of upstream's ``config/pldm.yaml`` (each term
enabled there is added with its weight, a zero weight included; ``temp_straight`` is disabled there).
It writes ``pldm_objective_upstream.npz``: the initial weights, the batch, every term, the loss, the
gradients, and the weights after one ``torch.optim.AdamW`` step (lr 1e-3).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import torch
import transformers

from stable_worldmodel.wm.loss import PLDMLoss, TemporalStraighteningLoss
from stable_worldmodel.wm.pldm import PLDM
from stable_worldmodel.wm.pldm.module import MLP, Embedder, Predictor

OUT = Path(__file__).with_name("pldm_objective_upstream.npz")
#: the tiny model's sizes (the test rebuilds it with our classes from the same numbers)
SIZES = dict(
    image=16,
    patch=8,
    hidden=32,
    vit_layers=1,
    vit_heads=2,
    depth=1,
    heads=2,
    dim_head=16,
    mlp=64,
    proj_hidden=64,
    idm_hidden=48,
    action_dim=4,
    history=3,
    num_preds=1,
    lr=1e-3,
)
#: upstream's config/pldm.yaml: the weight of each enabled term (temp_straight is disabled there)
WEIGHTS = dict(std_loss=18.0, std_t_loss=0.7, cov_loss=12.0, cov_t_loss=0.0, temp_align_loss=0.2, idm_loss=0.0)
TERMS = ("pred_loss", "idm_loss", "temp_align_loss", "std_loss", "std_t_loss", "cov_loss", "cov_t_loss",
         "temp_straight_loss")  # fmt: skip


def build() -> tuple[PLDM, MLP]:
    s = SIZES
    vit = transformers.ViTModel(
        transformers.ViTConfig(
            hidden_size=s["hidden"],
            num_hidden_layers=s["vit_layers"],
            num_attention_heads=s["vit_heads"],
            intermediate_size=2 * s["hidden"],
            image_size=s["image"],
            patch_size=s["patch"],
        ),
        add_pooling_layer=False,
        use_mask_token=False,
    )
    d = s["hidden"]
    predictor = Predictor(
        num_frames=s["history"],
        input_dim=d,
        hidden_dim=d,
        output_dim=d,
        depth=s["depth"],
        heads=s["heads"],
        dim_head=s["dim_head"],
        mlp_dim=s["mlp"],
        dropout=0.0,
        emb_dropout=0.0,
    )
    model = PLDM(
        encoder=vit,
        predictor=predictor,
        action_encoder=Embedder(input_dim=s["action_dim"], emb_dim=d),
        projector=MLP(input_dim=d, output_dim=d, hidden_dim=s["proj_hidden"], norm_fn=torch.nn.BatchNorm1d),
        pred_proj=MLP(input_dim=d, output_dim=d, hidden_dim=s["proj_hidden"], norm_fn=torch.nn.BatchNorm1d),
    )
    idm = MLP(input_dim=2 * d, hidden_dim=s["idm_hidden"], output_dim=s["action_dim"])
    return model, idm


def pldm_forward(model: PLDM, idm: MLP, batch: dict) -> dict:
    """Upstream's scripts/train/pldm.py objective, as that script computes it."""
    h, n_preds = SIZES["history"], SIZES["num_preds"]
    batch["action"] = torch.nan_to_num(batch["action"], 0.0)
    output = model.encode(batch)
    emb, act_emb = output["emb"], output["act_emb"]
    pred_emb = model.predict(emb[:, :h], act_emb[:, :h])
    act_pred = idm(torch.cat([emb[:, 1:], emb[:, :-1]], dim=-1))
    output["pred_loss"] = (pred_emb - emb[:, n_preds:]).square().mean()
    output["temp_straight_loss"] = TemporalStraighteningLoss()(emb)
    output.update(PLDMLoss()(emb, act_pred, batch["action"][:, :-1].detach()))
    output["loss"] = output["pred_loss"]
    for name, weight in WEIGHTS.items():
        output["loss"] = output["loss"] + weight * output[name]
    return output


def main() -> None:
    torch.manual_seed(1234)
    model, idm = build()
    both = torch.nn.ModuleDict({"model": model, "idm": idm}).train()
    init = {k: v.detach().clone() for k, v in both.state_dict().items()}
    g = torch.Generator().manual_seed(7)
    frames = SIZES["history"] + SIZES["num_preds"]
    pixels = torch.randn(6, frames, 3, SIZES["image"], SIZES["image"], generator=g)
    action = torch.randn(6, frames, SIZES["action_dim"], generator=g)
    action[:, -1] = float("nan")  # the last step of a clip has no action in the datasets
    opt = torch.optim.AdamW(both.parameters(), lr=SIZES["lr"])
    out = pldm_forward(model, idm, {"pixels": pixels.clone(), "action": action.clone()})
    opt.zero_grad()
    out["loss"].backward()
    grads = {k: v.grad.detach().clone() for k, v in both.named_parameters() if v.grad is not None}
    opt.step()
    after = both.state_dict()
    np.savez_compressed(
        OUT,
        pixels=pixels.numpy(),
        action=action.numpy(),
        loss=out["loss"].item(),
        **{name: out[name].item() for name in TERMS},
        **{f"init/{k}": v.numpy() for k, v in init.items()},
        **{f"after/{k}": v.detach().numpy() for k, v in after.items()},
        **{f"grad/{k}": v.numpy() for k, v in grads.items()},
    )
    print(f"wrote {OUT}: loss {out['loss'].item():.6f}; " + ", ".join(f"{t} {out[t].item():.5f}" for t in TERMS))


if __name__ == "__main__":
    main()

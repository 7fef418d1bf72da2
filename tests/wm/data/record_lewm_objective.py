"""Record upstream 0.1.1's LeWM training objective on a tiny model, for ``test_lewm_objective.py``.

Run once with the original's interpreter (``../shared/bench/setup_peer011_venv.sh``), from a folder that
does not hold this checkout's package:

    cd /tmp && /work/peer011-venv/bin/python /work/main/tests/wm/data/record_lewm_objective.py

It builds a LeWM with 0.1.1's own classes (``stable_worldmodel.wm.lewm``; the encoder a transformers
ViT as ``stable_pretraining.backbone.utils.vit_hf`` builds it) at 16x16 with width-32 modules, from a
seeded initialisation, and writes ``lewm_objective_upstream.npz``: the initial weights, one batch, and
what 0.1.1's ``scripts/train/lewm.py`` (``lejepa_forward``) computes on it (``pred_loss``,
``sigreg_loss``, ``loss``, with torch's global seed set to 0 just before, which SIGReg's random
directions are drawn from), its gradients, and the weights after one ``torch.optim.AdamW`` step (lr 1e-3).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import torch
import transformers

from stable_worldmodel.wm.lewm import LeWM
from stable_worldmodel.wm.lewm.module import MLP, Embedder, Predictor
from stable_worldmodel.wm.loss import SIGReg

OUT = Path(__file__).with_name("lewm_objective_upstream.npz")
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
    action_dim=4,
    history=1,
    num_preds=1,
    sigreg_proj=64,
    lambd=0.09,
    lr=1e-3,
)


def build() -> LeWM:
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
    return LeWM(
        encoder=vit,
        predictor=predictor,
        action_encoder=Embedder(input_dim=s["action_dim"], emb_dim=d),
        projector=MLP(input_dim=d, output_dim=d, hidden_dim=s["proj_hidden"], norm_fn=torch.nn.BatchNorm1d),
        pred_proj=MLP(input_dim=d, output_dim=d, hidden_dim=s["proj_hidden"], norm_fn=torch.nn.BatchNorm1d),
    )


def lejepa_forward(model: LeWM, sigreg: SIGReg, batch: dict) -> dict:
    """0.1.1's scripts/train/lewm.py objective, as that script computes it."""
    ctx_len, n_preds = SIZES["history"], SIZES["num_preds"]
    batch["action"] = torch.nan_to_num(batch["action"], 0.0)
    output = model.encode(batch)
    emb, act_emb = output["emb"], output["act_emb"]
    pred_emb = model.predict(emb[:, :ctx_len], act_emb[:, :ctx_len])
    output["pred_loss"] = (pred_emb - emb[:, n_preds:]).pow(2).mean()
    output["sigreg_loss"] = sigreg(emb.transpose(0, 1))
    output["loss"] = output["pred_loss"] + SIZES["lambd"] * output["sigreg_loss"]
    return output


def main() -> None:
    torch.manual_seed(1234)
    model = build().train()
    init = {k: v.detach().clone() for k, v in model.state_dict().items()}
    g = torch.Generator().manual_seed(7)
    frames = SIZES["history"] + SIZES["num_preds"]
    pixels = torch.randn(6, frames, 3, SIZES["image"], SIZES["image"], generator=g)
    action = torch.randn(6, frames, SIZES["action_dim"], generator=g)
    action[:, -1] = float("nan")  # the last step of a clip has no action in the datasets
    sigreg = SIGReg(knots=17, num_proj=SIZES["sigreg_proj"])
    opt = torch.optim.AdamW(model.parameters(), lr=SIZES["lr"])
    torch.manual_seed(0)
    out = lejepa_forward(model, sigreg, {"pixels": pixels.clone(), "action": action.clone()})
    opt.zero_grad()
    out["loss"].backward()
    grads = {k: v.grad.detach().clone() for k, v in model.named_parameters() if v.grad is not None}
    opt.step()
    after = model.state_dict()
    np.savez_compressed(
        OUT,
        pixels=pixels.numpy(),
        action=action.numpy(),
        loss=out["loss"].item(),
        pred_loss=out["pred_loss"].item(),
        sigreg_loss=out["sigreg_loss"].item(),
        **{f"init/{k}": v.numpy() for k, v in init.items()},
        **{f"after/{k}": v.detach().numpy() for k, v in after.items()},
        **{f"grad/{k}": v.numpy() for k, v in grads.items()},
    )
    print(
        f"wrote {OUT}: loss {out['loss'].item():.6f} (pred {out['pred_loss'].item():.6f}, "
        f"sigreg {out['sigreg_loss'].item():.6f}), {len(init)} tensors"
    )


if __name__ == "__main__":
    main()

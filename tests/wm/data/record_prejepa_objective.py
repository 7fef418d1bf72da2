"""Record upstream's PreJEPA (DINO-WM) training objective on a tiny model, for ``test_prejepa_objective.py``.

Run once with the original's interpreter (``../shared/bench/setup_peer011_venv.sh``), from a folder that
does not hold this checkout's package:

    cd /tmp && /work/peer011-venv/bin/python /work/main/tests/wm/data/record_prejepa_objective.py

It builds a PreJEPA with 0.1.1's own classes (``stable_worldmodel.wm.prejepa``: the model, its
``CausalPredictor`` and the action / proprio ``Embedder``s; the encoder a transformers ViT at 16x16, whose
features the model detaches, as a frozen backbone's) from a seeded initialisation, and computes on one batch
what upstream's ``scripts/train/prejepa.py`` (``dinowm_forward``) computes: the extra inputs with NaN as 0,
the embedding of every frame, the prediction from the first ``history`` frames, the per-part MSE against the
frames ``num_preds`` later (``pixels_loss``, ``proprio_loss``) and the loss, the MSE over every part except the
action's. It writes ``prejepa_objective_upstream.npz``: the initial weights, the batch, the losses, the
gradients, and the weights after one ``torch.optim.AdamW`` step (lr 1e-3).
"""

from __future__ import annotations

from collections import OrderedDict
from pathlib import Path

import numpy as np
import torch
import torch.nn.functional as F
import transformers

from stable_worldmodel.wm.prejepa import PreJEPA
from stable_worldmodel.wm.prejepa.module import CausalPredictor, Embedder

OUT = Path(__file__).with_name("prejepa_objective_upstream.npz")
#: the tiny model's sizes (the test rebuilds it with our classes from the same numbers)
SIZES = dict(
    image=16,
    patch=8,
    hidden=32,
    vit_layers=1,
    vit_heads=2,
    depth=2,
    heads=2,
    dim_head=16,
    mlp=64,
    action_dim=4,
    action_emb=6,
    proprio_dim=3,
    proprio_emb=5,
    history=2,
    num_preds=1,
    lr=1e-3,
)
LOSSES = ("pixels_loss", "proprio_loss", "loss")


def build() -> PreJEPA:
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
    dim = s["hidden"] + s["action_emb"] + s["proprio_emb"]
    predictor = CausalPredictor(
        num_patches=(s["image"] // s["patch"]) ** 2,
        num_frames=s["history"],
        dim=dim,
        depth=s["depth"],
        heads=s["heads"],
        mlp_dim=s["mlp"],
        dim_head=s["dim_head"],
    )
    extra = torch.nn.ModuleDict(
        OrderedDict(
            action=Embedder(in_chans=s["action_dim"], emb_dim=s["action_emb"]),
            proprio=Embedder(in_chans=s["proprio_dim"], emb_dim=s["proprio_emb"]),
        )
    )
    return PreJEPA(
        encoder=vit, predictor=predictor, extra_encoders=extra, history_size=s["history"], num_pred=s["num_preds"]
    )


def dinowm_forward(model: PreJEPA, batch: dict) -> dict:
    """Upstream's scripts/train/prejepa.py objective, as that script computes it."""
    h, n_preds = SIZES["history"], SIZES["num_preds"]
    for key in model.extra_encoders:
        batch[key] = torch.nan_to_num(batch[key], 0.0).squeeze()
    batch = model.encode(batch, target="emb")
    embedding = batch["emb"][:, :h]
    pred = model.predict(embedding)
    target = batch["emb"][:, n_preds:].detach()
    pixels_dim = batch["pixels_emb"].size(-1)
    batch["pixels_loss"] = F.mse_loss(pred[..., :pixels_dim], target[..., :pixels_dim])
    start, action = pixels_dim, (0, 0)
    for key in model.extra_encoders:
        lo, hi = start, start + batch[f"{key}_emb"].size(-1)
        if key == "action":
            action = (lo, hi)
        else:
            batch[f"{key}_loss"] = F.mse_loss(pred[..., lo:hi], target[..., lo:hi])
        start = hi

    def strip(t: torch.Tensor) -> torch.Tensor:
        return torch.cat([t[..., : action[0]], t[..., action[1] :]], dim=-1)

    batch["loss"] = F.mse_loss(strip(pred), strip(target))
    return batch


def main() -> None:
    torch.manual_seed(1234)
    model = build().train()
    init = {k: v.detach().clone() for k, v in model.state_dict().items()}
    g = torch.Generator().manual_seed(7)
    s = SIZES
    frames = s["history"] + s["num_preds"]
    pixels = torch.randn(6, frames, 3, s["image"], s["image"], generator=g)
    action = torch.randn(6, frames, s["action_dim"], generator=g)
    action[:, -1] = float("nan")  # the last step of a clip has no action in the datasets
    proprio = torch.randn(6, frames, s["proprio_dim"], generator=g)
    opt = torch.optim.AdamW(model.parameters(), lr=s["lr"])
    out = dinowm_forward(model, {"pixels": pixels.clone(), "action": action.clone(), "proprio": proprio.clone()})
    opt.zero_grad()
    out["loss"].backward()
    grads = {k: v.grad.detach().clone() for k, v in model.named_parameters() if v.grad is not None}
    opt.step()
    after = model.state_dict()
    np.savez_compressed(
        OUT,
        pixels=pixels.numpy(),
        action=action.numpy(),
        proprio=proprio.numpy(),
        **{name: out[name].item() for name in LOSSES},
        **{f"init/{k}": v.numpy() for k, v in init.items()},
        **{f"after/{k}": v.detach().numpy() for k, v in after.items()},
        **{f"grad/{k}": v.numpy() for k, v in grads.items()},
    )
    print(f"wrote {OUT}: " + ", ".join(f"{t} {out[t].item():.6f}" for t in LOSSES) + f"; {len(grads)} gradients")


if __name__ == "__main__":
    main()

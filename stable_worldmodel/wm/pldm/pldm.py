"""PLDM (Planning with Latent Dynamics Models, arXiv 2502.14819): a JEPA trained with a
prediction loss, VCReg, temporal alignment, temporal straightening and an inverse
dynamics model (upstream 0.1.1's ``stable_worldmodel.wm.pldm.PLDM``)."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import torch
from torch import nn

from ...errors import ConfigError
from ..jepa import JEPA
from ..loss import PLDMLoss, TemporalStraighteningLoss

__all__ = ["PLDM", "DEFAULT_LOSS_WEIGHTS"]

#: weight of each named term in ``loss`` (``pred_loss`` has weight 1)
DEFAULT_LOSS_WEIGHTS = {
    "std_loss": 1.0,
    "cov_loss": 0.5,
    "std_t_loss": 0.0,
    "cov_t_loss": 0.0,
    "temp_align_loss": 0.1,
    "temp_straight_loss": 0.0,
    "idm_loss": 1.0,
}


class PLDM(JEPA):
    """PLDM: ``PLDM(encoder, predictor, action_encoder, projector=None, pred_proj=None, idm=None)``.

    Same constructor, methods and ``state_dict`` keys as upstream 0.1.1; ``idm`` (keyword,
    default None: no inverse-dynamics term and no extra keys) is the inverse dynamics model,
    ``(N, 2 D) -> (N, A)``: it predicts the action block between two consecutive embeddings
    (``cat(z[t+1], z[t])``). ``loss_weights`` overrides :data:`DEFAULT_LOSS_WEIGHTS`.
    ``rollout_steps`` (keyword, 0: upstream's objective) K > 0 adds ``rollout_loss`` with weight 1:
    the error of K open-loop predictions as planning makes them (see ``JEPA._teacher_forcing``).
    """

    def __init__(
        self,
        encoder: nn.Module,
        predictor: nn.Module,
        action_encoder: nn.Module,
        projector: nn.Module | None = None,
        pred_proj: nn.Module | None = None,
        idm: nn.Module | None = None,
        *,
        num_preds: int = 1,
        history_size: int | None = None,
        rollout_steps: int = 0,
        loss_weights: Mapping[str, float] | None = None,
        **kwargs: Any,
    ):
        super().__init__(encoder, predictor, action_encoder, projector, pred_proj, **kwargs)
        if idm is not None:
            self.idm = idm
        unknown = set(loss_weights or {}) - set(DEFAULT_LOSS_WEIGHTS)
        if unknown:
            raise ConfigError(
                f"PLDM requires loss_weights keys among {sorted(DEFAULT_LOSS_WEIGHTS)}, got {sorted(unknown)}"
            )
        self.loss_weights = {**DEFAULT_LOSS_WEIGHTS, **dict(loss_weights or {})}
        self.num_preds, self.loss_history, self.rollout_steps = int(num_preds), history_size, int(rollout_steps)
        self.pldm_loss = _Unregistered(PLDMLoss())
        self.straightening = _Unregistered(TemporalStraighteningLoss())

    def loss(self, batch: dict) -> dict:
        out, pred_loss = self._teacher_forcing(batch, self.loss_history, self.num_preds, self.rollout_steps)
        emb, action = out["emb"], out["action"]
        a_pred = a_target = None
        if getattr(self, "idm", None) is not None:
            pairs = torch.cat([emb[:, 1:], emb[:, :-1]], dim=-1)
            a_pred = self.idm(pairs.reshape(-1, pairs.shape[-1])).reshape(*pairs.shape[:2], -1)
            a_target = action[:, :-1]
        terms = {"pred_loss": pred_loss, **self.pldm_loss.module(emb, a_pred, a_target)}
        if emb.shape[1] >= 3:
            terms["temp_straight_loss"] = self.straightening.module(emb)
        if "rollout_loss" in out:
            terms["rollout_loss"] = out["rollout_loss"]
        total = pred_loss + out.get("rollout_loss", 0.0)
        for name, weight in self.loss_weights.items():
            if name in terms:  # a zero weight too, as upstream's recipe adds every enabled term (its modules then
                total = total + weight * terms[name]  # get zero gradients, which AdamW's weight decay still acts on)
        return {"loss": total, **terms, "emb": emb}


class _Unregistered:
    """Holds a parameter-free loss module outside the module tree (no state-dict keys)."""

    def __init__(self, module: nn.Module):
        self.module = module

"""LeWM (LeWorldModel): a JEPA trained end to end from pixels with a prediction loss and
SIGReg as the only anti-collapse term (upstream 0.1.1's ``stable_worldmodel.wm.lewm.LeWM``)."""

from __future__ import annotations

from typing import Any

import torch
from torch import nn

from ..jepa import JEPA
from ..loss import SIGReg

__all__ = ["LeWM"]


class LeWM(JEPA):
    """LeWM: ``LeWM(encoder, predictor, action_encoder, projector=None, pred_proj=None)``.

    Same constructor, methods and ``state_dict`` keys as upstream 0.1.1. Training knobs
    (keyword-only, not part of the state dict): ``num_preds`` (frames ahead, default 1),
    ``history_size`` (context frames in the loss, default ``predictor.num_frames``),
    ``rollout_steps`` (0, upstream's objective; K > 0 adds ``rollout_loss``, the error of K
    open-loop predictions as planning makes them, see ``JEPA._teacher_forcing``),
    ``sigreg_weight`` (default 0.09), ``sigreg_knots`` (17) and ``sigreg_num_proj`` (1024).

    :meth:`loss` (``batch``: ``pixels (B, T, C, h, w)`` preprocessed floats and normalized
    ``action (B, T, A)``) returns ``loss = pred_loss + sigreg_weight * sigreg_loss`` with
    ``pred_loss`` the teacher-forced MSE of the next embeddings and ``sigreg_loss`` SIGReg
    of all the embeddings ``(T, B, D)`` (plus ``rollout_loss`` when ``rollout_steps > 0``).
    """

    def __init__(
        self,
        encoder: nn.Module,
        predictor: nn.Module,
        action_encoder: nn.Module,
        projector: nn.Module | None = None,
        pred_proj: nn.Module | None = None,
        *,
        num_preds: int = 1,
        history_size: int | None = None,
        rollout_steps: int = 0,
        sigreg_weight: float = 0.09,
        sigreg_knots: int = 17,
        sigreg_num_proj: int = 1024,
        **kwargs: Any,
    ):
        super().__init__(encoder, predictor, action_encoder, projector, pred_proj, **kwargs)
        self.num_preds, self.loss_history, self.rollout_steps = int(num_preds), history_size, int(rollout_steps)
        self.sigreg_weight = float(sigreg_weight)
        # kept out of the module tree: its buffers must not enter the state dict (upstream's has none)
        self._sigreg = {"module": SIGReg(knots=sigreg_knots, num_proj=sigreg_num_proj)}

    def __setstate__(self, state: dict) -> None:
        """A LeWM that upstream 0.1.1 pickled (``*_object.ckpt``) lacks our training attributes:
        they get the constructor's defaults."""
        super().__setstate__(state)
        for name, value in (("num_preds", 1), ("loss_history", None), ("sigreg_weight", 0.09)):
            self.__dict__.setdefault(name, value)
        if "_sigreg" not in self.__dict__:
            self._sigreg = {"module": SIGReg(knots=17, num_proj=1024)}

    def _sigreg_on(self, device: torch.device) -> SIGReg:
        module = self._sigreg["module"]
        if module.t.device != device:
            module = self._sigreg["module"] = module.to(device)
        return module

    def loss(self, batch: dict) -> dict:
        out, pred_loss = self._teacher_forcing(batch, self.loss_history, self.num_preds, self.rollout_steps)
        emb = out["emb"]
        sigreg = self._sigreg_on(emb.device)(emb.transpose(0, 1))
        terms = {"pred_loss": pred_loss, "sigreg_loss": sigreg}
        total = pred_loss + self.sigreg_weight * sigreg
        if "rollout_loss" in out:
            terms["rollout_loss"] = out["rollout_loss"]
            total = total + out["rollout_loss"]
        return {"loss": total, **terms, "emb": emb}

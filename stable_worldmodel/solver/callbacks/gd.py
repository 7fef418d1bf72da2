"""Recorders of the gradient solvers (gradient descent, PGD, Lagrangian)."""

from __future__ import annotations

from typing import Any

from .common import Callback, Reduction


class GradNormRecorder(Callback):
    """The gradient's L2 norm w.r.t. the plans (per env, mean over samples); ``per_step=True``
    records one norm per horizon step instead."""

    def __init__(self, reduction: Reduction = "mean", per_step: bool = False) -> None:
        super().__init__(reduction)
        self.per_step = bool(per_step)

    def compute(self, **state: Any) -> Any:
        params = state["params"]
        grad = params.grad
        if self.per_step:
            horizon = params.shape[2]
            if grad is None:
                return [0.0] * horizon
            per_step = grad.detach().norm(dim=-1).mean(dim=1)  # (b, H)
            return [self._reduce(per_step[:, h]) for h in range(horizon)]
        if grad is None:
            return 0.0
        return self._reduce(grad.detach().flatten(2).norm(dim=-1).mean(dim=-1))


class ActionNormRecorder(Callback):
    """The plans' L2 norm (per env, mean over samples)."""

    def compute(self, **state: Any) -> Any:
        return self._reduce(state["params"].detach().flatten(2).norm(dim=-1).mean(dim=-1))

"""Recorders of the sampling solvers' distribution (CEM, iCEM)."""

from __future__ import annotations

from typing import Any

from .common import Callback


class EliteCostRecorder(Callback):
    """The elites' costs at each iteration: ``{"mean", "min", "max"}`` (each reduced over envs)."""

    def compute(self, **state: Any) -> dict[str, Any]:
        vals = state["topk_vals"].detach()
        return {
            "mean": self._reduce(vals.mean(dim=1)),
            "min": self._reduce(vals.min(dim=1).values),
            "max": self._reduce(vals.max(dim=1).values),
        }


class VarNormRecorder(Callback):
    """The mean spread of the sampling distribution after each refit (per env)."""

    def compute(self, **state: Any) -> Any:
        return self._reduce(state["var"].detach().flatten(1).mean(dim=-1))


class MeanShiftRecorder(Callback):
    """How far the distribution's mean moved in an iteration (L2, per env); nothing the first time
    when the solver passes no previous mean."""

    def compute(self, **state: Any) -> Any:
        prev = state.get("prev_mean")
        if prev is None:
            return None
        return self._reduce((state["mean"] - prev).detach().flatten(1).norm(dim=-1))


class EliteSpreadRecorder(Callback):
    """The elites' standard deviation (their diversity), averaged over the plan (per env)."""

    def compute(self, **state: Any) -> Any:
        return self._reduce(state["topk_candidates"].detach().float().std(dim=1).flatten(1).mean(dim=-1))

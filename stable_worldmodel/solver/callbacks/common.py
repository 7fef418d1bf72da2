"""The callback base and the recorders every solver feeds.

State each solver passes (keyword arguments, tensors of the current batch of ``b`` envs):

* CEM / iCEM / categorical CEM: ``step``, ``candidates (b, S, H, A)``, ``costs (b, S)``,
  ``topk_vals (b, k)``, ``topk_inds (b, k)``, ``topk_candidates (b, k, H, A)``, ``mean`` and
  ``var`` (the distribution after the refit; categorical CEM: ``probs``), ``prev_mean``, ``prev_var``;
* gradient descent / PGD / Lagrangian: ``step``, ``params`` (the optimized tensor, ``.grad``
  set), ``cost`` (the summed loss), ``costs (b, S)``;
* predictive sampling: ``step``, ``candidates``, ``costs``.
"""

from __future__ import annotations

import math
from typing import Any, Literal

import torch

from ...errors import ConfigError

Reduction = Literal["mean", "sum", "none"]
REDUCTIONS = ("mean", "sum", "none")


class Callback:
    """A per-iteration hook: subclasses implement :meth:`compute` (``None`` records nothing).

    ``reduction`` folds a per-env value over the envs of a batch: ``"mean"``, ``"sum"`` or
    ``"none"`` (a list, one value per env). ``history`` is a list per batch of envs of the
    values of each iteration. ``stop``: set it to True to end the current batch's iterations.
    """

    #: key of the history in ``outputs["callbacks"]`` (default: the class name)
    name: str | None = None

    def __init__(self, reduction: Reduction = "mean") -> None:
        if reduction not in REDUCTIONS:
            raise ConfigError(
                f"{type(self).__name__} requires reduction in {', '.join(map(repr, REDUCTIONS))}, got {reduction!r}"
            )
        self.reduction = reduction
        self.history: list[list[Any]] = []
        self._current: list[Any] = []
        self.stop = False

    def _reduce(self, x: torch.Tensor) -> float | list[float]:
        x = x.detach().float()
        if self.reduction == "mean":
            return x.mean().item()
        if self.reduction == "sum":
            return x.sum().item()
        return x.cpu().tolist()

    def reset(self) -> None:
        """A new solve: forget the histories."""
        self.history, self._current, self.stop = [], [], False

    def start_batch(self) -> None:
        """A new batch of envs: close the current history list."""
        if self._current:
            self.history.append(self._current)
        self._current, self.stop = [], False

    def end_solve(self) -> None:
        """The solve ended: close the current history list."""
        if self._current:
            self.history.append(self._current)
            self._current = []

    def __call__(self, **state: Any) -> None:
        value = self.compute(**state)
        if value is not None:
            self._current.append(value)

    def compute(self, **state: Any) -> Any:
        raise NotImplementedError(f"{type(self).__name__}.compute(**state) -> a value to record (or None)")

    @property
    def output_key(self) -> str:
        return self.name or type(self).__name__


class BestCostRecorder(Callback):
    """The cheapest sample's cost at each iteration (per env)."""

    def compute(self, **state: Any) -> float | list[float]:
        return self._reduce(state["costs"].min(dim=1).values)


class MeanCostRecorder(Callback):
    """The mean cost over the samples at each iteration (per env)."""

    def compute(self, **state: Any) -> float | list[float]:
        return self._reduce(state["costs"].mean(dim=1))


class EarlyStopping(Callback):
    """Stop iterating once the best cost has improved by less than ``min_delta`` (relative to
    its size, for every env of the batch) for ``patience`` iterations in a row. Records the best
    cost of each iteration (mean over envs)."""

    def __init__(self, patience: int = 3, min_delta: float = 1e-4) -> None:
        super().__init__("mean")
        if isinstance(patience, bool) or not isinstance(patience, int) or patience < 1:
            raise ConfigError(f"EarlyStopping requires patience to be an integer >= 1, got {patience!r}")
        if isinstance(min_delta, bool) or not isinstance(min_delta, (int, float)) or not math.isfinite(min_delta):
            raise ConfigError(f"EarlyStopping requires min_delta to be a finite number >= 0, got {min_delta!r}")
        self.patience, self.min_delta = patience, float(min_delta)
        self._best: torch.Tensor | None = None
        self._flat = 0

    def start_batch(self) -> None:
        super().start_batch()
        self._best, self._flat = None, 0

    def compute(self, **state: Any) -> float:
        best = state["costs"].detach().min(dim=1).values.float()
        if self._best is not None:
            improved = (self._best - best) > self.min_delta * self._best.abs().clamp_min(1.0)
            self._flat = 0 if bool(improved.any()) else self._flat + 1
            best = torch.minimum(best, self._best)
        self._best = best
        self.stop = self._flat >= self.patience
        return best.mean().item()

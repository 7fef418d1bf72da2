"""Any `nevergrad <https://facebookresearch.github.io/nevergrad/>`_ optimizer as a solver.

Needs the ``nevergrad`` extra: ``pip install "stable-worldmodel[nevergrad]"``.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import torch

from .._optional import require
from ..errors import ConfigError
from ._registry import register_solver
from .base import AUTO_BATCH, BaseSolver, PlanKnobs


@register_solver("nevergrad")
class NevergradSolver(BaseSolver):
    """One nevergrad optimizer per env; candidates of all envs are scored in one batch.

    ``optimizer`` names an entry of ``nevergrad.optimizers.registry`` (e.g. ``"CMA"``,
    ``"TwoPointsDE"``, ``"OnePlusOne"``). Each of ``n_steps`` rounds asks every env's
    optimizer for ``num_samples`` candidates, scores the ``(B, S, H, A)`` batch with one
    ``get_cost`` call and tells the costs back (budget ``n_steps * num_samples`` per env).
    The search starts at the warm start (or zeros); finite Box bounds become the
    parametrization's bounds (clipping); the initial mutation sigma is ``var_scale``,
    at most a third of the narrowest bound interval. Returns the cheapest evaluated plan
    per env, ``actions: (B, H, A)``, and its ``costs: (B,)``.
    Nevergrad runs on the CPU, so each round copies the costs to the host.
    """

    knobs = PlanKnobs(summary="a nevergrad optimizer per env (CMA; needs the nevergrad extra)")

    def __init__(
        self,
        model: Any,
        optimizer: str = "CMA",
        n_steps: int = 30,
        num_samples: int = 16,
        batch_size: int | None = AUTO_BATCH,
        var_scale: float = 1.0,
        device: str | torch.device | None = "cpu",
        seed: int = 1234,
    ) -> None:
        self._ng = require("nevergrad", extra="nevergrad", purpose="NevergradSolver")
        if optimizer not in self._ng.optimizers.registry:
            from ..errors import unknown_name

            raise unknown_name("nevergrad optimizer", optimizer, self._ng.optimizers.registry)
        super().__init__(model, batch_size, num_samples, var_scale, device, seed, n_steps)
        self._check_number("var_scale", var_scale, minimum=0.0, strict=True)  # the mutation sigma: 0 never moves
        self.optimizer = optimizer

    def _make_optimizer(self, row: int, start: np.ndarray) -> Any:
        ng = self._ng
        low, high = self._low[row].cpu().numpy(), self._high[row].cpu().numpy()
        param = ng.p.Array(init=start.astype(np.float64))
        bounded = bool(np.isfinite(low).all() and np.isfinite(high).all())
        param.set_mutation(sigma=min(self.var_scale, float((high - low).min()) / 3) if bounded else self.var_scale)
        if bounded:
            shape = start.shape
            param.set_bounds(np.broadcast_to(low, shape).copy(), np.broadcast_to(high, shape).copy(), method="clipping")
        param.random_state = np.random.RandomState((self._solve_seed + row) % (2**32))
        budget = self.n_steps * self.num_samples
        return ng.optimizers.registry[self.optimizer](
            parametrization=param, budget=budget, num_workers=self.num_samples
        )

    @torch.no_grad()
    def _optimize(self, info: dict, init_action: torch.Tensor | None) -> dict:
        start, stop = self._rows
        starts = self._initial_mean(init_action).cpu().numpy()
        optimizers = [self._make_optimizer(row, starts[row - start]) for row in range(start, stop)]
        info_s = self._expand(info, self.num_samples)
        best = starts.copy()
        best_costs = np.full(len(optimizers), np.inf)
        for _ in range(self.n_steps):
            asked = [[opt.ask() for _ in range(self.num_samples)] for opt in optimizers]
            values = np.stack([np.stack([c.value for c in row]) for row in asked])
            candidates = torch.as_tensor(values, device=self.device, dtype=self.dtype)
            costs = self._cost(info_s, candidates).float().cpu().numpy()
            if not np.isfinite(costs).all():
                raise ConfigError("NevergradSolver requires finite costs from get_cost, got NaN or inf")
            for opt, row, row_costs in zip(optimizers, asked, costs, strict=False):
                for cand, cost in zip(row, row_costs, strict=False):
                    opt.tell(cand, float(cost))
            pick = costs.argmin(axis=1)
            better = costs[np.arange(len(pick)), pick] < best_costs
            best[better] = values[better, pick[better]]
            best_costs = np.minimum(best_costs, costs.min(axis=1))
        actions = torch.as_tensor(best, device=self.device, dtype=self.dtype)
        return {"actions": actions, "costs": torch.as_tensor(best_costs, device=self.device, dtype=self.dtype)}

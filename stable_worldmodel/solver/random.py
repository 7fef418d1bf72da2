"""Random shooting: sample candidate plans, keep the cheapest."""

from __future__ import annotations

from typing import Any

import torch

from ._registry import register_solver
from .base import AUTO_BATCH, BaseSolver, PlanKnobs


@register_solver("random")
class RandomSolver(BaseSolver):
    """Random shooting, batched over envs.

    Each of ``n_steps`` rounds draws ``num_samples`` candidates ``(B, S, H, A)``: uniform
    in the Box bounds where both are finite, else Gaussian with std ``var_scale`` around
    the warm start (or zeros). Candidate 0 of the first round is the warm start itself.
    Returns the cheapest plan seen, ``actions: (B, H, A)``, and its ``costs: (B,)``.
    """

    _inference_mode = True
    knobs = PlanKnobs(iterations=None, summary="random shooting: the best of uniform samples")

    def __init__(
        self,
        model: Any,
        batch_size: int | None = AUTO_BATCH,
        num_samples: int = 300,
        n_steps: int = 1,
        var_scale: float = 1.0,
        device: str | torch.device | None = "cpu",
        seed: int = 1234,
    ) -> None:
        super().__init__(model, batch_size, num_samples, var_scale, device, seed, n_steps)

    def _optimize(self, info: dict, init_action: torch.Tensor | None) -> dict:
        start, stop = self._rows
        low, high = self._low[start:stop, None, None], self._high[start:stop, None, None]
        finite = torch.isfinite(low) & torch.isfinite(high)
        center = self._initial_mean(init_action).unsqueeze(1)
        info_s = self._expand(info, self.num_samples)
        shape = (self.num_samples, self.horizon, self.action_dim)
        best, best_cost = center[:, 0], None
        for step in range(self.n_steps):
            uniform = torch.where(finite, low, 0) + torch.where(finite, high - low, 0) * self._rand(*shape)
            gauss = self._clamp(center + self.var_scale * self._randn(*shape))
            candidates = torch.where(finite, uniform, gauss)
            if step == 0:
                candidates[:, 0] = center[:, 0]
            costs = self._cost(info_s, candidates)
            cost, idx = costs.min(dim=1)
            pick = candidates[torch.arange(candidates.shape[0], device=self.device), idx]
            if best_cost is None:
                best, best_cost = pick, cost
            else:
                better = cost < best_cost
                best = torch.where(better[:, None, None], pick, best)
                best_cost = torch.minimum(cost, best_cost)
        return {"actions": best, "costs": best_cost}

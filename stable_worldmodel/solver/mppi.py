"""Model Predictive Path Integral: a softmax-weighted update of mean and variance."""

from __future__ import annotations

from typing import Any

import torch

from ._registry import register_solver
from ._start import GaussianStart
from .base import AUTO_BATCH, BaseSolver, PlanKnobs


@register_solver("mppi")
class MPPISolver(GaussianStart, BaseSolver):
    """MPPI over action sequences, batched over envs.

    Each of ``n_steps`` iterations samples ``num_samples`` candidates ``(B, S, H, A)``
    around the mean (candidate 0 is the mean), keeps the ``topk`` cheapest and weights them
    by ``softmax(-(cost - min) / (temperature * (max - min)))`` over the elites: the
    temperature is relative to the elites' cost spread, so it does not depend on the cost
    scale (0.5: the worst elite weighs ``e**-2`` of the best). Mean *and* std are refit to the
    weighted elites (variance adaptation), so the distribution contracts and converges.
    ``batch_size`` works as in :class:`~stable_worldmodel.solver.CEMSolver`.
    Returns ``actions: (B, H, A)`` (final mean), ``costs: (B,)``, ``mean``, ``var`` (std).
    """

    _inference_mode = True
    _uses_topk = True
    knobs = PlanKnobs(elites="topk", summary="model-predictive path integral: cost-weighted average")

    def __init__(
        self,
        model: Any,
        batch_size: int | None = AUTO_BATCH,
        num_samples: int = 300,
        var_scale: float = 1.0,
        n_steps: int = 30,
        topk: int = 30,
        temperature: float = 0.5,
        device: str | torch.device | None = "cpu",
        seed: int = 1234,
    ) -> None:
        super().__init__(model, batch_size, num_samples, var_scale, device, seed, n_steps, topk)
        self.temperature = self._check_number("temperature", temperature, minimum=0.0, strict=True)

    def _optimize(self, info: dict, init_action: torch.Tensor | None) -> dict:
        mean, std, info_s = self._gaussian_start(info, init_action)
        for _ in range(self.n_steps):
            elite_costs, elites = self._sample_elites(info_s, mean, std, self.topk)
            spread = (elite_costs[:, -1:] - elite_costs[:, :1]).clamp_min(1e-12)
            weights = torch.softmax(-(elite_costs - elite_costs[:, :1]) / (self.temperature * spread), dim=1)
            weights = weights[:, :, None, None]
            mean = (weights * elites).sum(dim=1)
            std = (weights * (elites - mean.unsqueeze(1)) ** 2).sum(dim=1).sqrt()
        return {"actions": mean, "costs": elite_costs[:, 0], "mean": mean, "var": std}

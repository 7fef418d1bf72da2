"""Predictive Sampling (Howell et al., 2022, "Predictive Sampling: Real-time Behaviour Synthesis
with MuJoCo"): perturb the nominal plan with Gaussian noise, keep the cheapest."""

from __future__ import annotations

from typing import Any

import torch

from ._registry import register_solver
from .base import AUTO_BATCH, BaseSolver, PlanKnobs


@register_solver("predictive_sampling")
class PredictiveSamplingSolver(BaseSolver):
    """Predictive Sampling over action sequences, batched over envs (upstream 0.1.1's signature).

    Each of ``n_steps`` rounds (upstream: one) draws ``num_samples`` candidates
    ``nominal + noise_scale * N(0, 1)`` ``(B, S, H, A)``, candidate 0 being the nominal itself (so
    the answer is never worse than the warm start), clamped into the Box bounds; the cheapest
    becomes the nominal. The nominal starts at ``init_action`` (the previous plan, shifted by the
    policy) or zeros. Returns ``actions: (B, H, A)`` and ``costs: (B,)``; ``callbacks`` get
    ``step``, ``candidates`` and ``costs``.
    """

    _inference_mode = True
    knobs = PlanKnobs(summary="predictive sampling: the best Gaussian perturbation of the last plan")

    def __init__(
        self,
        model: Any,
        batch_size: int | None = AUTO_BATCH,
        num_samples: int = 300,
        noise_scale: float = 1.0,
        device: str | torch.device | None = "cpu",
        seed: int = 1234,
        n_steps: int = 1,
        callbacks: list | None = None,
    ) -> None:
        super().__init__(model, batch_size, num_samples, 1.0, device, seed, n_steps, callbacks=callbacks)
        self.noise_scale = self._check_number("noise_scale", noise_scale, minimum=0.0)

    def _optimize(self, info: dict, init_action: torch.Tensor | None) -> dict:
        nominal = self._initial_mean(init_action)
        info_s = self._expand(info, self.num_samples)
        rows = torch.arange(nominal.shape[0], device=self.device)
        cost = None
        for step in range(self.n_steps):
            noise = self._randn(self.num_samples, self.horizon, self.action_dim)
            noise[:, 0].zero_()
            candidates = self._clamp_(torch.add(nominal.unsqueeze(1), noise, alpha=self.noise_scale))
            costs = self._cost(info_s, candidates)
            cost, idx = costs.min(dim=1)
            nominal = candidates[rows, idx]
            if self.callbacks and self._notify(step=step, candidates=candidates, costs=costs):
                break
        return {"actions": nominal, "costs": cost}

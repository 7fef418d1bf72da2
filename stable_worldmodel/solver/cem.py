"""Cross-Entropy Method: refit a diagonal Gaussian to the ``topk`` cheapest candidates."""

from __future__ import annotations

from typing import Any

import torch

from ._registry import register_solver
from ._start import GaussianStart
from .base import AUTO_BATCH, BaseSolver, PlanKnobs


@register_solver("cem")
class CEMSolver(GaussianStart, BaseSolver):
    """Cross-Entropy Method over action sequences, batched over envs.

    Each of ``n_steps`` iterations samples ``num_samples`` candidates ``(B, S, H, A)``
    around the mean (candidate 0 is the mean itself), clamps them into the Box bounds,
    and refits mean and std to the ``topk`` cheapest. The initial std is ``var_scale``
    (in action units; 0 samples nothing but the mean); the initial mean is ``init_action``
    (warm start) or zeros. :meth:`init_action_distrib` returns that starting ``(mean, var)``.

    ``batch_size``: the default (shown as 1, the original's value) plans all envs in one
    pass; an explicit int caps the envs per pass (``batch_size=1`` is the original's
    env-by-env loop), ``None`` also means all. Returns ``actions: (B, H, A)`` (the final
    mean), ``costs: (B,)`` (cost of the best elite of the last iteration), ``mean`` and
    ``var`` (the final std, ``(B, H, A)``), all on the CPU.

    Example::

        >>> import gymnasium as gym, numpy as np, torch
        >>> from stable_worldmodel.policy import PlanConfig
        >>> class Bowl:
        ...     def get_cost(self, info, candidates):  # (B, S, H, A) -> (B, S)
        ...         return ((candidates - 0.5) ** 2).sum(dim=(2, 3))
        >>> solver = CEMSolver(Bowl(), num_samples=64, n_steps=10, topk=8)
        >>> solver.configure(action_space=gym.spaces.Box(-1, 1, (3, 2)), n_envs=3, config=PlanConfig(2, 1))
        >>> solver.solve({})["actions"].shape
        torch.Size([3, 2, 2])
    """

    _inference_mode = True
    _uses_topk = True
    knobs = PlanKnobs(elites="topk", summary="cross-entropy method: Gaussian refitted to the best samples")

    def __init__(
        self,
        model: Any,
        batch_size: int | None = AUTO_BATCH,
        num_samples: int = 300,
        var_scale: float = 1,
        n_steps: int = 30,
        topk: int = 30,
        device: str | torch.device | None = "cpu",
        seed: int = 1234,
        callbacks: list | None = None,
    ) -> None:
        super().__init__(model, batch_size, num_samples, var_scale, device, seed, n_steps, topk, callbacks=callbacks)

    def _optimize(self, info: dict, init_action: torch.Tensor | None) -> dict:
        mean, std, info_s = self._gaussian_start(info, init_action)
        for step in range(self.n_steps):
            if not self.callbacks:
                elite_costs, elites = self._sample_elites(info_s, mean, std, self.topk)
                mean, std = self._mean_std(elites)
                continue
            candidates = self._sample_around(mean, std, self.num_samples)
            costs = self._cost(info_s, candidates)
            elite_costs, elites = self._elites(candidates, costs, self.topk)
            prev_mean, prev_var = mean, std
            mean, std = self._mean_std(elites)
            state = dict(candidates=candidates, costs=costs, topk_vals=elite_costs, topk_candidates=elites)
            topk_inds = costs.topk(self.topk, dim=1, largest=False).indices
            if self._notify(
                step=step, **state, topk_inds=topk_inds, mean=mean, var=std, prev_mean=prev_mean, prev_var=prev_var
            ):
                break
        return {"actions": mean, "costs": elite_costs[:, 0], "mean": mean, "var": std}

"""Categorical CEM: the cross-entropy method over discrete actions (upstream 0.1.1)."""

from __future__ import annotations

from typing import Any

import torch

from ._registry import register_solver
from .base import AUTO_BATCH, BaseSolver, PlanKnobs
from .discrete_solvers import DiscreteActions


@register_solver("categorical_cem")
class CategoricalCEMSolver(DiscreteActions, BaseSolver):
    """CEM with a categorical distribution per action of every block, batched over envs.

    The action space is discrete (see :class:`~stable_worldmodel.solver.discrete_solvers.DiscreteActions`:
    ``Discrete(n)``, or the batched ``MultiDiscrete``). ``probs: (B, H, A, n)`` start uniform;
    each of ``n_steps`` iterations draws ``num_samples`` plans by Gumbel-max (plan 0 is the
    argmax of ``probs``), scores their one-hots ``(B, S, H, A * n)`` with ``get_cost``, and refits
    ``probs`` to the ``topk`` cheapest plans' frequencies, plus ``smoothing`` (then renormalized;
    it keeps every action possible) and blended with the old ones by ``alpha`` (0: replaced).
    ``init_action`` is ignored, as upstream's. Returns ``actions: (B, H, A)`` int64 (the argmax
    of the final ``probs``), ``costs: (B,)`` (the best elite's), and ``probs``. ``callbacks``
    get CEM's state with ``probs`` / ``prev_probs`` in place of mean and var.
    """

    _inference_mode = True
    _uses_topk = True
    knobs = PlanKnobs(elites="topk", summary="categorical CEM (discrete actions)")

    def __init__(
        self,
        model: Any,
        batch_size: int | None = AUTO_BATCH,
        num_samples: int = 300,
        n_steps: int = 30,
        topk: int = 30,
        smoothing: float = 0.0,
        alpha: float = 0.0,
        device: str | torch.device | None = "cpu",
        seed: int = 1234,
        callbacks: list | None = None,
    ) -> None:
        super().__init__(model, batch_size, num_samples, 1.0, device, seed, n_steps, topk, callbacks=callbacks)
        self.smoothing = self._check_number("smoothing", smoothing, minimum=0.0)
        self.alpha = self._check_number("alpha", alpha, minimum=0.0, maximum=1.0)

    def solve(self, info_dict: dict, init_action: Any = None) -> dict:
        """Plan for every env (``init_action`` is accepted and ignored, as upstream's)."""
        return super().solve(info_dict, init_action=None)

    def _optimize(self, info: dict, init_action: torch.Tensor | None) -> dict:
        b = self._rows[1] - self._rows[0]
        h, a, n, s = self.horizon, self.action_dim, self.n_choices, self.num_samples
        probs = torch.full((b, h, a, n), 1.0 / n, device=self.device, dtype=self.dtype)
        info_s = self._expand(info, s)
        elite_costs = None
        for step in range(self.n_steps):
            gumbel = -torch.log(-torch.log(self._rand(s, h, a, n).clamp_min(1e-10)))
            index = (probs.clamp_min(1e-10).log().unsqueeze(1) + gumbel).argmax(dim=-1)  # (b, S, H, A)
            index[:, 0] = probs.argmax(dim=-1)
            one_hot = torch.nn.functional.one_hot(index, n).to(self.dtype)  # (b, S, H, A, n)
            candidates = one_hot.flatten(-2)
            costs = self._cost(info_s, candidates)
            elite_costs, elites = self._elites(one_hot, costs, self.topk)  # elites (b, k, H, A, n)
            fit = elites.mean(dim=1)
            if self.smoothing > 0:
                fit = (fit + self.smoothing) / (fit + self.smoothing).sum(dim=-1, keepdim=True)
            prev = probs
            probs = torch.lerp(fit, probs, self.alpha) if self.alpha > 0 else fit
            if self.callbacks:
                topk_inds = costs.topk(self.topk, dim=1, largest=False).indices
                state = dict(candidates=candidates, costs=costs, topk_vals=elite_costs, topk_inds=topk_inds)
                if self._notify(step=step, **state, topk_candidates=elites.flatten(-2), probs=probs, prev_probs=prev):
                    break
        return {"actions": probs.argmax(dim=-1), "costs": elite_costs[:, 0], "probs": probs}

"""Augmented-Lagrangian gradient descent: a cost to minimize under inequality constraints."""

from __future__ import annotations

from typing import Any

import torch

from ..errors import ConfigError, check_int
from ._registry import register_solver
from .base import PlanKnobs
from .gd import GradientSolver


@register_solver("lagrangian")
class LagrangianSolver(GradientSolver):
    """Gradient descent on the augmented Lagrangian of a constrained plan (upstream 0.1.1's signature).

    The model's ``get_cost(info, candidates) -> (B, S)`` is minimized subject to
    ``get_constraints(info, candidates) -> (B, S, C) <= 0`` when the model has that method (an
    equality is two inequalities: ``g <= 0`` and ``-g <= 0``). Each of ``n_outer_steps`` outer
    iterations runs ``n_steps`` optimizer steps (a fresh optimizer each time) on::

        L = cost + sum_i lambda_i * g_i + rho * sum_i max(0, g_i) ** 2

    then raises the multipliers by dual ascent, ``lambda <- max(0, lambda + rho * mean_S(g))``,
    and ``rho <- min(rho_max, rho * rho_scale)``. The multipliers are per env and carried to the
    next ``solve`` (a warm start, as the plan is) unless ``persist_multipliers=False``. Without
    ``get_constraints`` it is plain gradient descent. Plans start as in
    :class:`~stable_worldmodel.solver.GradientSolver` (default optimizer: Adam, ``lr`` 1.0).

    Returns ``actions: (B, H, A)``, ``costs: (B,)`` (the model's cost of the plan returned),
    ``lambdas: (B, C)`` and ``constraint_violation: (B,)`` (mean ``max(0, g)`` of that plan);
    the last two are absent without constraints.
    """

    knobs = PlanKnobs(samples=None, fixed=(("num_samples", 1),), summary="augmented Lagrangian gradient descent")

    def __init__(
        self,
        model: Any,
        n_steps: int,
        n_outer_steps: int = 5,
        batch_size: int | None = None,
        num_samples: int = 1,
        var_scale: float = 1.0,
        action_noise: float = 0.0,
        rho_init: float = 1.0,
        rho_max: float = 1e4,
        rho_scale: float = 2.0,
        persist_multipliers: bool = True,
        device: str | torch.device | None = "cpu",
        seed: int = 1234,
        optimizer_cls: type[torch.optim.Optimizer] = torch.optim.Adam,
        optimizer_kwargs: dict | None = None,
        grad_clip: float | None = None,
        callbacks: list | None = None,
    ) -> None:
        super().__init__(
            model,
            n_steps,
            batch_size,
            var_scale,
            num_samples,
            action_noise,
            device,
            seed,
            optimizer_cls,
            {"lr": 1.0} if optimizer_kwargs is None else optimizer_kwargs,
            grad_clip,
            callbacks,
        )
        self.n_outer_steps = check_int(type(self).__name__, "n_outer_steps", n_outer_steps)
        self.rho_init = self._check_number("rho_init", rho_init, minimum=0.0, strict=True)
        self.rho_max = self._check_number("rho_max", rho_max, minimum=self.rho_init)
        self.rho_scale = self._check_number("rho_scale", rho_scale, minimum=1.0)
        self.persist_multipliers = bool(persist_multipliers)
        self._lambdas: torch.Tensor | None = None  # (n_envs, C), carried across solves
        self._lambda_rows: torch.Tensor | None = None
        self._rho = self.rho_init

    @property
    def lambdas(self) -> torch.Tensor | None:
        """The multipliers ``(n_envs, C)`` after the last solve (None before, or without constraints)."""
        return None if self._lambdas is None else self._lambdas.detach().cpu()

    def _constraints(self, info_s: dict, candidates: torch.Tensor) -> torch.Tensor | None:
        get = getattr(self.model, "get_constraints", None)
        if get is None:
            return None
        g = get(info_s, candidates)
        b, s = candidates.shape[:2]
        if not torch.is_tensor(g) or g.ndim != 3 or tuple(g.shape[:2]) != (b, s):
            raise ConfigError(
                f"LagrangianSolver requires get_constraints to return (B, S, C) = ({b}, {s}, C) violations "
                f"(satisfied where <= 0), got {tuple(g.shape) if torch.is_tensor(g) else type(g).__name__}"
            )
        return g

    def _loss(self, info_s: dict, x: torch.Tensor, costs: torch.Tensor) -> torch.Tensor:
        g = self._constraints(info_s, self._candidates(x))
        if g is None:
            return costs.sum()
        if self._lambda_rows is None or self._lambda_rows.shape[-1] != g.shape[-1]:
            self._lambda_rows = g.new_zeros(g.shape[0], g.shape[-1])
        linear = (self._lambda_rows.unsqueeze(1) * g).sum(dim=-1)
        quadratic = self._rho * torch.relu(g).square().sum(dim=-1)
        return (costs + linear + quadratic).sum()

    def _optimize(self, info: dict, init_action: torch.Tensor | None) -> dict:
        start, stop = self._rows
        if not self.persist_multipliers:
            self._lambdas = None
        self._lambda_rows = None if self._lambdas is None else self._lambdas[start:stop].clone()
        self._rho = self.rho_init
        info_s = self._expand(info, self.num_samples)
        with torch.no_grad():
            x = self._init_variable(init_action)
        for _ in range(self.n_outer_steps):
            x = self._descend(info_s, x)  # n_steps optimizer steps on L (a fresh optimizer)
            with torch.no_grad():
                g = self._constraints(info_s, self._candidates(x))
                if g is None:
                    continue
                if self._lambda_rows is None:
                    self._lambda_rows = g.new_zeros(g.shape[0], g.shape[-1])
                self._lambda_rows = torch.clamp(self._lambda_rows + self._rho * g.mean(dim=1), min=0.0)
                self._rho = min(self.rho_max, self._rho * self.rho_scale)
        with torch.no_grad():
            plans = self._decode(x)
            candidates = self._encode(plans)
            costs = self._cost(info_s, candidates)
            g = self._constraints(info_s, candidates)
            violation = None if g is None else torch.relu(g).sum(dim=-1)
            rank = costs if violation is None else costs + 1e6 * violation  # feasible plans first
            idx = rank.argmin(dim=1)
            rows = torch.arange(plans.shape[0], device=plans.device)
            out = {"actions": plans[rows, idx], "costs": costs[rows, idx]}
            if g is not None:
                out["constraint_violation"] = torch.relu(g[rows, idx]).mean(dim=-1)
                out["lambdas"] = self._lambda_rows.clone()
                if self._lambdas is None or self._lambdas.shape[-1] != g.shape[-1]:
                    self._lambdas = g.new_zeros(self.n_envs, g.shape[-1])
                self._lambdas[start:stop] = self._lambda_rows
        return out

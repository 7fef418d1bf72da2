"""Gradient descent on action sequences through a differentiable cost."""

from __future__ import annotations

import copy
from collections.abc import Mapping
from typing import Any

import torch

from ..errors import ConfigError
from ._registry import register_solver
from .base import BaseSolver, PlanKnobs


@register_solver("gd")
class GradientSolver(BaseSolver):
    """Optimize ``num_samples`` plans per env with a torch optimizer, batched over envs.

    Plans start at ``init_action`` (sample 0 exactly, the others perturbed by
    ``var_scale`` noise) or, without warm start, at ``var_scale * N(0, 1)``. Each of
    ``n_steps`` steps back-propagates ``get_cost`` (gradients w.r.t. the actions only: the
    model's ``.grad`` are untouched), steps the optimizer, adds ``action_noise`` noise and
    clamps into the Box bounds. The cheapest sample after the last step is returned.
    ``optimizer_kwargs`` default to ``{"lr": 0.1}``; ``batch_size=None`` plans all envs in
    one pass. Returns ``actions: (B, H, A)`` and ``costs: (B,)``. :meth:`init_action` draws
    the starting plans of the next solve into :attr:`init` (``var_scale=0``: no noise).
    ``grad_clip``: clip the gradient's norm before each step (upstream 0.1.1); ``callbacks`` as in
    :mod:`.callbacks` (state: ``params``, ``cost``, ``costs``).
    """

    #: starting plans ``(B, S, H, A)`` drawn by the last :meth:`init_action` call (None before)
    init: torch.Tensor | None = None
    knobs = PlanKnobs(samples=None, fixed=(("num_samples", 1),), summary="gradient descent through the model")

    def __init__(
        self,
        model: Any,
        n_steps: int,
        batch_size: int | None = None,
        var_scale: float = 1,
        num_samples: int = 1,
        action_noise: float = 0.0,
        device: str | torch.device | None = "cpu",
        seed: int = 1234,
        optimizer_cls: type[torch.optim.Optimizer] = torch.optim.SGD,
        optimizer_kwargs: dict | None = None,
        grad_clip: float | None = None,
        callbacks: list | None = None,
    ) -> None:
        super().__init__(model, batch_size, num_samples, var_scale, device, seed, n_steps, callbacks=callbacks)
        self.grad_clip = (
            None if grad_clip is None else self._check_number("grad_clip", grad_clip, minimum=0.0, strict=True)
        )
        self.action_noise = self._check_number("action_noise", action_noise, minimum=0.0)
        if not callable(optimizer_cls):
            raise ConfigError(
                f"{type(self).__name__} requires optimizer_cls to be a torch optimizer class (e.g. torch.optim.Adam), "
                f"got {optimizer_cls!r}"
            )
        if optimizer_kwargs is not None and not isinstance(optimizer_kwargs, Mapping):
            raise ConfigError(
                f"{type(self).__name__} requires optimizer_kwargs to be a dict (e.g. {{'lr': 0.1}}) or None, "
                f"got {optimizer_kwargs!r}"
            )
        self.optimizer_kwargs = {"lr": 0.1} if optimizer_kwargs is None else dict(optimizer_kwargs)
        if "lr" in self.optimizer_kwargs:  # the learning rate: 0 freezes the plans, negative or NaN ascends/breaks
            self._check_number("optimizer_kwargs['lr'] (the learning rate)", self.optimizer_kwargs["lr"], minimum=0.0)
        self.optimizer_cls = optimizer_cls

    def init_action(self, actions: Any = None) -> None:
        """Draw the starting plans of the next :meth:`solve` into :attr:`init`: ``(B, S, H, A)``.

        Sample 0 is ``actions: (B, k <= H, A)`` padded with zeros (zeros without it), clamped
        into the Box bounds; the other samples add ``var_scale`` noise. The draw is the one the
        next solve makes, and the random stream is not advanced (seed 000's ``init_action``).
        """
        self._require_configured()
        self.init = self._draw_start(self._pad_init(actions))

    def _draw_start(self, init: torch.Tensor | None) -> torch.Tensor:
        """:meth:`_init_variable` for all envs with the next solve's seed, leaving the stream as it is."""
        self._solve_seed = int(copy.deepcopy(self._seed_rng).integers(0, 2**62))
        self._rows, self._draw = (0, self.n_envs), 0
        with torch.no_grad():
            return self._init_variable(init)

    # -- hooks for relaxations (see discrete_solvers.PGDSolver) ------------------------------
    def _init_variable(self, init_action: torch.Tensor | None) -> torch.Tensor:
        """The optimized tensor ``(b, S, H, A)``."""
        mean = self._initial_mean(init_action).unsqueeze(1)
        noise = self.var_scale * self._randn(self.num_samples, self.horizon, self.action_dim)
        if init_action is not None:
            noise[:, 0] = 0
        return self._project(mean + noise)

    def _project(self, x: torch.Tensor) -> torch.Tensor:
        """Back into the feasible set after each step (here: the Box bounds)."""
        return self._clamp(x)

    def _candidates(self, x: torch.Tensor) -> torch.Tensor:
        """What ``get_cost`` sees for the variable ``x`` (here: ``x`` itself)."""
        return x

    def _decode(self, x: torch.Tensor) -> torch.Tensor:
        """Final plans ``(b, S, H, A)`` from the variable (here: ``x`` itself)."""
        return x

    def _encode(self, plans: torch.Tensor) -> torch.Tensor:
        """Candidates for final plans, to score them (here: the plans themselves)."""
        return plans

    def _loss(self, info_s: dict, x: torch.Tensor, costs: torch.Tensor) -> torch.Tensor:
        """What a step descends (here: the summed costs; the Lagrangian adds constraint terms)."""
        return costs.sum()

    # -- the algorithm ---------------------------------------------------------------------
    def _optimize(self, info: dict, init_action: torch.Tensor | None) -> dict:
        info_s = self._expand(info, self.num_samples)
        with torch.no_grad():
            x = self._init_variable(init_action)
        x = self._descend(info_s, x)
        with torch.no_grad():
            plans = self._decode(x)
            costs = self._cost(info_s, self._encode(plans))
            cost, idx = costs.min(dim=1)
            best = plans[torch.arange(plans.shape[0], device=plans.device), idx]
        return {"actions": best, "costs": cost}

    def _descend(self, info_s: dict, x: torch.Tensor) -> torch.Tensor:
        """``n_steps`` steps of a fresh optimizer on :meth:`_loss` from ``x``; the variable after them."""
        x = x.detach().requires_grad_(True)
        optimizer = self.optimizer_cls([x], **self.optimizer_kwargs)
        with torch.enable_grad():
            for step in range(self.n_steps):
                costs = self._cost(info_s, self._candidates(x))
                if not costs.requires_grad:
                    raise ConfigError(
                        f"{type(self).__name__} requires get_cost to be differentiable in the candidates "
                        f"(Cost must requires_grad for {self.name.upper()} solver), got costs without a graph; "
                        "do not call it under torch.no_grad() or detach the candidates, or use a sampling solver (cem)"
                    )
                loss = self._loss(info_s, x, costs)
                (x.grad,) = torch.autograd.grad(loss, [x])
                stop = self.callbacks and self._notify(step=step, params=x, cost=loss.detach(), costs=costs.detach())
                if self.grad_clip is not None:
                    torch.nn.utils.clip_grad_norm_([x], self.grad_clip)
                optimizer.step()
                with torch.no_grad():
                    if self.action_noise > 0:
                        x.add_(self.action_noise * self._randn(*x.shape[1:]))
                    x.copy_(self._project(x))
                if stop:
                    break
        return x.detach()


GDSolver = GradientSolver

"""Solvers for discrete action spaces."""

from __future__ import annotations

import math
from typing import Any

import gymnasium as gym
import numpy as np
import torch

from ..errors import SpaceError
from ._registry import register_solver
from .gd import GradientSolver


def project_simplex(v: torch.Tensor) -> torch.Tensor:
    """Euclidean projection of every vector ``(..., n)`` onto the probability simplex."""
    n = v.shape[-1]
    u = torch.sort(v, dim=-1, descending=True).values
    css = u.cumsum(dim=-1) - 1
    k = torch.arange(1, n + 1, device=v.device, dtype=v.dtype)
    rho = (u - css / k > 0).sum(dim=-1, keepdim=True)
    theta = css.gather(-1, rho - 1) / rho.to(v.dtype)
    return (v - theta).clamp_min(0)


@register_solver("pgd")
class PGDSolver(GradientSolver):
    """Projected gradient descent on the simplex relaxation of discrete actions.

    For a batched ``MultiDiscrete`` action space (B envs of ``Discrete(n)`` or of a
    ``MultiDiscrete`` with equal ``nvec``), each of the ``A = action_dim`` integer actions
    of a block is relaxed to a point of the ``n``-simplex. ``get_cost`` receives
    candidates ``(B, S, H, A * n)`` (soft one-hots, :attr:`action_simplex_dim` = ``A * n``);
    after every optimizer step they are projected back onto the simplex. The answer is
    the argmax of the cheapest sample (re-scored as hard one-hots):
    ``actions: (B, H, A)`` of dtype int64, and ``costs: (B,)``.
    Without warm start, plans start at the uniform point plus ``var_scale`` noise.
    """

    def _check_space(self, action_space: gym.Space) -> None:
        nvec = np.asarray(getattr(action_space, "nvec", []))
        if not isinstance(action_space, gym.spaces.MultiDiscrete) or nvec.size == 0 or (nvec != nvec.flat[0]).any():
            raise SpaceError(
                f"PGDSolver requires a batched discrete action space (MultiDiscrete with equal nvec), got {action_space!r}"
            )
        if (np.asarray(action_space.start) != 0).any():
            raise SpaceError(f"PGDSolver requires actions starting at 0, got start={action_space.start}")

    @property
    def n_choices(self) -> int | None:
        """Choices per discrete action (n); None before :meth:`configure`."""
        return None if self._space is None else int(np.asarray(self._space.nvec).flat[0])

    @property
    def action_simplex_dim(self) -> int | None:
        """Width of the relaxed candidates given to ``get_cost``: ``action_dim * n``."""
        return None if self._space is None else self.action_dim * self.n_choices

    def _init_variable(self, init_action: torch.Tensor | None) -> torch.Tensor:
        b = self._rows[1] - self._rows[0]
        shape = (b, self.num_samples, self.horizon, self.action_dim, self.n_choices)
        start = torch.full(shape, 1.0 / self.n_choices, device=self.device, dtype=self.dtype)
        noise = self.var_scale / math.sqrt(self.n_choices) * self._randn(*shape[1:])
        if init_action is not None:
            start = self._one_hot(init_action.unsqueeze(1)).expand(shape).clone()
            noise[:, 0] = 0
        return self._project(start + noise)

    def _project(self, x: torch.Tensor) -> torch.Tensor:
        return project_simplex(x)

    def _candidates(self, x: torch.Tensor) -> torch.Tensor:
        return x.flatten(-2)

    def _decode(self, x: torch.Tensor) -> torch.Tensor:
        return x.argmax(dim=-1)

    def _encode(self, plans: torch.Tensor) -> torch.Tensor:
        return self._one_hot(plans).flatten(-2)

    def _one_hot(self, actions: torch.Tensor) -> torch.Tensor:
        """Integer actions ``(...)`` -> one-hots ``(..., n)``; entries < 0 give the uniform point."""
        index = actions.round().long()
        hot = torch.nn.functional.one_hot(index.clamp(0, self.n_choices - 1), self.n_choices).to(self.dtype)
        return torch.where((index >= 0).unsqueeze(-1), hot, torch.full_like(hot, 1.0 / self.n_choices))

    def _pad_init(self, init_action: Any) -> torch.Tensor | None:
        """Integer warm start ``(B, k, A)``; the padded blocks are marked -1 (start uniform)."""
        init = super()._pad_init(init_action)
        if init is None:
            return None
        init = init.round()
        init[:, torch.as_tensor(init_action).shape[1] :] = -1
        return init

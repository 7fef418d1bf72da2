"""The solver contract: :class:`Solver` (what a planner offers) and :class:`Costable` (what a model offers).

A solver plans ``H`` action blocks for ``B`` envs at once. A cost model provides
``get_cost(info_dict, candidates) -> (B, S)`` for ``candidates: (B, S, H, A)``, where every
tensor of ``info_dict`` is expanded to ``(B, S, ...)`` (views, not copies). Subclass
:class:`~stable_worldmodel.solver.base.BaseSolver` to get all the plumbing.
"""

from __future__ import annotations

from typing import Any, Protocol, runtime_checkable

import gymnasium as gym
import torch

from .base import AUTO_BATCH, BaseSolver

__all__ = ["AUTO_BATCH", "BaseSolver", "Costable", "Solver"]


@runtime_checkable
class Costable(Protocol):
    """A model that scores action candidates."""

    def get_cost(self, info_dict: dict, action_candidates: torch.Tensor) -> torch.Tensor:
        """``info_dict`` entries ``(B, S, ...)``, candidates ``(B, S, H, A)`` -> costs ``(B, S)``."""


@runtime_checkable
class Solver(Protocol):
    """What :class:`~stable_worldmodel.policy.WorldModelPolicy` needs from a planner."""

    def configure(self, *, action_space: gym.Space, n_envs: int, config: Any) -> None:
        """Set the batched action space ``(B, ...)``, ``B = n_envs`` and the ``PlanConfig``."""

    @property
    def action_dim(self) -> int:
        """``prod(single action shape) * config.action_block``."""

    @property
    def n_envs(self) -> int:
        """Number of envs planned for (B)."""

    @property
    def horizon(self) -> int:
        """Number of planned action blocks (H)."""

    def solve(self, info_dict: dict, init_action: torch.Tensor | None = None) -> dict:
        """Plan; returns at least ``actions: (B, H, A)`` on the CPU."""

    def __call__(self, info_dict: dict, init_action: torch.Tensor | None = None) -> dict:
        """Same as :meth:`solve`."""

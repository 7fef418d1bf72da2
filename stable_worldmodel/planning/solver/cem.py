"""``CEMSolver(cost, ...)``: upstream 0.1.1's planning-side CEM, a thin adapter over our CEM.

Upstream splits "what is scored" from "the world model": its planning CEM takes a ``cost``
object (a world model, or an evaluator that rolls one out and compares with the goal). Here
``cost`` may also be a plain function; the algorithm, seeding, batching and results are
those of :class:`stable_worldmodel.solver.CEMSolver`.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import torch

from ...errors import ConfigError
from ...solver.base import AUTO_BATCH
from ...solver.cem import CEMSolver as _ModelCEM

__all__ = ["CEMSolver"]


class _CallableCost(torch.nn.Module):
    """Gives a function ``cost(info, candidates) -> (B, S)`` the ``get_cost`` the solvers call.

    A module: when the function is itself an ``nn.Module`` its parameters are seen, so the
    solver follows its device and dtype.
    """

    def __init__(self, fn: Callable[[dict, torch.Tensor], torch.Tensor]):
        super().__init__()
        self.fn = fn

    def get_cost(self, info_dict: dict, action_candidates: torch.Tensor) -> torch.Tensor:
        return self.fn(info_dict, action_candidates)


class CEMSolver(_ModelCEM):
    """Cross-Entropy Method planning against ``cost`` (upstream 0.1.1's ``planning.CEMSolver``).

    - ``cost``: an object with ``get_cost(info_dict, candidates) -> (B, S)`` (a world model,
      a shooting cost evaluator ...), or a function with that signature. Kept as :attr:`cost`.
    - ``batch_size`` ... ``seed``: as :class:`stable_worldmodel.solver.CEMSolver` (the default
      batch size, shown as 1, plans all envs in one pass with the same plans as 1).
    - ``callbacks``: upstream's per-iteration hooks are not supported; only ``None`` or ``[]``
      are accepted. :meth:`solve` returns the final ``mean`` and ``var`` and the elite ``costs``.

    Results: ``actions: (B, H, A)``, ``costs: (B,)``, ``mean``, ``var``, as tensors (upstream
    returns ``costs`` as a list of floats and ``mean``/``var`` as one-element lists).

    Example::

        >>> import gymnasium as gym, torch
        >>> from stable_worldmodel.policy import PlanConfig
        >>> def bowl(info, candidates):  # (B, S, H, A) -> (B, S)
        ...     return ((candidates - 0.5) ** 2).sum(dim=(2, 3))
        >>> solver = CEMSolver(bowl, num_samples=64, n_steps=10, topk=8)
        >>> solver.configure(action_space=gym.spaces.Box(-1, 1, (2, 3)), n_envs=2, config=PlanConfig(4, 1))
        >>> solver.solve({})["actions"].shape
        torch.Size([2, 4, 3])
    """

    def __init__(
        self,
        cost: Any,
        batch_size: int | None = AUTO_BATCH,
        num_samples: int = 300,
        var_scale: float = 1,
        n_steps: int = 30,
        topk: int = 30,
        device: str | torch.device | None = "cpu",
        seed: int = 1234,
        callbacks: list | None = None,
    ) -> None:
        if callable(getattr(cost, "get_cost", None)):
            model = cost
        elif callable(cost):
            model = _CallableCost(cost)
        else:
            raise ConfigError(
                "CEMSolver requires cost: an object with get_cost(info_dict, candidates) or a function "
                f"(info_dict, candidates) -> costs (B, S), got {cost!r}"
            )
        if callbacks:
            raise ConfigError(
                f"CEMSolver does not support callbacks, got {callbacks!r}; read the final mean, var and costs "
                "from the dict that solve() returns"
            )
        super().__init__(model, batch_size, num_samples, var_scale, n_steps, topk, device, seed)
        self.cost = cost
        self.callbacks: list = []

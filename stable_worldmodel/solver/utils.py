"""Helpers shared by planning solvers (upstream 0.1.1's ``stable_worldmodel.solver.utils``)."""

from __future__ import annotations

from typing import Any

import torch

from ..errors import ConfigError

__all__ = ["prepare_init_action"]


def prepare_init_action(
    model: Any, info_dict: dict, init_action: torch.Tensor | None, horizon: int, n_envs: int, action_dim: int
) -> torch.Tensor:
    """A warm start ``(n_envs, horizon, action_dim)`` from ``init_action`` ``(n_envs, t <= horizon,
    action_dim)`` (or None): returned as it is when it covers the horizon; otherwise the missing
    ``horizon - t`` blocks come from the model's actor when it has one
    (``model.get_action(info_dict, horizon=remaining, prefix_actions=init_action)``: the actor
    rolled out from the latent the given actions reach), else zeros.
    """
    from ..protocols import Actionable

    if init_action is not None:
        shape = tuple(init_action.shape)
        if len(shape) != 3 or shape[0] != n_envs or shape[2] != action_dim or shape[1] > horizon:
            raise ConfigError(
                f"prepare_init_action requires init_action of shape ({n_envs}, t <= {horizon}, {action_dim}), "
                f"got {shape}"
            )
    remaining = horizon - (init_action.shape[1] if init_action is not None else 0)
    if remaining <= 0:
        return init_action
    if isinstance(model, Actionable):
        with torch.no_grad():
            tail = model.get_action(info_dict, horizon=remaining, prefix_actions=init_action)
    else:
        device = init_action.device if init_action is not None else "cpu"
        dtype = init_action.dtype if init_action is not None else torch.float32
        tail = torch.zeros(n_envs, remaining, action_dim, device=device, dtype=dtype)
    return tail if init_action is None else torch.cat([init_action.to(tail.device), tail], dim=1)

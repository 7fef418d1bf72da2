"""Planning objectives that score a rolled-out ``info_dict`` (upstream main's
``stable_worldmodel.planning.objective``): combine them freely, no world-model subclass needed.
Each returns a cost per candidate, ``(B, S)`` (see :class:`~stable_worldmodel.protocols.Objective`)."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import torch

from ..errors import ConfigError

__all__ = ["ControlPenalty", "GoalMSE", "WeightedSum"]


class GoalMSE:
    """Squared distance between the last predicted embedding and the last goal embedding, summed
    over the embedding (what LeWM's planning cost is with ``goal_cost="final"``).

    Reads ``info[pred_key]: (B, S, T, D)`` and ``info[goal_key]``: ``(B, T', D)``, or ``(B, S, T', D)``.
    """

    def __init__(self, pred_key: str = "predicted_emb", goal_key: str = "goal_emb") -> None:
        self.pred_key, self.goal_key = pred_key, goal_key

    def __call__(self, info_dict: dict) -> torch.Tensor:
        pred = info_dict[self.pred_key][..., -1, :]  # (B, S, D)
        goal = info_dict[self.goal_key]
        goal = goal[:, :, -1] if goal.ndim == pred.ndim + 1 else goal[:, -1].unsqueeze(1)  # (B, S or 1, D)
        return (pred - goal.detach()).square().flatten(2).sum(-1)


class ControlPenalty:
    """The squared size of the candidates themselves, ``sum a**2`` over the plan (an action
    cost the world model knows nothing about). Reads ``info[action_key]: (B, S, H, A)``."""

    def __init__(self, action_key: str = "action_candidates") -> None:
        self.action_key = action_key

    def __call__(self, info_dict: dict) -> torch.Tensor:
        actions = info_dict[self.action_key]
        return actions.square().flatten(2).sum(-1)


class WeightedSum:
    """``sum_i w_i * term_i(info)`` of ``terms = [(w_1, term_1), ...]``."""

    def __init__(self, terms: Sequence[tuple[float, Any]]) -> None:
        terms = list(terms)
        if not terms:
            raise ConfigError("WeightedSum requires at least one (weight, objective) term, got none")
        bad = [t for t in terms if not (isinstance(t, tuple) and len(t) == 2 and callable(t[1]))]
        if bad:
            raise ConfigError(f"WeightedSum requires (weight, objective) pairs, got {bad[0]!r}")
        self.terms = terms

    def __call__(self, info_dict: dict) -> torch.Tensor:
        total = None
        for weight, term in self.terms:
            value = weight * term(info_dict)
            total = value if total is None else total + value
        return total

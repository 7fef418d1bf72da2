"""The VoidRun expert: follow a shortest path over intact cells, recomputed every step."""

from __future__ import annotations

from typing import Any

import numpy as np

from ... import keys
from ...policy import ExpertPolicy
from .env import MOVES, shortest_path_lengths


def expert_action(state: np.ndarray) -> int:
    """The action for one VoidRun ``state`` vector ``(4 + N * N,)`` (layout in ``env.py``).

    Moves to the intact neighbour closest to the goal (BFS over the current floor mask); when
    the goal is cut off, steps onto any intact neighbour; when there is none, moves LEFT.
    """
    n = int(round(np.sqrt(state.shape[-1] - 4)))
    agent = np.rint(state[:2]).astype(np.int64)
    goal = np.rint(state[2:4]).astype(np.int64)
    mask = state[4:].reshape(n, n) > 0.5
    dist = shortest_path_lengths(mask, (goal[0], goal[1]))
    best, best_dist = 0, None
    for action, (dx, dy) in enumerate(MOVES):
        x, y = agent[0] + dx, agent[1] + dy
        if not (0 <= x < n and 0 <= y < n and mask[y, x]):
            continue
        d = dist[y, x] if dist[y, x] >= 0 else n * n  # reachable cells first
        if best_dist is None or d < best_dist:
            best, best_dist = action, d
    return best


class VoidRunExpert(ExpertPolicy):
    """Batched BFS expert for ``swm/VoidRun-v0``.

    ``get_action(infos)`` reads ``infos["state"]`` of shape ``(B, T, 4 + N * N)`` (the last of the
    ``T`` history steps is used) and returns ``(B,)`` int64 actions.
    """

    def __init__(self, env_id: str = "swm/VoidRun-v0", **kwargs: Any):
        super().__init__(env_id=env_id, **kwargs)

    def get_action(self, infos: dict[str, np.ndarray], **kwargs: Any) -> np.ndarray:
        states = np.asarray(infos[keys.STATE])[:, -1]
        return np.array([expert_action(s) for s in states], np.int64)

"""Scripted expert of ``swm/SimpleNavigation-v0``: along the maze's shortest path to the goal square.

Each step it reads the env's infos (``maze``, ``pos_agent``, ``dir_agent``, ``pos_goal``; the
last of the ``T`` history steps), measures every open cell's distance to the goal square (BFS
over the 4-neighbourhood) and heads for the neighbour closest to the goal: ``forward`` when the
agent faces it, else the turn towards it (``left`` when it is behind, so a reversal is two lefts
and a forward, as 0.0.3's expert). On the goal square, or with no way there, it turns left (which
keeps its cell). Mazes drawn by the env are trees, so this is 0.0.3's path and action sequence;
it needs no env handle and works with any number of envs, in-process or not. Returns ``(B,)``
int64.
"""

from __future__ import annotations

from collections import deque
from typing import Any

import numpy as np

from ...errors import ConfigError
from ...policy import ExpertPolicy

LEFT, RIGHT, FORWARD = 0, 1, 2
STEPS = ((1, 0), (0, 1), (-1, 0), (0, -1))  # (dx, dy) of MiniGrid's directions 0..3
_INFOS = ("maze", "pos_agent", "dir_agent", "pos_goal")


def distances_to(walls: np.ndarray, goal: tuple[int, int]) -> np.ndarray:
    """Steps from each open cell of ``walls`` (``[y, x]``, True = wall) to ``goal`` = (x, y); -1: unreachable."""
    h, w = walls.shape
    dist = np.full((h, w), -1, np.int64)
    gx, gy = goal
    if not (0 <= gx < w and 0 <= gy < h) or walls[gy, gx]:
        return dist
    dist[gy, gx] = 0
    todo = deque([(gx, gy)])
    while todo:
        x, y = todo.popleft()
        for dx, dy in STEPS:
            nx, ny = x + dx, y + dy
            if 0 <= nx < w and 0 <= ny < h and not walls[ny, nx] and dist[ny, nx] < 0:
                dist[ny, nx] = dist[y, x] + 1
                todo.append((nx, ny))
    return dist


def expert_action(walls: np.ndarray, agent: tuple[int, int], direction: int, goal: tuple[int, int]) -> int:
    """The expert's action for one env (see the module docstring)."""
    dist = distances_to(np.asarray(walls, bool), goal)
    x, y = agent
    here = dist[y, x] if 0 <= y < dist.shape[0] and 0 <= x < dist.shape[1] else -1
    if here <= 0:
        return LEFT
    for d, (dx, dy) in enumerate(STEPS):
        if dist[y + dy, x + dx] == here - 1:
            turn = (d - direction) % 4
            return {0: FORWARD, 1: RIGHT}.get(turn, LEFT)
    return LEFT


class SimpleNavigationExpert(ExpertPolicy):
    """Batched shortest-path expert for ``swm/SimpleNavigation-v0`` (module docstring)."""

    def __init__(self, env_id: str = "swm/SimpleNavigation-v0", **kwargs: Any):
        super().__init__(env_id=env_id, **kwargs)

    def get_action(self, infos: dict[str, Any], **kwargs: Any) -> np.ndarray:
        missing = [k for k in _INFOS if k not in infos]
        if missing:
            raise ConfigError(
                f"{type(self).__name__} requires the env's infos {list(_INFOS)} (batched as (B, T, ...)), "
                f"missing {missing}"
            )
        maze, agent, direction, goal = (np.asarray(infos[k]) for k in _INFOS)
        out = [
            expert_action(
                maze[b, -1] > 0,
                (int(agent[b, -1, 0]), int(agent[b, -1, 1])),
                int(np.asarray(direction[b, -1]).reshape(-1)[0]),
                (int(goal[b, -1, 0]), int(goal[b, -1, 1])),
            )
            for b in range(maze.shape[0])
        ]
        return np.array(out, np.int64)

"""Scripted expert of ``swm/SimplePointMaze-v0``: a wavefront over a grid of free cells, then greedy steps."""

from __future__ import annotations

from typing import Any

import numpy as np

from ... import keys
from ...policy import ExpertPolicy
from .v0 import LAYOUT, MAX_ACTION, WIDTH

CELL = 0.05  # grid step (world units)
_MARGIN = 0.01  # a cell is free when the agent disk grown by this much touches no wall
_CACHE_SIZE = 64


def _clear(x: np.ndarray, y: np.ndarray, layout: np.ndarray, margin: float) -> np.ndarray:
    """Whether the agent disk grown by ``margin`` at ``(x, y)`` (broadcast) touches no wall of ``layout``.

    ``layout``: the env's private ``_layout`` row (speed, agent radius, goal radius, n, walls).
    """
    n = int(layout[3])
    walls = layout[4 : 4 + 4 * n].reshape(n, 4).astype(np.float64)
    x, y = np.asarray(x, np.float64)[..., None], np.asarray(y, np.float64)[..., None]
    left, low = walls[:, 0], walls[:, 1]
    right, high = left + walls[:, 2], low + walls[:, 3]
    dx, dy = np.clip(x, left, right) - x, np.clip(y, low, high) - y
    r = float(layout[1]) + margin
    return ~np.any(dx**2 + dy**2 <= r * r, axis=-1)


def free_cells(layout: np.ndarray) -> np.ndarray:
    """(N, N) bool, rows along y: cell centres where the agent disk plus :data:`_MARGIN` touches no wall."""
    centres = (np.arange(int(round(WIDTH / CELL))) + 0.5) * CELL
    return _clear(centres[None, :], centres[:, None], layout, _MARGIN)


def wavefront(free: np.ndarray, start: tuple[int, int]) -> np.ndarray:
    """Steps (8-connected, over ``free`` cells) from ``start`` = (row, col) to every cell; inf where unreachable."""
    dist = np.full(free.shape, np.inf)
    if not free.any():
        return dist
    if not free[start]:  # start from the free cell nearest to it
        rows, cols = np.nonzero(free)
        k = int(np.argmin((rows - start[0]) ** 2 + (cols - start[1]) ** 2))
        start = (int(rows[k]), int(cols[k]))
    front = np.zeros_like(free)
    front[start] = True
    reached = front.copy()
    step = 0
    while front.any():
        dist[front] = step
        grown = front.copy()
        grown[1:] |= front[:-1]
        grown[:-1] |= front[1:]
        grown[:, 1:] |= grown[:, :-1].copy()
        grown[:, :-1] |= grown[:, 1:].copy()
        front = grown & free & ~reached
        reached |= front
        step += 1
    return dist


def _cell(point: np.ndarray) -> tuple[int, int]:
    n = int(round(WIDTH / CELL))
    col = int(np.clip(point[0] // CELL, 0, n - 1))
    row = int(np.clip(point[1] // CELL, 0, n - 1))
    return row, col


class SimplePointMazeV0Expert(ExpertPolicy):
    """Batched planner for release 0.1.1's SimplePointMaze.

    Reads ``infos[state][:, -1]`` (B, 2) agent position, ``infos[goal_state][:, -1]`` (B, 2)
    goal position and the env's private ``infos["_layout"][:, -1]``. On a grid of
    :data:`CELL`-sized cells it marks the cells where the agent disk is clear of every wall, runs
    a wavefront from the goal's cell (cached per layout and goal), and each step moves to the
    goal itself when it is within one step, else to the free cell within one step (an action
    moves at most ``0.2 * speed`` per axis) that is fewest grid steps from the goal (or one
    inside the goal disk when there is one). The env
    only checks where a move ends, so such moves never stall. When the goal cannot be reached
    on the grid it heads straight for the goal. ``noise`` adds seeded Gaussian noise of that
    std. Returns (B, 2) float32 in ``[-0.2, 0.2]``.
    """

    def __init__(
        self, env_id: str = "swm/SimplePointMaze-v0", noise: float = 0.0, seed: int | None = None, **kwargs: Any
    ):
        super().__init__(env_id=env_id, noise=noise, seed=seed, **kwargs)
        self.rng = np.random.default_rng(seed)
        self._fields: dict[bytes, np.ndarray] = {}

    def get_action(self, infos: dict[str, np.ndarray], **kwargs: Any) -> np.ndarray:
        pos = np.asarray(infos[keys.STATE], np.float64)[:, -1, :2]
        goal = np.asarray(infos[keys.GOAL_STATE], np.float64)[:, -1, :2]
        layout = np.asarray(infos[LAYOUT], np.float32)[:, -1]
        target = np.array([self._target(p, g, lay) for p, g, lay in zip(pos, goal, layout, strict=True)])
        speed = layout[:, :1].astype(np.float64)
        action = np.clip((target - pos) / speed, -MAX_ACTION, MAX_ACTION)
        if self.noise:
            action = np.clip(action + self.noise * self.rng.standard_normal(action.shape), -MAX_ACTION, MAX_ACTION)
        return action.astype(np.float32)

    def _field(self, goal: np.ndarray, layout: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        key = layout.tobytes() + goal.astype(np.float32).tobytes()
        if key not in self._fields:
            if len(self._fields) >= _CACHE_SIZE:
                self._fields.clear()
            free = free_cells(layout)
            self._fields[key] = (free, wavefront(free, _cell(goal)))
        return self._fields[key]

    def _target(self, pos: np.ndarray, goal: np.ndarray, layout: np.ndarray) -> np.ndarray:
        reach = MAX_ACTION * float(layout[0]) * (1 - 1e-3)
        if np.max(np.abs(goal - pos)) <= reach and _clear(goal[0], goal[1], layout, _MARGIN):
            return goal
        free, dist = self._field(goal, layout)
        window = max(reach, 1.5 * CELL)  # below one cell per step, aim at a neighbour (the action is clipped)
        n = free.shape[0]
        lo = np.clip(((pos - window) / CELL).astype(int), 0, n - 1)
        hi = np.clip(((pos + window) / CELL).astype(int) + 1, 0, n)
        cols, rows = np.arange(lo[0], hi[0]), np.arange(lo[1], hi[1])
        cx, cy = (cols + 0.5) * CELL, (rows + 0.5) * CELL
        inside = (np.abs(cx[None, :] - pos[0]) <= window) & (np.abs(cy[:, None] - pos[1]) <= window)
        d = np.where(inside, dist[lo[1] : hi[1], lo[0] : hi[0]], np.inf)
        if not np.isfinite(d).any():
            return goal
        gap = (cx[None, :] - goal[0]) ** 2 + (cy[:, None] - goal[1]) ** 2
        inside_goal = np.isfinite(d) & (gap < (0.9 * float(layout[2])) ** 2)
        best = inside_goal if inside_goal.any() else d == d.min()  # a free cell on the goal disk ends it
        gap = np.where(best, gap, np.inf)
        r, c = np.unravel_index(int(np.argmin(gap)), gap.shape)
        return np.array([cx[c], cy[r]])

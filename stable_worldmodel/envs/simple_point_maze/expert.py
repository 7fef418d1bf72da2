"""Scripted expert of ``swm/SimplePointMaze-v1``: BFS over the maze cells and a velocity controller."""

from __future__ import annotations

from typing import Any

import numpy as np

from ... import keys
from ...policy import ExpertPolicy
from ..planar import grow_boxes, segment_clear
from .env import ACCEL, RADIUS_RANGE
from .layout import LAYOUTS

_R = RADIUS_RANGE[1]  # the expert does not see the radius: it checks sight lines for the largest one
_LOOKAHEAD = 3
_CRUISE = 0.4  # commanded speed (above every max_speed: the env's cap does the limiting)


class SimplePointMazeExpert(ExpertPolicy):
    """Batched maze solver reading everything it needs from the state.

    From ``infos[state][:, -1]`` (B, 5) = (x, y, vx, vy, layout index) and
    ``infos[goal_state][:, -1]`` (B, 5): a shortest path over the free cells of
    ``LAYOUTS[layout]`` from the agent's cell to the goal's cell (BFS, recomputed every step),
    aims at the farthest of the next :data:`_LOOKAHEAD` cell centres (the goal itself in the
    last cell) reachable in a straight line, and commands the velocity ``_CRUISE`` towards it
    with force ``(v_des - v) / ACCEL``. ``noise`` adds Gaussian noise of that std to the bounded action
    (seeded by ``seed``). Returns actions (B, 2) in ``[-1, 1]``.
    """

    def __init__(
        self, env_id: str = "swm/SimplePointMaze-v1", noise: float = 0.0, seed: int | None = None, **kwargs: Any
    ):
        super().__init__(env_id=env_id, noise=noise, seed=seed, **kwargs)
        self.rng = np.random.default_rng(seed)
        self._boxes = [grow_boxes(m.wall_boxes, _R) for m in LAYOUTS]

    def get_action(self, infos: dict[str, np.ndarray], **kwargs: Any) -> np.ndarray:
        state = np.asarray(infos[keys.STATE], np.float64)[:, -1]
        goal = np.asarray(infos[keys.GOAL_STATE], np.float64)[:, -1, :2]
        target = np.array([self._waypoint(s, g) for s, g in zip(state, goal, strict=True)]).reshape(-1, 2)
        offset = target - state[:, :2]
        norm = np.maximum(np.linalg.norm(offset, axis=1, keepdims=True), 1e-9)
        action = (_CRUISE * offset / norm - state[:, 2:4]) / ACCEL
        action = np.clip(action, -1.0, 1.0)
        if self.noise:  # perturbs the bounded action, so saturated commands still vary
            action = np.clip(action + self.noise * self.rng.standard_normal(action.shape), -1.0, 1.0)
        return action.astype(np.float32)

    def _waypoint(self, state: np.ndarray, goal: np.ndarray) -> np.ndarray:
        layout = int(np.clip(round(state[4]), 0, len(LAYOUTS) - 1))
        maze, boxes = LAYOUTS[layout], self._boxes[layout]
        pos = state[:2]
        cells = maze.path(maze.cell(pos), maze.cell(goal))
        points = [maze.centre(c) for c in cells[1 : 1 + _LOOKAHEAD]]
        if len(cells) <= 1 + _LOOKAHEAD:
            points = points[:-1] + [goal] if points else [goal]
        for point in reversed(points[1:]):
            if segment_clear(pos, point, boxes):
                return point
        return points[0]

"""Scripted expert of ``swm/TwoRoom-v0``: to the goal, through a door that fits when the goal is across the wall."""

from __future__ import annotations

from typing import Any

import numpy as np

from ... import keys
from ...policy import ExpertPolicy
from .v0 import LAYOUT, MAX_DOORS

_CLEARANCE = 3.0  # px kept between the agent and the wall faces / door edges


class TwoRoomV0Expert(ExpertPolicy):
    """Batched door-seeking controller for release 0.0.3's TwoRoom.

    Reads ``infos[state][:, -1]`` (B, 6): agent x, y, goal x, y, energy, speed, and the env's
    private ``infos["_layout"][:, -1]`` (B, 11): wall axis, wall position, half thickness,
    agent radius, number of door gaps, then the gaps ``(lo, hi)`` along the wall. When the goal
    is across the wall it lines up in front of the gap that fits the agent and gives the
    shortest path, then crosses; otherwise it goes to the goal. An action moves the agent by
    ``action * speed`` px, so the command ``(target - agent) / speed`` (clipped to [-1, 1])
    never overshoots. ``noise`` adds seeded Gaussian noise of that std. Returns (B, 2) float32.
    """

    def __init__(self, env_id: str = "swm/TwoRoom-v0", noise: float = 0.0, seed: int | None = None, **kwargs: Any):
        super().__init__(env_id=env_id, noise=noise, seed=seed, **kwargs)
        self.rng = np.random.default_rng(seed)

    def get_action(self, infos: dict[str, np.ndarray], **kwargs: Any) -> np.ndarray:
        state = np.asarray(infos[keys.STATE], np.float64)[:, -1]
        layout = np.asarray(infos[LAYOUT], np.float64)[:, -1]
        target = np.array([self._target(s, g) for s, g in zip(state, layout, strict=True)]).reshape(-1, 2)
        action = np.clip((target - state[:, :2]) / state[:, 5:6], -1.0, 1.0)
        if self.noise:
            action = np.clip(action + self.noise * self.rng.standard_normal(action.shape), -1.0, 1.0)
        return action.astype(np.float32)

    @staticmethod
    def _target(state: np.ndarray, layout: np.ndarray) -> np.ndarray:
        pos, goal = state[:2], state[2:4]
        axis, wall, half, radius, n = layout[0], layout[1], layout[2], layout[3], int(layout[4])
        i = 0 if axis == 1 else 1  # the coordinate across the wall
        j = 1 - i
        side, goal_side = np.sign(pos[i] - wall), np.sign(goal[i] - wall)
        gaps = layout[5 : 5 + 2 * min(n, MAX_DOORS)].reshape(-1, 2)
        gaps = gaps[gaps[:, 1] - gaps[:, 0] >= 2 * (radius + _CLEARANCE)]
        if side == goal_side or side == 0 or not len(gaps):
            return goal
        centres = gaps.mean(1)
        cost = np.abs(centres - pos[j]) + np.abs(centres - goal[j])
        k = int(np.argmin(cost))
        clear = half + radius + _CLEARANCE
        out = np.empty(2)
        out[j] = centres[k]
        if gaps[k, 0] + radius + _CLEARANCE <= pos[j] <= gaps[k, 1] - radius - _CLEARANCE:  # in line with the gap
            out[i] = wall + goal_side * clear
        else:
            out[i] = wall - side * clear
        return out

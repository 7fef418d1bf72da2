"""Scripted expert of ``swm/TwoRoom-v2`` (upstream 0.1.1's TwoRoom): through the nearest door that fits,
then to the target."""

from __future__ import annotations

from typing import Any

import numpy as np

from ... import keys
from ...policy import ExpertPolicy
from .v1 import LAYOUT, MAX_DOOR

DOOR_FIT = 1.1  # a door fits when its half-extent is at least this many agent radii
DOOR_REACHED = 10.5  # px from the door centre at which the agent heads for the target


class TwoRoomV1Expert(ExpertPolicy):
    """Batched door-seeking controller for upstream's TwoRoom, as upstream's expert behaves.

    Reads ``infos[state][:, -1]`` (B, 2) agent position, ``infos[goal_state][:, -1]`` (B, 2)
    target and the env's private ``infos["_layout"][:, -1]`` (B, 4 + 2 * 3): wall axis, wall
    position, agent radius, agent speed, door centres, door half-extents (0 for absent doors).
    When the target is in the other room it heads for the centre of the nearest door that fits
    (half-extent >= ``door_fit`` radii) until within :data:`DOOR_REACHED` px (``door_reached``) of
    it, then for the target. The action points at the waypoint with length
    ``min(1, distance / speed)`` (so it never overshoots). ``noise`` adds
    seeded Gaussian noise of that std; actions are clipped to [-1, 1]. Returns (B, 2) float32.
    """

    def __init__(self, env_id: str = "swm/TwoRoom-v2", noise: float = 0.0, seed: int | None = None, **kwargs: Any):
        super().__init__(env_id=env_id, noise=noise, seed=seed, **kwargs)
        self.rng = np.random.default_rng(seed)
        self.door_fit, self.door_reached = DOOR_FIT, DOOR_REACHED

    def get_action(self, infos: dict[str, np.ndarray], **kwargs: Any) -> np.ndarray:
        pos = np.asarray(infos[keys.STATE], np.float64)[:, -1, :2]
        goal = np.asarray(infos[keys.GOAL_STATE], np.float64)[:, -1, :2]
        layout = np.asarray(infos[LAYOUT], np.float64)[:, -1]
        waypoint = np.array(
            [
                self._waypoint(p, g, lay, self.door_fit, self.door_reached)
                for p, g, lay in zip(pos, goal, layout, strict=True)
            ]
        ).reshape(-1, 2)
        delta = waypoint - pos
        dist = np.linalg.norm(delta, axis=1, keepdims=True)
        scale = np.minimum(1.0, dist / np.maximum(layout[:, 3:4], 1e-6)) / np.maximum(dist, 1e-8)
        action = delta * scale
        if self.noise:
            action = action + self.noise * self.rng.standard_normal(action.shape)
        return np.clip(action, -1.0, 1.0).astype(np.float32)

    @staticmethod
    def _waypoint(
        pos: np.ndarray, goal: np.ndarray, layout: np.ndarray, door_fit: float, door_reached: float
    ) -> np.ndarray:
        axis, wall, radius = int(layout[0]), layout[1], layout[2]
        i = 0 if axis == 1 else 1  # the coordinate across the wall
        if (pos[i] > wall) == (goal[i] > wall):
            return goal
        centres, sizes = layout[4 : 4 + MAX_DOOR], layout[4 + MAX_DOOR : 4 + 2 * MAX_DOOR]
        fits = sizes >= door_fit * radius
        if not fits.any():  # no door fits: press against the wall in line with the target
            out = goal.copy()
            out[i] = wall
            return out
        doors = np.zeros((MAX_DOOR, 2))
        doors[:, i], doors[:, 1 - i] = wall, centres
        dist = np.where(fits, np.linalg.norm(doors - pos, axis=1), np.inf)
        k = int(np.argmin(dist))
        return doors[k] if dist[k] > door_reached else goal

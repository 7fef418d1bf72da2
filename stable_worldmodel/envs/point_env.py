"""Template of the 2-D envs where a disk agent reaches a goal point (TwoRoom, SimplePointMaze).

The base class owns the shared contract: reset options (factors, per-seed start and goal,
``state`` / ``goal_state`` restore), success rule, observation and info dicts, the cached
goal image and the drawing of the two disks over a cached static layer. A subclass sets
its spaces and :attr:`world_size`, and implements the hooks :meth:`_setup`,
:meth:`_draw_positions`, :meth:`_legal`, :meth:`_state`, :meth:`_draw_static` and ``step``
(which ends with :meth:`_transition`). The variation space must hold
``agent.{color,radius,position}`` and ``goal.{color,radius,position}``.
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np

from .. import keys
from . import utils as draw
from .base import DatasetResetMixin, apply_variation_options
from .planar import given_factors


class PointEnv(DatasetResetMixin, gym.Env):
    """A disk agent, a goal point, success within :attr:`success_distance` (reward = -distance)."""

    metadata = {"render_modes": ["rgb_array"], "render_fps": 10}
    success_distance: float = 1.0
    proprio_dim: int = 2

    def __init__(
        self,
        render_mode: str | None = "rgb_array",
        render_size: tuple[int, int] = (224, 224),
        render_target: bool = True,
    ):
        self.render_mode = render_mode
        #: draw the goal disk in the frames (the goal image is then the agent on the goal disk)
        self.render_target = bool(render_target)
        self.render_size = (int(render_size[0]), int(render_size[1]))
        self.world_size = 1.0
        self._pos = np.zeros(2)
        self._goal = np.zeros(2)
        self._static: np.ndarray | None = None
        self._goal_img: np.ndarray | None = None

    # -- protocol hooks -------------------------------------------------------------
    def set_render_size(self, size: tuple[int, int]) -> None:
        self.render_size = (int(size[0]), int(size[1]))
        self._static = self._goal_img = None

    def eval_state(self, goal_state: np.ndarray, cur_state: np.ndarray) -> tuple[bool, float]:
        """``(distance < success_distance, distance)`` between the positions (first two entries)."""
        dist = float(np.linalg.norm(np.asarray(goal_state, np.float64)[:2] - np.asarray(cur_state, np.float64)[:2]))
        return dist < self.success_distance, dist

    # -- gym API ---------------------------------------------------------------------
    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None):
        super().reset(seed=seed)
        options = options or {}
        apply_variation_options(self.variation_space, options, self.np_random)
        state = np.asarray(options[keys.STATE], np.float64).reshape(-1) if keys.STATE in options else None
        self._setup(state)
        start, goal = self._draw_positions()
        given = given_factors(options)
        if "agent.position" in given:
            start = self.variation_space["agent"]["position"].value
        if "goal.position" in given:
            goal = self.variation_space["goal"]["position"].value
        if state is not None:
            start = state[:2]
        if keys.GOAL_STATE in options:
            goal = np.asarray(options[keys.GOAL_STATE], np.float64).reshape(-1)[:2]
        self._pos, self._goal = self._legal(start), self._legal(goal)
        self.variation_space.set_value(
            {"agent.position": self._pos.astype(np.float32), "goal.position": self._goal.astype(np.float32)}
        )
        self._static = self._goal_img = None
        return self._obs(), self._info()

    def render(self) -> np.ndarray:
        return self._draw(self._pos, show_goal=self.render_target)

    def _transition(self):
        """The ``step`` return value once the agent has moved."""
        success, dist = self.eval_state(self._goal, self._pos)
        return self._obs(), -dist, success, False, self._info()

    # -- hooks ---------------------------------------------------------------------------
    def _setup(self, state: np.ndarray | None) -> None:
        """Build the episode's geometry from the factors (and from ``state`` when restoring one)."""
        raise NotImplementedError("_setup(state | None) -> None")

    def _draw_positions(self) -> tuple[np.ndarray, np.ndarray]:
        """Start and goal positions (2,) drawn from ``self.np_random``."""
        raise NotImplementedError("_draw_positions() -> (start, goal)")

    def _legal(self, pos: np.ndarray) -> np.ndarray:
        """``pos`` moved to the nearest position the agent may occupy."""
        raise NotImplementedError("_legal(pos) -> pos")

    def _state(self, goal: bool = False) -> np.ndarray:
        """The full state vector (float32) of the agent, or of the goal configuration."""
        raise NotImplementedError("_state(goal) -> (D,) float32")

    def _draw_static(self) -> np.ndarray:
        """The frame without the disks, at ``render_size``."""
        raise NotImplementedError("_draw_static() -> (H, W, 3) uint8")

    # -- observation and drawing --------------------------------------------------------
    def _obs(self) -> dict[str, np.ndarray]:
        state = self._state()
        return {keys.PROPRIO: state[: self.proprio_dim].copy(), keys.STATE: state}

    def _info(self) -> dict[str, Any]:
        if self._goal_img is None:  # the goal image only changes on reset
            self._goal_img = self._draw(self._goal, show_goal=self.render_target)  # what the agent sees at the goal
        goal_state = self._state(goal=True)
        return {
            keys.GOAL: self._goal_img.copy(),
            keys.GOAL_STATE: goal_state,
            keys.GOAL_PROPRIO: goal_state[: self.proprio_dim].copy(),
        }

    def _draw(self, agent_pos: np.ndarray, show_goal: bool) -> np.ndarray:
        if self._static is None:
            self._static = self._draw_static()
        v = self.variation_space.value
        img = self._static.copy()
        scale = self.render_size[1] / self.world_size
        disks = [(self._goal, v["goal"])] if show_goal else []
        for pos, look in [*disks, (agent_pos, v["agent"])]:
            centre = draw.world_to_pixels(pos, self.world_size, self.render_size)
            draw.fill_circle(img, centre, float(look["radius"]) * scale, look["color"])
        return img

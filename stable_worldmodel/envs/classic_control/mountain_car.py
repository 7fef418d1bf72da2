"""``swm/MountainCarControl-v0`` and ``swm/MountainCarContinuousControl-v0``: Gymnasium's mountain cars
with factors of variation.

- **Dynamics**: Gymnasium's. Discrete: ``Discrete(3)`` = push left / nothing / right with
  ``force``; continuous: ``Box(-1, 1, (1,))`` times ``power``. The velocity gains
  ``- gravity * cos(3 position)`` each step and is clipped to ``max_speed``; the position is clipped
  to [-1.2, 0.6] (the velocity zeroed against the left wall).
- **Start**: Gymnasium's: position uniform in [-0.6, -0.4], velocity 0.
- **Goal**: Gymnasium's flag: ``goal_state = [0.5, 0]`` (continuous: ``[0.45, 0]``). ``eval_state``
  with a goal at or past the flag is Gymnasium's rule: success when ``position >= goal position``
  and ``velocity >= 0``; with any other goal (e.g. a dataset row's): success when the position is
  within 0.05 of the goal's. Distance: how far the position is from the goal's (0 past a flag goal).
  The flag is drawn at the goal position.
- **End / reward**: success is ``terminated``; Gymnasium's rewards (discrete: -1 per step;
  continuous: ``-0.1 action^2`` per step plus 100 on success).
- **Factors**: discrete (upstream's): ``physics.gravity``, ``force``, ``max_speed``;
  ``visuals.bg``, ``fg`` (track, car body, flagpole). Continuous: upstream's ``physics.power``,
  ``max_speed``, ``visuals.bg``, ``fg``, plus ``physics.gravity`` (upstream cannot vary it: Gymnasium
  hard-codes 0.0025 in the continuous env's step; the dynamics here are written out, so it can).
- The observation bounds allow the largest ``max_speed`` of the factor range (0.105; Gymnasium
  declares 0.07).
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np

from ... import spaces
from ._base import Canvas, ClassicControlEnv, rgb, rotate, scalar

MIN_POSITION, MAX_POSITION = -1.2, 0.6
MAX_SPEED_BOUND = 0.105  # the top of the max_speed factor
POSITION_TOLERANCE = 0.05
SCALE = 600 / (MAX_POSITION - MIN_POSITION)  # Gymnasium's pixels per unit of position
WHEEL_RGB = np.array([128, 128, 128], np.uint8)
FLAG_RGB = np.array([204, 204, 0], np.uint8)


def height(xs: Any) -> Any:
    """The track's height at positions ``xs`` (Gymnasium's ``sin(3 x) * 0.45 + 0.55``)."""
    return np.sin(3 * np.asarray(xs, np.float64)) * 0.45 + 0.55


def visuals_space() -> spaces.Dict:
    return spaces.Dict({"bg": rgb(0.6, 1.0, (1.0, 1.0, 1.0)), "fg": rgb(0.0, 0.4, (0.0, 0.0, 0.0))})


class _MountainCarBase(ClassicControlEnv):
    RENDER_SIZE = (400, 600)
    FEATURES = 2
    GOAL_POSITION = 0.5
    GOAL_VELOCITY = 0.0
    metadata = {"render_modes": ["rgb_array"], "render_fps": 30}

    def __init__(self, render_mode: str | None = "rgb_array", render_size: tuple[int, int] | None = None):
        self._scenery_key: tuple | None = None
        self._scenery_img = np.zeros((1, 1, 3), np.uint8)
        super().__init__(render_mode, render_size)
        low = np.array([MIN_POSITION, -MAX_SPEED_BOUND], np.float32)
        high = np.array([MAX_POSITION, MAX_SPEED_BOUND], np.float32)
        self.observation_space = gym.spaces.Box(low, high, dtype=np.float32)

    def state_size(self) -> int:
        return 2

    def sample_start(self) -> np.ndarray:
        return np.array([self.np_random.uniform(low=-0.6, high=-0.4), 0.0])

    def default_goal(self) -> np.ndarray:
        return np.array([self.GOAL_POSITION, self.GOAL_VELOCITY])

    def features(self, s: np.ndarray) -> np.ndarray:
        return np.asarray(s, np.float64).copy()

    def from_features(self, f: np.ndarray) -> np.ndarray:
        return np.asarray(f, np.float64).copy()

    def eval_state(self, goal_state: np.ndarray, cur_state: np.ndarray) -> tuple[bool, float]:
        g, c = self._pair(goal_state, cur_state)
        if g[0] >= self.GOAL_POSITION - 1e-6:  # the flag (or past it; float32 goals too): Gymnasium's rule
            return bool(c[0] >= g[0] and c[1] >= self.GOAL_VELOCITY), float(max(g[0] - c[0], 0.0))
        dist = float(abs(c[0] - g[0]))
        return dist <= POSITION_TOLERANCE, dist

    def _move(self, push: float) -> None:
        """One Gymnasium step with velocity change ``push`` from the engine."""
        position, velocity = self._s
        velocity += push + np.cos(3 * position) * (-self._p["gravity"])
        velocity = np.clip(velocity, -self._p["max_speed"], self._p["max_speed"])
        position += velocity
        position = np.clip(position, MIN_POSITION, MAX_POSITION)
        if position == MIN_POSITION and velocity < 0:
            velocity = 0.0
        self._s = np.array([position, velocity], np.float64)

    def _scenery(self) -> np.ndarray:
        """The frame without the car: track and flag (cached per size, colors and goal)."""
        c = self._colors
        key = (self.render_size, c["bg"].tobytes(), c["fg"].tobytes(), float(self._goal_s[0]))
        if self._scenery_key != key:
            cv = Canvas(self.render_size, (600, 400), c["bg"])
            xs = np.linspace(MIN_POSITION, MAX_POSITION, 100)
            cv.polyline(np.stack([(xs - MIN_POSITION) * SCALE, height(xs) * SCALE], 1), c["fg"])
            flag = self._goal_s[0]
            fx, fy1 = (flag - MIN_POSITION) * SCALE, float(height(flag)) * SCALE
            fy2 = fy1 + 50
            cv.line((fx, fy1), (fx, fy2), c["fg"])
            cv.polygon([(fx, fy2), (fx, fy2 - 10), (fx + 25, fy2 - 5)], FLAG_RGB)
            self._scenery_key, self._scenery_img = key, cv.img
        return self._scenery_img

    def draw(self, s: np.ndarray) -> np.ndarray:
        # Gymnasium's 600 x 400 screen: the track spans [-1.2, 0.6], car 40 x 20 px, flag 50 px high
        c = self._colors
        cv = Canvas(self.render_size, (600, 400), self._scenery())
        pos, angle, clearance = float(s[0]), float(np.cos(3 * s[0])), 10.0
        at = np.array([(pos - MIN_POSITION) * SCALE, clearance + float(height(pos)) * SCALE])
        cv.polygon(rotate([(-20, 0), (-20, 20), (20, 20), (20, 0)], angle) + at, c["fg"])
        for wheel in rotate([(10, 0), (-10, 0)], angle) + at:
            cv.circle(wheel, 20 / 2.5, WHEEL_RGB)
        return cv.img


class MountainCarControlEnv(_MountainCarBase):
    """Gymnasium's ``MountainCar-v0`` (discrete pushes) with factors (see the module docstring)."""

    ENV_NAME = "MountainCar-v0"

    def __init__(self, render_mode: str | None = "rgb_array", render_size: tuple[int, int] | None = None):
        super().__init__(render_mode, render_size)
        self.action_space = gym.spaces.Discrete(3)

    @classmethod
    def build_variation_space(cls) -> spaces.Dict:
        return spaces.Dict(
            {
                "physics": spaces.Dict(
                    {
                        "gravity": scalar(0.00125, 0.00375, 0.0025),
                        "force": scalar(0.0005, 0.0015, 0.001),
                        "max_speed": scalar(0.035, 0.105, 0.07),
                    }
                ),
                "visuals": visuals_space(),
            }
        )

    def step(self, action: Any):
        a = self._discrete(action, 3)
        self._move((a - 1) * self._p["force"])
        success, _ = self._success()
        return self._obs(), -1.0, success, False, self._info()


class MountainCarContinuousControlEnv(_MountainCarBase):
    """Gymnasium's ``MountainCarContinuous-v0`` with factors (see the module docstring)."""

    ENV_NAME = "MountainCarContinuous-v0"
    GOAL_POSITION = 0.45

    def __init__(self, render_mode: str | None = "rgb_array", render_size: tuple[int, int] | None = None):
        super().__init__(render_mode, render_size)
        self.action_space = gym.spaces.Box(-1.0, 1.0, (1,), np.float32)

    @classmethod
    def build_variation_space(cls) -> spaces.Dict:
        return spaces.Dict(
            {
                "physics": spaces.Dict(
                    {
                        "power": scalar(0.00075, 0.00225, 0.0015),
                        "max_speed": scalar(0.035, 0.105, 0.07),
                        "gravity": scalar(0.00125, 0.00375, 0.0025),
                    }
                ),
                "visuals": visuals_space(),
            }
        )

    def step(self, action: Any):
        a = self._continuous(action)
        self._move(min(max(a, -1.0), 1.0) * self._p["power"])
        success, _ = self._success()
        reward = (100.0 if success else 0.0) - a**2 * 0.1  # Gymnasium's: the unclipped action's square
        return self._obs(), reward, success, False, self._info()

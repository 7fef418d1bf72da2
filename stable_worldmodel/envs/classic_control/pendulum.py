"""``swm/PendulumControl-v1``: Gymnasium's ``Pendulum-v1`` with factors of variation and a goal.

- **Dynamics**: Gymnasium's (``theta`` = 0 upright; semi-implicit Euler steps of ``dt``, the rate
  clipped to ``max_speed``); action ``Box(-2, 2, (1,))``, the torque clipped to ``max_torque``
  (as upstream: values above 2 only matter for actions outside the declared space). Physical
  state ``[theta, theta_dot]``; the observation (and ``info["state"]``) is Gymnasium's
  ``[cos theta, sin theta, theta_dot]``.
- **Start**: Gymnasium's: ``theta`` uniform in [-pi, pi], ``theta_dot`` in [-1, 1].
- **Goal**: upright and at rest, ``goal_state = [1, 0, 0]``. ``eval_state``: success when the angle
  is within 0.1 rad of the goal's and the rate within 0.5 rad/s; distance = the norm of the
  (wrapped) angle and rate errors.
- **End / reward**: success is ``terminated`` (Gymnasium's pendulum never ends; ``World`` needs an
  end to count a success); Gymnasium's reward ``-(theta^2 + 0.1 theta_dot^2 + 0.001 u^2)``.
- **Factors** (upstream's): ``physics.g``, ``m``, ``l``, ``max_torque``, ``max_speed``, ``dt``;
  ``visuals.bg``, ``rod``, ``hub``. The rod is drawn ``l`` long (Gymnasium draws it 1 long whatever
  ``l``: identical at the default); Gymnasium's torque arrow is not drawn (it shows the action).
- The observation bounds allow the largest ``max_speed`` of the factor range (12; Gymnasium: 8).
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np

from ... import spaces
from ._base import Canvas, ClassicControlEnv, rgb, rotate, scalar, wrap_angle

MAX_SPEED_BOUND = 12.0  # the top of the max_speed factor
ACTION_BOUND = 2.0  # Gymnasium's action space (its default max_torque)
TOLERANCE = np.array([0.1, 0.5])  # angle, rate


class PendulumControlEnv(ClassicControlEnv):
    """Pendulum swing-up to upright (see the module docstring)."""

    ENV_NAME = "Pendulum-v1"
    RENDER_SIZE = (500, 500)
    FEATURES = 3

    def __init__(self, render_mode: str | None = "rgb_array", render_size: tuple[int, int] | None = None):
        super().__init__(render_mode, render_size)
        high = np.array([1.0, 1.0, MAX_SPEED_BOUND], np.float32)
        self.observation_space = gym.spaces.Box(-high, high, dtype=np.float32)
        self.action_space = gym.spaces.Box(-ACTION_BOUND, ACTION_BOUND, (1,), np.float32)

    @classmethod
    def build_variation_space(cls) -> spaces.Dict:
        return spaces.Dict(
            {
                "physics": spaces.Dict(
                    {
                        "g": scalar(5.0, 15.0, 10.0),
                        "m": scalar(0.5, 1.5, 1.0),
                        "l": scalar(0.5, 1.5, 1.0),
                        "max_torque": scalar(1.0, 4.0, 2.0),
                        "max_speed": scalar(4.0, 12.0, 8.0),
                        "dt": scalar(0.025, 0.1, 0.05),
                    }
                ),
                "visuals": spaces.Dict(
                    {
                        "bg": rgb(0.6, 1.0, (1.0, 1.0, 1.0)),
                        "rod": rgb(0.0, 1.0, (204 / 255, 77 / 255, 77 / 255)),
                        "hub": rgb(0.0, 0.4, (0.0, 0.0, 0.0)),
                    }
                ),
            }
        )

    def state_size(self) -> int:
        return 2

    def sample_start(self) -> np.ndarray:
        high = np.array([np.pi, 1.0])
        return self.np_random.uniform(low=-high, high=high)

    def default_goal(self) -> np.ndarray:
        return np.zeros(2)

    def features(self, s: np.ndarray) -> np.ndarray:
        theta, rate = np.asarray(s, np.float64)
        return np.array([np.cos(theta), np.sin(theta), rate])

    def from_features(self, f: np.ndarray) -> np.ndarray:
        return np.array([np.arctan2(f[1], f[0]), f[2]])

    def eval_state(self, goal_state: np.ndarray, cur_state: np.ndarray) -> tuple[bool, float]:
        g, c = self._pair(goal_state, cur_state)
        d = np.array([wrap_angle(np.arctan2(c[1], c[0]) - np.arctan2(g[1], g[0])), c[2] - g[2]])
        return bool(np.all(np.abs(d) <= TOLERANCE)), float(np.linalg.norm(d))

    def step(self, action: Any):
        p = self._p
        u = min(max(self._continuous(action), -p["max_torque"]), p["max_torque"])
        th, thdot = self._s
        cost = float(wrap_angle(th)) ** 2 + 0.1 * thdot**2 + 0.001 * u**2
        newthdot = thdot + (3 * p["g"] / (2 * p["l"]) * np.sin(th) + 3.0 / (p["m"] * p["l"] ** 2) * u) * p["dt"]
        newthdot = min(max(newthdot, -p["max_speed"]), p["max_speed"])
        self._s = np.array([th + newthdot * p["dt"], newthdot], np.float64)
        success, _ = self._success()
        return self._obs(), -float(cost), success, False, self._info()

    def draw(self, s: np.ndarray) -> np.ndarray:
        # Gymnasium's 500 x 500 screen: 2.2 units each side of the hub, rod 0.2 wide
        c = self._colors
        scale, off = 500 / (2 * 2.2), 250.0
        cv = Canvas(self.render_size, (500, 500), c["bg"])
        length, half = self._p["l"] * scale, 0.1 * scale
        rod = rotate([(0, -half), (0, half), (length, half), (length, -half)], s[0] + np.pi / 2)
        cv.polygon(rod + off, c["rod"])
        cv.circle(rotate([(length, 0.0)], s[0] + np.pi / 2)[0] + off, half, c["rod"])
        cv.circle((off, off), 0.05 * scale, c["hub"])
        return cv.img

"""``swm/AcrobotControl-v1``: Gymnasium's ``Acrobot-v1`` with factors of variation.

- **Dynamics**: Gymnasium's ("book" equations, one Runge-Kutta-4 step of 0.2 s, angles wrapped to
  [-pi, pi], rates clipped to 4 pi and 9 pi); action ``Discrete(3)`` = torque -1 / 0 / +1 on the
  second joint. Physical state ``[theta1, theta2, theta1_dot, theta2_dot]``; the observation (and
  ``info["state"]``) is Gymnasium's ``[cos theta1, sin theta1, cos theta2, sin theta2, theta1_dot,
  theta2_dot]``.
- **Start**: Gymnasium's, the four numbers uniform in [-0.1, 0.1].
- **Goal**: Gymnasium's "tip above the line": the tip height ``-cos theta1 - cos(theta1 + theta2)``
  (in link lengths, as Gymnasium's rule) at least the goal state's. The default goal state is the
  pose at rest with the first link horizontal and the second upright (``theta = (pi/2, pi/2)``),
  whose tip is exactly on the line (height 1), so success is Gymnasium's termination; a goal from a
  dataset row asks for the tip at least as high as in that row. Distance: the missing height (0
  once reached).
- **End / reward**: success is ``terminated``; Gymnasium's reward (-1 per step, 0 on success).
- **Factors** (upstream's): ``physics.link_length_1``, ``link_length_2`` (drawn; Gymnasium's
  dynamics do not use the second length), ``link_mass_1``, ``link_mass_2``, ``link_com_pos_1``,
  ``link_com_pos_2``, ``link_moi`` (both links); ``visuals.bg``, ``line``, ``link``, ``joint``.
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np

from ... import spaces
from ._base import Canvas, ClassicControlEnv, rgb, rotate, scalar

DT = 0.2
GRAVITY = 9.8
MAX_VEL_1, MAX_VEL_2 = 4 * np.pi, 9 * np.pi
TORQUES = (-1.0, 0.0, 1.0)
GOAL_THETA = (np.pi / 2, np.pi / 2)


def tip_height(f: np.ndarray) -> np.ndarray:
    """Gymnasium's tip height ``-cos t1 - cos(t1 + t2)`` of observation vectors ``f`` (..., 6)."""
    f = np.asarray(f, np.float64)
    c1, s1, c2, s2 = f[..., 0], f[..., 1], f[..., 2], f[..., 3]
    return -c1 - (c1 * c2 - s1 * s2)


def _wrap(x: float) -> float:
    """Gymnasium's ``wrap(x, -pi, pi)`` (the same arithmetic, so the same floats)."""
    while x > np.pi:
        x = x - 2 * np.pi
    while x < -np.pi:
        x = x + 2 * np.pi
    return x


class AcrobotControlEnv(ClassicControlEnv):
    """Acrobot swing-up (see the module docstring)."""

    ENV_NAME = "Acrobot-v1"
    RENDER_SIZE = (500, 500)
    FEATURES = 6
    metadata = {"render_modes": ["rgb_array"], "render_fps": 15}

    def __init__(self, render_mode: str | None = "rgb_array", render_size: tuple[int, int] | None = None):
        super().__init__(render_mode, render_size)
        high = np.array([1.0, 1.0, 1.0, 1.0, MAX_VEL_1, MAX_VEL_2], np.float32)
        self.observation_space = gym.spaces.Box(-high, high, dtype=np.float32)
        self.action_space = gym.spaces.Discrete(3)

    @classmethod
    def build_variation_space(cls) -> spaces.Dict:
        return spaces.Dict(
            {
                "physics": spaces.Dict(
                    {
                        "link_length_1": scalar(0.5, 1.5, 1.0),
                        "link_length_2": scalar(0.5, 1.5, 1.0),
                        "link_mass_1": scalar(0.5, 1.5, 1.0),
                        "link_mass_2": scalar(0.5, 1.5, 1.0),
                        "link_com_pos_1": scalar(0.25, 0.75, 0.5),
                        "link_com_pos_2": scalar(0.25, 0.75, 0.5),
                        "link_moi": scalar(0.5, 1.5, 1.0),
                    }
                ),
                "visuals": spaces.Dict(
                    {
                        "bg": rgb(0.6, 1.0, (1.0, 1.0, 1.0)),
                        "line": rgb(0.0, 0.4, (0.0, 0.0, 0.0)),
                        "link": rgb(0.0, 1.0, (0.0, 204 / 255, 204 / 255)),
                        "joint": rgb(0.0, 1.0, (204 / 255, 204 / 255, 0.0)),
                    }
                ),
            }
        )

    def state_size(self) -> int:
        return 4

    def sample_start(self) -> np.ndarray:
        return self.np_random.uniform(low=-0.1, high=0.1, size=(4,)).astype(np.float32).astype(np.float64)

    def default_goal(self) -> np.ndarray:
        return np.array([*GOAL_THETA, 0.0, 0.0])

    def features(self, s: np.ndarray) -> np.ndarray:
        t1, t2, r1, r2 = np.asarray(s, np.float64)
        return np.array([np.cos(t1), np.sin(t1), np.cos(t2), np.sin(t2), r1, r2])

    def from_features(self, f: np.ndarray) -> np.ndarray:
        return np.array([np.arctan2(f[1], f[0]), np.arctan2(f[3], f[2]), f[4], f[5]])

    def eval_state(self, goal_state: np.ndarray, cur_state: np.ndarray) -> tuple[bool, float]:
        g, c = self._pair(goal_state, cur_state)
        missing = float(tip_height(g) - tip_height(c))
        return missing <= 0.0, max(missing, 0.0)

    def _success(self) -> tuple[bool, float]:
        # Gymnasium's test on the physical angles: the same floats as its termination
        def h(s: np.ndarray) -> float:
            return float(-np.cos(s[0]) - np.cos(s[1] + s[0]))

        missing = h(self._goal_s) - h(self._s)
        return missing <= 0.0, max(missing, 0.0)

    def _dsdt(self, s: np.ndarray, torque: float) -> np.ndarray:
        p = self._p
        m1, m2, l1 = p["link_mass_1"], p["link_mass_2"], p["link_length_1"]
        lc1, lc2, i1, i2 = p["link_com_pos_1"], p["link_com_pos_2"], p["link_moi"], p["link_moi"]
        theta1, theta2, dtheta1, dtheta2 = s
        d1 = m1 * lc1**2 + m2 * (l1**2 + lc2**2 + 2 * l1 * lc2 * np.cos(theta2)) + i1 + i2
        d2 = m2 * (lc2**2 + l1 * lc2 * np.cos(theta2)) + i2
        phi2 = m2 * lc2 * GRAVITY * np.cos(theta1 + theta2 - np.pi / 2.0)
        phi1 = (
            -m2 * l1 * lc2 * dtheta2**2 * np.sin(theta2)
            - 2 * m2 * l1 * lc2 * dtheta2 * dtheta1 * np.sin(theta2)
            + (m1 * lc1 + m2 * l1) * GRAVITY * np.cos(theta1 - np.pi / 2)
            + phi2
        )
        ddtheta2 = (torque + d2 / d1 * phi1 - m2 * l1 * lc2 * dtheta1**2 * np.sin(theta2) - phi2) / (
            m2 * lc2**2 + i2 - d2**2 / d1
        )
        ddtheta1 = -(d2 * ddtheta2 + phi1) / d1
        return np.array([dtheta1, dtheta2, ddtheta1, ddtheta2])

    def step(self, action: Any):
        torque = TORQUES[self._discrete(action, 3)]
        s, h = self._s, DT
        k1 = self._dsdt(s, torque)
        k2 = self._dsdt(s + h / 2.0 * k1, torque)
        k3 = self._dsdt(s + h / 2.0 * k2, torque)
        k4 = self._dsdt(s + h * k3, torque)
        ns = s + h / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4)
        ns[0], ns[1] = _wrap(ns[0]), _wrap(ns[1])
        ns[2] = min(max(ns[2], -MAX_VEL_1), MAX_VEL_1)
        ns[3] = min(max(ns[3], -MAX_VEL_2), MAX_VEL_2)
        self._s = ns
        success, _ = self._success()
        return self._obs(), 0.0 if success else -1.0, success, False, self._info()

    def draw(self, s: np.ndarray) -> np.ndarray:
        # Gymnasium's 500 x 500 screen, scaled so that both links plus 0.2 fit each side of the base
        c, p = self._colors, self._p
        l1, l2 = p["link_length_1"], p["link_length_2"]
        scale, off = 500 / (2 * (l1 + l2 + 0.2)), 250.0
        cv = Canvas(self.render_size, (500, 500), c["bg"])
        cv.line((-2.2 * scale + off, scale + off), (2.2 * scale + off, scale + off), c["line"])
        joints = np.array([[0.0, 0.0], [l1 * np.sin(s[0]) * scale, -l1 * np.cos(s[0]) * scale]]) + off
        half = 0.1 * scale
        for joint, th, length in zip(joints, (s[0] - np.pi / 2, s[0] + s[1] - np.pi / 2), (l1, l2), strict=True):
            link = rotate([(0, -half), (0, half), (length * scale, half), (length * scale, -half)], th)
            cv.polygon(link + joint, c["link"])
            cv.circle(joint, half, c["joint"])
        return cv.img

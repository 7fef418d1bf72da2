"""``swm/CartPoleControl-v1``: Gymnasium's ``CartPole-v1`` with factors of variation and a goal.

- **Dynamics**: Gymnasium's (Euler steps of ``tau`` seconds, Barto, Sutton & Anderson's equations);
  action ``Discrete(2)``: push the cart left (0) or right (1) with ``force_mag`` newtons.
- **Start**: Gymnasium's, each of ``[x, x_dot, theta, theta_dot]`` uniform in [-0.05, 0.05].
- **Goal**: the pole upright and at rest over the cart, the cart at rest at ``goal x``, drawn per
  reset uniform in ``[-1.5, -0.5] U [0.5, 1.5]`` m (``goal_state = [goal_x, 0, 0, 0]``; a marker
  under the track shows it). ``eval_state``: success when ``|dx| <= 0.1`` m, ``|dtheta| <= 0.05``
  rad, ``|dx_dot| <= 0.3`` m/s and ``|dtheta_dot| <= 0.5`` rad/s; distance = the Euclidean norm.
- **End**: reaching the goal is ``terminated`` (success); the pole past 12 degrees or the cart past
  2.4 m (Gymnasium's failure) is ``truncated`` (a failure, as ``World`` counts ``terminated`` as
  success). Reward: Gymnasium's 1.0 per step.
- **Factors** (upstream's): ``physics.gravity``, ``masscart``, ``masspole``, ``length`` (half the
  pole), ``force_mag``, ``tau``; ``visuals.bg``, ``cart`` (the cart, the track and the goal
  marker), ``pole``, ``axle``.
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np

from ... import spaces
from ._base import Canvas, ClassicControlEnv, rgb, rotate, scalar, wrap_angle

X_THRESHOLD = 2.4
THETA_THRESHOLD = 12 * 2 * np.pi / 360
GOAL_RANGE = (0.5, 1.5)  # |goal x|, metres
TOLERANCE = np.array([0.1, 0.3, 0.05, 0.5])  # x, x_dot, theta, theta_dot
POLE_RGB = (202 / 255, 152 / 255, 101 / 255)
AXLE_RGB = (129 / 255, 132 / 255, 203 / 255)


class CartPoleControlEnv(ClassicControlEnv):
    """Cart-pole balancing with a goal cart position (see the module docstring)."""

    ENV_NAME = "CartPole-v1"
    RENDER_SIZE = (400, 600)
    FEATURES = 4
    metadata = {"render_modes": ["rgb_array"], "render_fps": 50}

    def __init__(self, render_mode: str | None = "rgb_array", render_size: tuple[int, int] | None = None):
        super().__init__(render_mode, render_size)
        high = np.array([X_THRESHOLD * 2, np.inf, THETA_THRESHOLD * 2, np.inf], np.float32)
        self.observation_space = gym.spaces.Box(-high, high, dtype=np.float32)
        self.action_space = gym.spaces.Discrete(2)

    @classmethod
    def build_variation_space(cls) -> spaces.Dict:
        return spaces.Dict(
            {
                "physics": spaces.Dict(
                    {
                        "gravity": scalar(4.9, 14.7, 9.8),
                        "masscart": scalar(0.5, 1.5, 1.0),
                        "masspole": scalar(0.05, 0.5, 0.1),
                        "length": scalar(0.25, 0.75, 0.5),
                        "force_mag": scalar(5.0, 15.0, 10.0),
                        "tau": scalar(0.01, 0.04, 0.02),
                    }
                ),
                "visuals": spaces.Dict(
                    {
                        "bg": rgb(0.6, 1.0, (1.0, 1.0, 1.0)),
                        "cart": rgb(0.0, 0.4, (0.0, 0.0, 0.0)),
                        "pole": rgb(0.0, 1.0, POLE_RGB),
                        "axle": rgb(0.0, 1.0, AXLE_RGB),
                    }
                ),
            }
        )

    def state_size(self) -> int:
        return 4

    def sample_start(self) -> np.ndarray:
        return self.np_random.uniform(low=-0.05, high=0.05, size=(4,))

    def default_goal(self) -> np.ndarray:
        x = self.np_random.uniform(*GOAL_RANGE) * (1.0 if self.np_random.random() < 0.5 else -1.0)
        return np.array([x, 0.0, 0.0, 0.0])

    def features(self, s: np.ndarray) -> np.ndarray:
        return np.asarray(s, np.float64).copy()

    def from_features(self, f: np.ndarray) -> np.ndarray:
        return np.asarray(f, np.float64).copy()

    def eval_state(self, goal_state: np.ndarray, cur_state: np.ndarray) -> tuple[bool, float]:
        g, c = self._pair(goal_state, cur_state)
        d = c - g
        d[2] = wrap_angle(d[2])
        return bool(np.all(np.abs(d) <= TOLERANCE)), float(np.linalg.norm(d))

    def step(self, action: Any):
        push = self._discrete(action, 2)
        p = self._p
        x, x_dot, theta, theta_dot = self._s
        force = p["force_mag"] if push == 1 else -p["force_mag"]
        total_mass = p["masspole"] + p["masscart"]
        polemass_length = p["masspole"] * p["length"]
        cos, sin = np.cos(theta), np.sin(theta)
        temp = (force + polemass_length * theta_dot**2 * sin) / total_mass
        theta_acc = (p["gravity"] * sin - cos * temp) / (
            p["length"] * (4.0 / 3.0 - p["masspole"] * cos**2 / total_mass)
        )
        x_acc = temp - polemass_length * theta_acc * cos / total_mass
        tau = p["tau"]
        self._s = np.array(
            [x + tau * x_dot, x_dot + tau * x_acc, theta + tau * theta_dot, theta_dot + tau * theta_acc], np.float64
        )
        x, theta = self._s[0], self._s[2]
        fell = bool(x < -X_THRESHOLD or x > X_THRESHOLD or theta < -THETA_THRESHOLD or theta > THETA_THRESHOLD)
        success, _ = self._success()
        return self._obs(), 1.0, success, fell and not success, self._info()

    def draw(self, s: np.ndarray) -> np.ndarray:
        # Gymnasium's 600 x 400 screen: 125 px per metre, cart 50 x 30 px, pole 10 px wide
        c, p = self._colors, self._p
        cv = Canvas(self.render_size, (600, 400), c["bg"])
        scale, cart_y, axle_offset = 600 / (2 * X_THRESHOLD), 100.0, 30 / 4.0
        cv.line((0, cart_y), (600, cart_y), c["cart"])  # the track
        gx = self._goal_s[0] * scale + 300
        cv.polygon([(gx, cart_y - 17), (gx - 6, cart_y - 27), (gx + 6, cart_y - 27)], c["cart"])  # goal marker
        cart_x = s[0] * scale + 300
        cv.polygon([(cart_x + dx, cart_y + dy) for dx, dy in ((-25, -15), (-25, 15), (25, 15), (25, -15))], c["cart"])
        pole_len = scale * 2 * p["length"]
        pole = rotate([(-5, -5), (-5, pole_len - 5), (5, pole_len - 5), (5, -5)], -s[2])
        cv.polygon(pole + [cart_x, cart_y + axle_offset], c["pole"])
        cv.circle((cart_x, cart_y + axle_offset), 5.0, c["axle"])
        return cv.img

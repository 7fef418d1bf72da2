"""Scripted experts of the classic-control envs: batched, no learning.

:class:`ClassicControlExpert` reads ``infos["state"]`` and ``infos["goal_state"]`` (``(B, T, D)``,
the observation layout) and returns ``(B,)`` int64 actions (discrete envs) or ``(B, 1)`` float32:

- **CartPole**: discrete LQR. The gain is the discrete-time LQR of Gymnasium's cart-pole
  linearised about upright (Euler step ``tau``), at the default factors; the expert pushes right
  when ``-K (state - goal)`` is positive (the cart's distance to the goal clipped to 0.5 m, so it
  travels at a bounded speed). One gain holds the pole over the whole factor range.
- **MountainCar** (both): energy pumping: push along the velocity (right at rest). It passes every
  position and climbs to the flag in one or two swings at the default factors.
- **Acrobot**: energy pumping through the reaction torque: torque against the first joint's rate
  (-1 when it turns counter-clockwise, +1 otherwise), which raises the swing until the tip passes
  the goal height.
- **Pendulum**: energy shaping (torque ``k (E_goal - E) theta_dot`` with ``E = theta_dot^2 / 2 + a
  cos theta``, ``a = 3 g / (2 l)``) until within 0.6 rad of the goal angle, then PD with gravity
  feed-forward (natural frequency 4 rad/s), clipped to the action space.
  It uses ``g``, ``m``, ``l`` from ``infos["variation.physics.*"]`` when World records them (the
  factors named in ``reset(options={"variation": [...]})``), else the defaults.

``noise`` makes the data less regular: Gaussian noise of that std on continuous actions (in
action units, before clipping), or the probability of a uniformly random discrete action; drawn
from ``seed`` (:meth:`set_seed` restarts it).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ... import keys
from ...errors import ConfigError, unknown_name
from ...policy import ExpertPolicy
from ._base import batch_factor, wrap_angle

CARTPOLE = {"q": (10.0, 1.0, 10.0, 1.0), "r": 0.1, "max_offset": 0.5}
PENDULUM = {"pump": 2.0, "catch": 0.6, "omega": 4.0}
_DEFAULTS = {"gravity": 9.8, "masscart": 1.0, "masspole": 0.1, "length": 0.5, "tau": 0.02}
_GAIN: dict[str, np.ndarray] = {}


def cartpole_gain(
    gravity: float = 9.8,
    masscart: float = 1.0,
    masspole: float = 0.1,
    length: float = 0.5,
    tau: float = 0.02,
    q: tuple[float, ...] = CARTPOLE["q"],
    r: float = CARTPOLE["r"],
    iters: int = 2000,
) -> np.ndarray:
    """The (4,) discrete LQR gain (force per unit of ``[x, x_dot, theta, theta_dot]`` error) of
    Gymnasium's cart-pole linearised about upright, one Euler step of ``tau``."""
    total = masscart + masspole
    den = length * (4.0 / 3.0 - masspole / total)
    a_tt, b_t = gravity / den, -1.0 / (total * den)
    a_xt, b_x = -masspole * length * a_tt / total, 1.0 / total - masspole * length * b_t / total
    a = np.eye(4) + tau * np.array([[0, 1, 0, 0], [0, 0, a_xt, 0], [0, 0, 0, 1], [0, 0, a_tt, 0]])
    b = tau * np.array([[0.0], [b_x], [0.0], [b_t]])
    qm, rm = np.diag(q), np.array([[r]])
    p = qm.copy()
    for _ in range(iters):
        k = np.linalg.solve(rm + b.T @ p @ b, b.T @ p @ a)
        p = qm + a.T @ p @ (a - b @ k)
    return k[0]


def cartpole(state: np.ndarray, goal: np.ndarray, infos: dict) -> np.ndarray:
    """(B,) pushes (0 left, 1 right) for states ``[x, x_dot, theta, theta_dot]`` (B, 4)."""
    if "cartpole" not in _GAIN:
        _GAIN["cartpole"] = cartpole_gain(**_DEFAULTS)
    err = state - goal
    err[:, 0] = np.clip(err[:, 0], -CARTPOLE["max_offset"], CARTPOLE["max_offset"])
    err[:, 2] = wrap_angle(err[:, 2])
    return (-(err @ _GAIN["cartpole"]) > 0).astype(np.int64)


def mountain_car(state: np.ndarray, goal: np.ndarray, infos: dict) -> np.ndarray:
    """(B,) pushes (0 left, 2 right) along the velocity, for states ``[position, velocity]``."""
    return np.where(state[:, 1] >= 0, 2, 0).astype(np.int64)


def mountain_car_continuous(state: np.ndarray, goal: np.ndarray, infos: dict) -> np.ndarray:
    """(B, 1) full throttle along the velocity."""
    return np.where(state[:, 1] >= 0, 1.0, -1.0)[:, None]


def acrobot(state: np.ndarray, goal: np.ndarray, infos: dict) -> np.ndarray:
    """(B,) torque indices (0: -1, 2: +1) against the first joint's rate (observation index 4)."""
    return np.where(state[:, 4] > 0, 0, 2).astype(np.int64)


def pendulum(state: np.ndarray, goal: np.ndarray, infos: dict) -> np.ndarray:
    """(B, 1) torques for states ``[cos theta, sin theta, theta_dot]``."""
    n = state.shape[0]
    g, m, length = (batch_factor(infos, f"physics.{k}", d, n) for k, d in (("g", 10.0), ("m", 1.0), ("l", 1.0)))
    a, b = 3.0 * g / (2.0 * length), 3.0 / (m * length**2)
    theta, rate = np.arctan2(state[:, 1], state[:, 0]), state[:, 2]
    theta_g, rate_g = np.arctan2(goal[:, 1], goal[:, 0]), goal[:, 2]
    err = wrap_angle(theta - theta_g)
    energy = 0.5 * rate**2 + a * np.cos(theta)
    energy_g = 0.5 * rate_g**2 + a * np.cos(theta_g)
    pump = PENDULUM["pump"] * (energy_g - energy) * rate / b
    w = PENDULUM["omega"]
    hold = (-a * np.sin(theta_g) - (a + w * w) * err - 2 * w * (rate - rate_g)) / b
    return np.where(np.abs(err) < PENDULUM["catch"], hold, pump)[:, None]


#: env id -> (controller, number of discrete actions or None, continuous action bound)
CONTROLLERS: dict[str, tuple[Any, int | None, float]] = {
    "swm/CartPoleControl-v1": (cartpole, 2, 0.0),
    "swm/MountainCarControl-v0": (mountain_car, 3, 0.0),
    "swm/MountainCarContinuousControl-v0": (mountain_car_continuous, None, 1.0),
    "swm/AcrobotControl-v1": (acrobot, 3, 0.0),
    "swm/PendulumControl-v1": (pendulum, None, 2.0),
}


class ClassicControlExpert(ExpertPolicy):
    """Batched scripted expert of the classic-control envs (see the module docstring)."""

    def __init__(
        self, env_id: str = "swm/CartPoleControl-v1", noise: float = 0.0, seed: int | None = None, **kwargs: Any
    ):
        if env_id not in CONTROLLERS:
            raise unknown_name("classic-control env with a scripted expert", str(env_id), CONTROLLERS)
        if isinstance(noise, bool) or not isinstance(noise, (int, float, np.number)) or not np.isfinite(noise):
            raise ConfigError(f"ClassicControlExpert requires noise to be a number >= 0, got {noise!r}")
        if noise < 0:
            raise ConfigError(f"ClassicControlExpert requires noise >= 0, got {noise!r}")
        super().__init__(env_id=env_id, noise=float(noise), seed=seed, **kwargs)
        self.controller, self.n_actions, self.bound = CONTROLLERS[env_id]
        self.rng = np.random.default_rng(seed)

    def get_action(self, infos: dict[str, np.ndarray], **kwargs: Any) -> np.ndarray:
        state = np.asarray(infos[keys.STATE], np.float64)[:, -1]
        goal = np.asarray(infos[keys.GOAL_STATE], np.float64)[:, -1]
        action = self.controller(state, goal, infos)
        if self.n_actions is not None:
            if self.noise:
                flip = self.rng.random(action.shape[0]) < min(self.noise, 1.0)
                action = np.where(flip, self.rng.integers(0, self.n_actions, action.shape[0]), action)
            return action.astype(np.int64)
        if self.noise:
            action = action + self.noise * self.rng.standard_normal(action.shape)
        return np.clip(action, -self.bound, self.bound).astype(np.float32)

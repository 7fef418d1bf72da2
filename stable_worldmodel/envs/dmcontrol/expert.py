"""Experts of the DeepMind Control envs.

- :class:`DMControlExpert`: batched scripted controllers, no learning, for the domains in
  :data:`CONTROLLERS` (the registry's ``DMC_EXPERTS``). They read ``infos["state"]`` and
  ``infos["goal_state"]`` (``[qpos, qvel, act]``, ``(B, T, D)``) and return ``(B, A)`` float32:

  - Pendulum: energy pumping (torque along the velocity while the energy is below the upright
    one), then a PD balance within 0.4 rad of the goal (upright).
  - Cartpole: energy-based swing-up (cart pushed along ``E * angle_rate * cos(angle)`` with a
    weak centring term), then an LQR balance about the goal (upright over the goal's cart
    position) within 0.5 rad; the gain is computed once from dm_control's model (finite
    differences over one env step, discrete Riccati iteration).
  - Reacher: joint-space PD towards the goal configuration (which the env computes by inverse
    kinematics so that the fingertip is on the target).

  Gains are tuned at the default factors (nominal masses and gravity). Measured with ``World``
  (20 episodes of 500 steps, one dm_control episode; return on dm_control's 0-1000 scale):
  Pendulum 852 +- 95, Cartpole 623 +- 45, Reacher 980 +- 11 (random actions: 0, 0, 11), the
  goal reached at the end of every episode. With every factor resampled, Reacher still succeeds;
  Pendulum and Cartpole mostly fail (lateral or strong gravity moves or hides the upright
  equilibrium the sparse goal asks for).

- :class:`ExpertPolicy`: upstream 0.1.1's expert, a Stable-Baselines3 SAC checkpoint with its
  ``VecNormalize`` statistics, acting on ``infos["observation"]`` (needs ``stable-baselines3``).
"""

from __future__ import annotations

import os
import pickle
import re
from collections.abc import Callable
from typing import Any

import numpy as np

from ... import keys
from ..._optional import require
from ...errors import ConfigError, SWMError, unknown_name
from ...policy import BasePolicy
from ...policy import ExpertPolicy as ScriptedExpert

PENDULUM = {"inertia": 0.251, "mgl": 9.81 * 0.5, "pump": 5.0, "kp": 10.0, "kd": 2.0, "balance": 0.4}
CARTPOLE = {
    "mgl": 0.1 * 9.81 * 0.5,
    "inertia": 0.1 / 3,
    "pump": 30.0,
    "kx": 0.5,
    "kv": 0.5,
    "balance": 0.5,
    "q": (1.0, 10.0, 0.1, 0.1),
    "r": 1.0,
}
REACHER = {"kp": 5.0, "kd": 0.2}
_GAINS: dict[str, np.ndarray] = {}


def _wrap(angle: np.ndarray) -> np.ndarray:
    return (angle + np.pi) % (2 * np.pi) - np.pi


def pendulum(state: np.ndarray, goal: np.ndarray) -> np.ndarray:
    """(B, 1) torques for pendulum states ``[angle, rate]`` (B, >=2)."""
    p = PENDULUM
    angle, rate = _wrap(state[:, 0] - goal[:, 0]), state[:, 1]
    energy = 0.5 * p["inertia"] * rate**2 + p["mgl"] * np.cos(angle)
    pump = p["pump"] * (p["mgl"] - energy) * rate
    balance = -p["kp"] * angle - p["kd"] * rate
    return np.where(np.cos(angle) > np.cos(p["balance"]), balance, pump)[:, None]


def cartpole(state: np.ndarray, goal: np.ndarray) -> np.ndarray:
    """(B, 1) cart forces for cart-pole states ``[x, angle, x_rate, angle_rate]`` (B, >=4)."""
    p = CARTPOLE
    x, angle, x_rate, rate = state[:, 0] - goal[:, 0], _wrap(state[:, 1] - goal[:, 1]), state[:, 2], state[:, 3]
    energy = 0.5 * p["inertia"] * rate**2 + p["mgl"] * (np.cos(angle) - 1.0)
    swing = p["pump"] * energy * rate * np.cos(angle) - p["kx"] * x - p["kv"] * x_rate
    balance = -(np.stack([x, angle, x_rate, rate], 1) @ cartpole_gain().T)[:, 0]
    return np.where(np.cos(angle) > np.cos(p["balance"]), balance, swing)[:, None]


def reacher(state: np.ndarray, goal: np.ndarray) -> np.ndarray:
    """(B, 2) joint torques for reacher states ``[shoulder, wrist, rates]`` (B, >=4)."""
    err = np.stack([_wrap(goal[:, 0] - state[:, 0]), goal[:, 1] - state[:, 1]], 1)
    return REACHER["kp"] * err - REACHER["kd"] * state[:, 2:4]


CONTROLLERS: dict[str, Callable[[np.ndarray, np.ndarray], np.ndarray]] = {
    "Pendulum": pendulum,
    "Cartpole": cartpole,
    "Reacher": reacher,
}


def cartpole_gain() -> np.ndarray:
    """The (1, 4) discrete LQR gain of dm_control's cart-pole about upright, per env step (2 x 0.01 s)."""
    if "cartpole" not in _GAINS:
        _GAINS["cartpole"] = _lqr_gain()
    return _GAINS["cartpole"]


def _lqr_gain(repeat: int = 2, iters: int = 2000) -> np.ndarray:
    from ..mujoco_render import setup_gl

    setup_gl()  # mujoco may be imported here first
    import mujoco
    from dm_control.suite import cartpole as suite_cartpole

    from ._model import parse_spec, strip_textures

    xml, assets = suite_cartpole.get_model_and_assets()
    spec = parse_spec(xml.decode(), assets)
    strip_textures(spec)
    model = spec.compile()
    data = mujoco.MjData(model)
    nq, nv = model.nq, model.nv

    def step(x: np.ndarray, u: np.ndarray) -> np.ndarray:
        mujoco.mj_resetData(model, data)
        data.qpos[:], data.qvel[:], data.ctrl[:] = x[:nq], x[nq:], u
        mujoco.mj_step(model, data, repeat)
        return np.concatenate([data.qpos, data.qvel])

    x0, u0, eps = np.zeros(nq + nv), np.zeros(model.nu), 1e-6
    a = np.stack([(step(x0 + eps * e, u0) - step(x0 - eps * e, u0)) / (2 * eps) for e in np.eye(nq + nv)], 1)
    b = np.stack([(step(x0, u0 + eps * e) - step(x0, u0 - eps * e)) / (2 * eps) for e in np.eye(model.nu)], 1)
    q, r = np.diag(CARTPOLE["q"]), CARTPOLE["r"] * np.eye(model.nu)
    p = q.copy()
    for _ in range(iters):
        k = np.linalg.solve(r + b.T @ p @ b, b.T @ p @ a)
        p = q + a.T @ p @ (a - b @ k)
    return k


class DMControlExpert(ScriptedExpert):
    """Batched scripted expert of ``swm/<Name>DMControl-v0`` for the domains in :data:`CONTROLLERS`.

    ``noise`` adds seeded Gaussian noise of that std before clipping to [-1, 1].
    """

    def __init__(
        self, env_id: str = "swm/CartpoleDMControl-v0", noise: float = 0.0, seed: int | None = None, **kwargs: Any
    ):
        match = re.fullmatch(r"swm/(\w+)DMControl-v0", str(env_id))
        name = match.group(1) if match else str(env_id)
        if name not in CONTROLLERS:
            raise unknown_name(
                "DMControl domain with a scripted expert", str(env_id), [f"swm/{n}DMControl-v0" for n in CONTROLLERS]
            )
        if not np.isfinite(noise) or noise < 0:
            raise ConfigError(f"DMControlExpert requires noise >= 0, got {noise!r}")
        super().__init__(env_id=env_id, noise=float(noise), seed=seed, **kwargs)
        self.controller = CONTROLLERS[name]
        self.rng = np.random.default_rng(seed)

    def get_action(self, infos: dict[str, np.ndarray], **kwargs: Any) -> np.ndarray:
        state = np.asarray(infos[keys.STATE], np.float64)[:, -1]
        goal = np.asarray(infos[keys.GOAL_STATE], np.float64)[:, -1]
        action = self.controller(state, goal)
        if self.noise:
            action = action + self.noise * self.rng.standard_normal(action.shape)
        return np.clip(action, -1.0, 1.0).astype(np.float32)


class CheckpointNotFoundError(SWMError, FileNotFoundError):
    """A checkpoint or statistics file that does not exist."""


class ExpertPolicy(BasePolicy):
    """Upstream 0.1.1's DMControl expert: a Stable-Baselines3 SAC policy on normalized observations.

    - ``ckpt_path``: the SAC ``.zip``; ``vec_normalize_path``: the pickled ``VecNormalize`` whose
      ``obs_rms`` (mean, var) normalize observations as ``clip((obs - mean) / sqrt(var + 1e-8), -10, 10)``.
    - ``get_action(infos)`` reads ``infos["observation"][:, -1]`` (B, D) and returns ``(B, A)``
      float32 from ``model.predict`` (stochastic unless ``deterministic=True`` is passed), plus
      seeded Gaussian noise of std ``noise_std``, clipped to [-1, 1].

    The pickle is loaded with ``pickle``: load only files you trust.
    """

    def __init__(
        self,
        ckpt_path: str,
        vec_normalize_path: str,
        noise_std: float = 0.0,
        seed: int | None = None,
        device: str = "cpu",
        **kwargs: Any,
    ):
        for what, path in (("ckpt_path", ckpt_path), ("vec_normalize_path", vec_normalize_path)):
            if not os.path.isfile(str(path)):
                raise CheckpointNotFoundError(f"ExpertPolicy requires {what} to be an existing file, got {str(path)!r}")
        if not np.isfinite(noise_std) or noise_std < 0:
            raise ConfigError(f"ExpertPolicy requires noise_std >= 0, got {noise_std!r}")
        sb3 = require("stable_baselines3", purpose="the DMControl SAC experts (ExpertPolicy)")
        self.deterministic = bool(kwargs.pop("deterministic", False))
        super().__init__(**kwargs)
        self.type = "expert"
        self.model = sb3.SAC.load(str(ckpt_path), device=device)
        if seed is not None:
            self.model.set_random_seed(seed)
        with open(vec_normalize_path, "rb") as f:
            stats = pickle.load(f)  # noqa: S301 - a VecNormalize the user points at
        self.obs_mean = np.asarray(stats.obs_rms.mean, np.float64)
        self.obs_var = np.asarray(stats.obs_rms.var, np.float64)
        self.clip_obs, self.epsilon = 10.0, 1e-8
        self.noise_std = float(noise_std)
        self.rng = np.random.default_rng(seed)

    def normalize(self, obs: np.ndarray) -> np.ndarray:
        """Observations (B, D) as the SAC policy saw them in training."""
        z = (np.asarray(obs, np.float64) - self.obs_mean) / np.sqrt(self.obs_var + self.epsilon)
        return np.clip(z, -self.clip_obs, self.clip_obs)

    def get_action(self, info_dict: dict[str, np.ndarray], **kwargs: Any) -> np.ndarray:
        obs = np.asarray(info_dict["observation"])
        obs = obs[:, -1] if obs.ndim == 3 else obs
        action, _ = self.model.predict(self.normalize(obs), deterministic=self.deterministic)
        action = np.asarray(action, np.float64)
        if self.noise_std:
            action = action + self.noise_std * self.rng.standard_normal(action.shape)
        return np.clip(action, -1.0, 1.0).astype(np.float32)

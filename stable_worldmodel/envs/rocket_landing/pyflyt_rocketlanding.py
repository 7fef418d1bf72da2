"""``swm/PFRocketLanding-v0``: land PyFlyt's rocket on its pad (extra ``pyflyt``), with factors of variation.

Written from the behaviour of upstream's ``rocket_landing/pyflyt_rocketlanding.py`` (same id, module
and class names, observation, reward and success rule), on PyFlyt's ``Aviary`` and rocket model
(``PyFlyt.core``; pybullet physics at 240 Hz, the rocket's controls at 120 Hz):

- **Constructor**: ``RocketLandingEnv(sparse_reward=False, ceiling=250.0, max_displacement=200.0,
  max_duration_seconds=30.0, agent_hz=40, render_mode="rgb_array", render_size=(480, 480))``.
  ``agent_hz`` divides 120; an agent step is ``120 / agent_hz`` rocket control steps.
- **Action** ``Box(7)`` float64, PyFlyt's: finlet x, finlet y, finlet roll (``[-1, 1]``), ignition
  (``[0, 1]``, on above 0.5), throttle (``[0, 1]``: 39 % to 100 % of the booster's thrust once lit),
  booster gimbal x, y (``[-1, 1]``: +-5 degrees). Actions are clipped to the space.
- **Observation** ``Box(17)`` float64 (upstream's): position (3, world, m), velocity (3, world, m/s),
  attitude quaternion (4, w x y z), angular velocity (3, body frame, rad/s), fuel left (1, fraction
  of a full tank), pad position minus position (3).
- **Reward**: PyFlyt's (upstream's): a dense shaping term each control step (progress towards the
  pad, descent, deceleration near the ground, penalties on spin and tilt; off with
  ``sparse_reward``), ``5 - 0.3 |v_z|`` while touching the pad and ``+3`` on landing.
- **Ends**: landing (touching the pad with speed below 2 m/s, angular speed below 5 rad/s, tilt
  below 0.5 rad and the centre within 5 m of the pad's) is ``terminated`` with
  ``info["env_complete"]``. Touching the pad faster than 5 m/s or 10 rad/s, touching anything else,
  going below the ground (``info["fatal_collision"]``) or farther than ``max_displacement`` from the
  origin or above ``ceiling`` (``info["out_of_bounds"]``), and ``max_duration_seconds`` are
  ``truncated``: the swm tools count ``terminated`` episodes as successes.
- **Factors** (``variation_space``): upstream's ``rocket.{body,fin,leg,booster}_color``,
  ``pad.color``, ``environment.{sky_color, start_height_ratio, start_horizontal_offset,
  start_tilt}``; and ours: ``rocket.fuel_ratio`` (starting fuel, PyFlyt's 5 % by default),
  ``rocket.body_mass`` (kg, the hull without fuel and booster), ``pad.position``,
  ``environment.{ground_color, start_speed, gravity, wind}`` (``start_speed``: the downward speed
  at the start, PyFlyt's accelerated drop of 100 m/s by default; ``wind``: a uniform horizontal
  wind in m/s). Every factor keeps its default unless ``options["variation"]`` or
  ``["variation_values"]`` names it (as upstream, the defaults give the same start every episode).
- **Goal**: the rocket standing on the pad: ``goal_state`` is that state (pad position at the
  standing height, at rest, upright, the start's fuel), ``goal_proprio`` its first 14 numbers and
  ``goal`` its frame. ``eval_state(goal_state, state)`` is ``(success, distance)``: within 2 m of
  the goal laterally and 0.5 m vertically, slower than 2 m/s, tilted less than 0.5 rad; distance
  the position error in m.
- **Reset options**: ``variation`` / ``variation_values``; ``state`` (an observation: start at its
  position, velocity, attitude and angular velocity; its fuel when positive); ``goal_state`` (move the pad
  under its position).
- **Info**: upstream's ``out_of_bounds``, ``fatal_collision``, ``env_complete``; plus ``state``
  (the observation), ``proprio`` (its first 14 numbers), ``goal``, ``goal_state``,
  ``goal_proprio``, ``pad_contact``.
- **Rendering**: upstream's view, a camera riding with the rocket (3 m up and 1 m back in the
  rocket's frame, pitched 30 degrees, 90 degrees field of view) looking at it, drawn headless by
  pybullet's software renderer directly at ``render_size``; the flame shows while the booster is lit,
  the background takes ``environment.sky_color``.

Deliberate differences from upstream: the env is built on ``PyFlyt.core`` (upstream subclasses
PyFlyt's gym env) and never prints; landing is ``terminated`` and failures ``truncated`` (upstream:
the reverse, as PyFlyt); the reset options ``randomize_drop`` / ``accelerate_drop`` /
``starting_fuel_ratio`` are factors instead; no ``angle_representation`` (the observation always
holds a quaternion, as upstream's); PyFlyt's numba kernels run as plain Python when this module
imports PyFlyt first (the same results, as fast for one rocket, without a 10 s compilation).
"""

from __future__ import annotations

import contextlib
import os
import sys
from typing import Any

import gymnasium as gym
import numpy as np

from ... import keys, spaces
from ..._optional import require
from ...errors import ConfigError
from ..base import DatasetResetMixin, apply_variation_options, check_render_size
from ..base import rgb_factor as _rgb

__all__ = ["REST_HEIGHT", "RocketLandingEnv"]

_WHY = "swm/PFRocketLanding-v0"


def _flush_c_stdio() -> None:
    with contextlib.suppress(Exception):
        import ctypes

        ctypes.CDLL(None).fflush(None)


@contextlib.contextmanager
def _quiet_stdout():
    """Silence what pybullet's C code and PyFlyt print on importing and connecting (file descriptors 1
    and 2; Python exceptions still propagate)."""
    streams = []
    for stream in (sys.stdout, sys.stderr):
        try:
            streams.append((stream, stream.fileno()))
        except (AttributeError, OSError, ValueError):  # a replaced stream: leave its descriptor alone
            pass
    saved = []
    with open(os.devnull, "w") as null:
        for stream, fd in streams:
            stream.flush()
            saved.append((stream, fd, os.dup(fd)))
            os.dup2(null.fileno(), fd)
        try:
            yield
        finally:
            _flush_c_stdio()  # C's buffers are flushed at exit otherwise, after the descriptors are back
            for stream, fd, old in saved:
                stream.flush()
                os.dup2(old, fd)
                os.close(old)


def _import_pyflyt():
    """``PyFlyt.core.aviary`` and ``pybullet``; PyFlyt's numba kernels stay plain Python when this is
    the first import of PyFlyt (numba would spend ~10 s compiling them, for no speed-up here)."""
    numba = require("numba", extra="pyflyt", purpose=_WHY)
    fresh = "PyFlyt.core" not in sys.modules
    before = numba.config.DISABLE_JIT
    if fresh:
        numba.config.DISABLE_JIT = True  # read by numba's decorators when PyFlyt's modules define their kernels
    try:
        aviary = require("PyFlyt.core.aviary", extra="pyflyt", purpose=_WHY)
    finally:
        numba.config.DISABLE_JIT = before
    return aviary, require("pybullet", extra="pyflyt", purpose=_WHY)


with _quiet_stdout():  # pybullet prints its build time on import
    _aviary, p = _import_pyflyt()
Aviary = _aviary.Aviary

REST_HEIGHT = 2.576  # m: the rocket's centre when it stands on the pad
PAD_HEIGHT = 0.1  # m: the pad's centre
PAD_RADIUS = 2.0
OBS_DIM = 17
PROPRIO_DIM = 14
# link indices of PyFlyt's rocket.urdf
FUELTANK, BOOSTER, FINS, LEGS, FLAME = 0, 1, (2, 3, 4, 5), (6, 7, 8), 9
FLAME_ON = (1.0, 0.3, 0.3, 0.8)
FLAME_OFF = (1.0, 0.3, 0.3, 0.0)
# the tracking camera (PyFlyt's rocket camera as upstream renders it)
CAMERA_OFFSET = np.array([-1.0, 0.0, 3.0])
CAMERA_PITCH = np.deg2rad(30.0)
CAMERA_FOV = 90.0
# landing and crash thresholds (upstream's)
LAND_SPEED, LAND_SPIN, LAND_TILT, LAND_LATERAL = 2.0, 5.0, 0.5, 5.0
CRASH_SPEED, CRASH_SPIN = 5.0, 10.0


def _box(low, high, init) -> spaces.Box:
    init = np.asarray(init, np.float32)
    return spaces.Box(
        np.broadcast_to(np.float32(low), init.shape).copy() if init.shape else np.float32(low),
        np.broadcast_to(np.float32(high), init.shape).copy() if init.shape else np.float32(high),
        shape=init.shape,
        dtype=np.float32,
        init_value=init,
    )


def _quat_wxyz(q_xyzw) -> np.ndarray:
    return np.array([q_xyzw[3], q_xyzw[0], q_xyzw[1], q_xyzw[2]], np.float64)


def tilt_of(quat_wxyz: np.ndarray) -> np.ndarray:
    """Angle (rad) between the body's z axis and the vertical, for quaternions ``(..., 4)`` (w x y z)."""
    q = np.asarray(quat_wxyz, np.float64)
    x, y = q[..., 1], q[..., 2]
    cos = np.clip(1.0 - 2.0 * (x * x + y * y), -1.0, 1.0)  # the world z of the body z axis
    return np.arccos(cos)


class RocketLandingEnv(DatasetResetMixin, gym.Env):
    """PyFlyt's rocket landing with factors of variation (see the module docstring)."""

    metadata = {"render_modes": ["rgb_array"], "render_fps": 40}

    def __init__(
        self,
        sparse_reward: bool = False,
        ceiling: float = 250.0,
        max_displacement: float = 200.0,
        max_duration_seconds: float = 30.0,
        agent_hz: int = 40,
        render_mode: str | None = "rgb_array",
        render_size: tuple[int, int] = (480, 480),
    ):
        owner = "RocketLandingEnv"
        if render_mode not in (None, "rgb_array"):
            raise ConfigError(f"{owner} requires render_mode 'rgb_array' or None, got {render_mode!r}")
        if isinstance(agent_hz, bool) or not isinstance(agent_hz, (int, np.integer)) or agent_hz < 1 or 120 % agent_hz:
            raise ConfigError(
                f"{owner} requires agent_hz to divide 120 (1, 2, 3, 4, 5, 6, 8, 10, 12, 15, 20, 24, 30, 40, 60, "
                f"120), got {agent_hz!r}"
            )
        for name, value in (
            ("ceiling", ceiling),
            ("max_displacement", max_displacement),
            ("max_duration_seconds", max_duration_seconds),
        ):
            if isinstance(value, bool) or not isinstance(value, (int, float, np.number)) or not value > 0:
                raise ConfigError(f"{owner} requires {name} to be a positive number, got {value!r}")
        self.render_mode = render_mode
        self.render_size = check_render_size(owner, render_size)
        self.sparse_reward = bool(sparse_reward)
        self.ceiling, self.max_displacement = float(ceiling), float(max_displacement)
        self.agent_hz = int(agent_hz)
        self.env_step_ratio = 120 // self.agent_hz
        self.max_steps = int(self.agent_hz * float(max_duration_seconds))
        self.metadata = {**self.metadata, "render_fps": self.agent_hz}
        self.env_name = "PFRocketLanding"
        self.observation_space = gym.spaces.Box(-np.inf, np.inf, (OBS_DIM,), np.float64)
        self.observation_space.low[13], self.observation_space.high[13] = 0.0, 1.0
        self.action_space = gym.spaces.Box(
            np.array([-1.0, -1.0, -1.0, 0.0, 0.0, -1.0, -1.0]), np.array([1.0] * 7), dtype=np.float64
        )
        self.variation_space = self._build_variation_space()
        pyflyt_dir = os.path.dirname(os.path.realpath(_aviary.__file__))
        self._pad_urdf = os.path.join(pyflyt_dir, "..", "models", "landing_pad.urdf")
        self.aviary: Any = None
        self.state = np.zeros(OBS_DIM)
        self._goal_state = np.zeros(OBS_DIM)
        self._goal_img: np.ndarray | None = None
        self._pad = np.zeros(3)
        self._view: tuple[Any, Any] | None = None

    # -- variation space ------------------------------------------------------------------------
    def _build_variation_space(self) -> spaces.Dict:
        return spaces.Dict(
            {
                "rocket": spaces.Dict(
                    {
                        "body_color": _rgb([255, 204, 0]),
                        "fin_color": _rgb([51, 51, 51]),
                        "leg_color": _rgb([0, 0, 0]),
                        "booster_color": _rgb([51, 51, 51]),
                        "fuel_ratio": _box(0.03, 0.2, 0.05),
                        "body_mass": _box(70.0, 115.0, 91.0),
                    },
                    sampling_order=["body_color", "fin_color", "leg_color", "booster_color", "fuel_ratio", "body_mass"],
                ),
                "pad": spaces.Dict(
                    {"color": _rgb([200, 200, 200]), "position": _box(-20.0, 20.0, [0.0, 0.0])},
                    sampling_order=["color", "position"],
                ),
                "environment": spaces.Dict(
                    {
                        "sky_color": _rgb([135, 206, 235]),
                        "ground_color": _rgb([255, 255, 255]),
                        "start_height_ratio": _box(0.7, 0.95, 0.9),
                        "start_horizontal_offset": _box(-20.0, 20.0, [0.0, 0.0]),
                        "start_tilt": _box(-0.2, 0.2, [0.0, 0.0]),
                        "start_speed": _box(0.0, 100.0, 100.0),
                        "gravity": _box(7.0, 12.0, 9.81),
                        "wind": _box(-5.0, 5.0, [0.0, 0.0]),
                    },
                    sampling_order=[
                        "sky_color",
                        "ground_color",
                        "start_height_ratio",
                        "start_horizontal_offset",
                        "start_tilt",
                        "start_speed",
                        "gravity",
                        "wind",
                    ],
                ),
            },
            sampling_order=["environment", "rocket", "pad"],
        )

    def _factor(self, name: str) -> np.ndarray:
        return np.asarray(self.variation_space[name].value, np.float64)

    # -- gym API ----------------------------------------------------------------------------------
    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None):
        super().reset(seed=seed)
        options = dict(options or {})
        apply_variation_options(self.variation_space, options, self.np_random)
        start = self._start_from(options.get(keys.STATE))
        pad = self._factor("pad.position")
        if options.get(keys.GOAL_STATE) is not None:
            goal = np.asarray(options[keys.GOAL_STATE], np.float64).reshape(-1)
            if goal.shape[0] < 2:
                raise ConfigError(
                    f"RocketLandingEnv requires reset option 'goal_state' with at least 2 numbers, got {goal!r}"
                )
            pad = goal[:2]
        self._pad = np.array([pad[0], pad[1], 0.0])
        self._build_world(start)
        self.step_count = 0
        self.termination = self.truncation = False
        self.info: dict[str, Any] = {"out_of_bounds": False, "fatal_collision": False, "env_complete": False}
        self.action = np.zeros(7)
        self._pad_contact = 0.0
        for _ in range(10):  # let the contacts settle, as PyFlyt
            self.aviary.step()
        self._update_state()
        self._previous = self._tracked()
        self._goal_state = self._landed_state()
        self._goal_img = None
        return self.state.copy(), self._info()

    def step(self, action):
        action = np.clip(np.asarray(action, np.float64).reshape(7), self.action_space.low, self.action_space.high)
        self.action = action
        self.reward = 0.0
        self.aviary.set_setpoint(0, action)
        for _ in range(self.env_step_ratio):
            if self.termination or self.truncation:
                break
            self.aviary.step()
            self._update_state()
            self._term_trunc_reward()
        self.step_count += 1
        self._show_flame(bool(self.aviary.aux_state(0)[4] > 0.5))
        return self.state.copy(), float(self.reward), bool(self.termination), bool(self.truncation), self._info()

    def render(self) -> np.ndarray:
        """The rocket's tracking view, ``(*render_size, 3)`` uint8."""
        return self._draw()

    def set_render_size(self, size: tuple[int, int]) -> None:
        """Draw frames and the goal image at ``size`` = (H, W) from now on."""
        size = check_render_size("RocketLandingEnv", size)
        if size != self.render_size:
            self.render_size = size
            self._goal_img = None

    def eval_state(self, goal_state: np.ndarray, cur_state: np.ndarray) -> tuple[bool, float]:
        """``(success, distance)``: ``cur_state`` within 2 m laterally and 0.5 m vertically of
        ``goal_state``'s position, slower than 2 m/s and tilted less than 0.5 rad; distance in m."""
        g = np.asarray(goal_state, np.float64).reshape(-1)
        c = np.asarray(cur_state, np.float64).reshape(-1)
        if g.shape[0] < 3 or c.shape[0] < 10:
            raise ConfigError(
                "RocketLandingEnv.eval_state requires a goal state of at least 3 numbers and a state of at least 10 "
                f"(position, velocity, quaternion), got {g.shape[0]} and {c.shape[0]}"
            )
        err = c[:3] - g[:3]
        ok = (
            np.linalg.norm(err[:2]) < PAD_RADIUS
            and abs(err[2]) < 0.5
            and np.linalg.norm(c[3:6]) < LAND_SPEED
            and tilt_of(c[6:10]) < LAND_TILT
        )
        return bool(ok), float(np.linalg.norm(err))

    def close(self) -> None:
        if self.aviary is not None:
            with contextlib.suppress(Exception):
                self.aviary.disconnect()
            self.aviary = None

    # -- construction -----------------------------------------------------------------------------
    def _start_from(self, state) -> dict[str, np.ndarray]:
        """Start position, attitude (Euler), velocity (world), angular velocity (body) and fuel."""
        if state is not None:
            s = np.asarray(state, np.float64).reshape(-1)
            if s.shape[0] < 13:
                raise ConfigError(
                    "RocketLandingEnv requires reset option 'state' with at least 13 numbers (position, velocity, "
                    f"quaternion, angular velocity), got {s.shape[0]}"
                )
            q = s[6:10] / max(np.linalg.norm(s[6:10]), 1e-9)
            euler = np.array(p.getEulerFromQuaternion([q[1], q[2], q[3], q[0]]))
            fuel = s[13] if s.shape[0] > 13 and s[13] > 0 else float(self._factor("rocket.fuel_ratio"))
            return {"pos": s[:3], "orn": euler, "vel": s[3:6], "ang_vel": s[10:13], "fuel": float(fuel)}
        off = self._factor("environment.start_horizontal_offset")
        tilt = self._factor("environment.start_tilt")
        height = self.ceiling * float(self._factor("environment.start_height_ratio"))
        return {
            "pos": np.array([off[0], off[1], height]),
            "orn": np.array([tilt[0], tilt[1], 0.0]),
            "vel": np.array([0.0, 0.0, -float(self._factor("environment.start_speed"))]),
            "ang_vel": np.zeros(3),
            "fuel": float(self._factor("rocket.fuel_ratio")),
        }

    def _build_world(self, start: dict[str, np.ndarray]) -> None:
        options = {"starting_fuel_ratio": start["fuel"], "use_camera": False}
        if self.aviary is None:
            with _quiet_stdout():
                self.aviary = Aviary(
                    start_pos=start["pos"][None],
                    start_orn=start["orn"][None],
                    drone_type="rocket",
                    drone_options=options,
                    np_random=self.np_random,
                )
        else:  # the same connection, a fresh world
            av = self.aviary
            av.start_pos, av.start_orn, av.np_random = start["pos"][None], start["orn"][None], self.np_random
            av.drone_options = [options]
            av.reset()
        av = self.aviary
        g = float(self._factor("environment.gravity"))
        av.setGravity(0.0, 0.0, -g)
        wind = np.array([*self._factor("environment.wind"), 0.0])
        if np.any(wind != 0.0):
            av.register_wind_field_function(lambda t, pos: np.broadcast_to(wind, np.shape(pos)).astype(np.float64))
        else:
            av.wind_field = None
        rocket = av.drones[0].Id
        self._pad_id = av.loadURDF(
            self._pad_urdf, basePosition=[self._pad[0], self._pad[1], PAD_HEIGHT], useFixedBase=True
        )
        av.register_all_new_bodies()
        av.set_mode(0)
        av.changeDynamics(rocket, -1, mass=float(self._factor("rocket.body_mass")))
        av.resetBaseVelocity(rocket, start["vel"], start["ang_vel"])
        self._apply_colors(rocket)

    def _apply_colors(self, rocket: int) -> None:
        av = self.aviary

        def rgba(name: str) -> list[float]:
            return [*(self._factor(name) / 255.0).tolist(), 1.0]

        av.changeVisualShape(rocket, -1, rgbaColor=rgba("rocket.body_color"))
        av.changeVisualShape(rocket, BOOSTER, rgbaColor=rgba("rocket.booster_color"))
        for link in FINS:
            av.changeVisualShape(rocket, link, rgbaColor=rgba("rocket.fin_color"))
        for link in LEGS:
            av.changeVisualShape(rocket, link, rgbaColor=rgba("rocket.leg_color"))
        av.changeVisualShape(self._pad_id, -1, rgbaColor=rgba("pad.color"))
        av.changeVisualShape(av.planeId, -1, rgbaColor=rgba("environment.ground_color"))
        self._flame = None
        self._show_flame(False)

    def _show_flame(self, on: bool) -> None:
        if self.render_mode is not None and on != self._flame:
            self.aviary.changeVisualShape(self.aviary.drones[0].Id, FLAME, rgbaColor=FLAME_ON if on else FLAME_OFF)
            self._flame = on

    # -- state, reward, ends ----------------------------------------------------------------------
    def _update_state(self) -> None:
        av = self.aviary
        rocket = av.drones[0].Id
        pos, quat = av.getBasePositionAndOrientation(rocket)
        vel, _ = av.getBaseVelocity(rocket)
        raw = av.state(0)  # body angular velocity, Euler angles, body velocity, position
        aux = av.aux_state(0)  # finlets (4), ignition, fuel, throttle, gimbal (2)
        self._euler = np.asarray(raw[1], np.float64)
        self._spin = np.asarray(raw[0], np.float64)
        self.state = np.concatenate(
            [np.asarray(pos), np.asarray(vel), _quat_wxyz(quat), self._spin, [aux[5]], self._pad - np.asarray(pos)]
        ).astype(np.float64)

    def _tracked(self) -> dict[str, np.ndarray]:
        return {"pos": self.state[:3].copy(), "vel": self.state[3:6].copy(), "spin": self._spin.copy()}

    def _term_trunc_reward(self) -> None:
        av = self.aviary
        rocket = av.drones[0].Id
        prev, now = self._previous, self._tracked()
        self._previous = now
        if self.step_count > self.max_steps:
            self.truncation = True
        contacts = av.contact_array.copy()
        contacts[rocket, self._pad_id] = contacts[self._pad_id, rocket] = False
        pos, vel = now["pos"], now["vel"]
        if np.any(contacts) or pos[2] < 0.0:
            self.info["fatal_collision"] = True
            self.truncation = True
        if np.linalg.norm(pos[:2]) > self.max_displacement or pos[2] > self.ceiling:
            self.info["out_of_bounds"] = True
            self.truncation = True
        rel_prev, rel_now = prev["pos"][:2] - self._pad[:2], pos[:2] - self._pad[:2]
        if not self.sparse_reward:
            lateral_progress = float(np.linalg.norm(rel_prev) - np.linalg.norm(rel_now))
            vertical_progress = float(prev["pos"][2] - pos[2])
            lateral_distance = float(np.linalg.norm(rel_now)) + 0.1
            deceleration = (
                (vel[2] - prev["vel"][2] + 1.0) / np.exp(min(pos[2], 700.0)) * (1.0 if vel[2] < 0.0 else -1.0)
            )
            self.reward += (
                -0.3
                + 0.3 / lateral_distance
                + 10.0 * lateral_progress
                + 0.2 * vertical_progress
                + 4.0 * deceleration
                - abs(self._spin[2])
                - float(np.linalg.norm(self._euler[:2]))
            )
        if not av.contact_array[rocket, self._pad_id]:
            self._pad_contact = 0.0
            return
        self._pad_contact = 1.0
        self.reward += 5.0 - 0.3 * abs(vel[2])
        speed, spin = float(np.linalg.norm(vel)), float(np.linalg.norm(self._spin))
        if spin > CRASH_SPIN or speed > CRASH_SPEED:
            self.info["fatal_collision"] = True
            self.truncation = True
            return
        if (
            spin < LAND_SPIN
            and speed < LAND_SPEED
            and float(tilt_of(self.state[6:10])) < LAND_TILT
            and float(np.linalg.norm(rel_now)) < LAND_LATERAL
            and not self.truncation
        ):
            self.info["env_complete"] = True
            self.termination = True
            self.reward += 3.0

    def _landed_state(self) -> np.ndarray:
        goal = np.zeros(OBS_DIM)
        goal[:3] = (self._pad[0], self._pad[1], REST_HEIGHT)
        goal[6] = 1.0
        goal[13] = self.state[13]
        goal[14:17] = self._pad - goal[:3]
        return goal

    def _info(self) -> dict[str, Any]:
        if self._goal_img is None:
            self._goal_img = self._draw_landed()
        return {
            **self.info,
            "env_name": self.env_name,
            "pad_contact": self._pad_contact,
            keys.STATE: self.state.copy(),
            keys.PROPRIO: self.state[:PROPRIO_DIM].copy(),
            keys.GOAL: self._goal_img.copy(),
            keys.GOAL_STATE: self._goal_state.copy(),
            keys.GOAL_PROPRIO: self._goal_state[:PROPRIO_DIM].copy(),
        }

    # -- rendering ------------------------------------------------------------------------------
    def _camera(self, pos, quat_xyzw) -> tuple[Any, Any]:
        av = self.aviary
        rot = np.array(av.getMatrixFromQuaternion(quat_xyzw)).reshape(3, 3)
        eye = np.asarray(pos) + rot @ CAMERA_OFFSET
        euler = np.array(av.getEulerFromQuaternion(quat_xyzw))
        euler[1] += CAMERA_PITCH
        up = np.array(av.getMatrixFromQuaternion(av.getQuaternionFromEuler(euler))).reshape(3, 3) @ [0.0, 0.0, 1.0]
        h, w = self.render_size
        view = av.computeViewMatrix(cameraEyePosition=eye, cameraTargetPosition=pos, cameraUpVector=up)
        proj = av.computeProjectionMatrixFOV(fov=CAMERA_FOV, aspect=w / h, nearVal=0.1, farVal=255.0)
        return view, proj

    def _draw(self, pose: tuple[Any, Any] | None = None) -> np.ndarray:
        av = self.aviary
        h, w = self.render_size
        if av is None:
            img = np.empty((h, w, 3), np.uint8)
            img[:] = self._factor("environment.sky_color").astype(np.uint8)
            return img
        pos, quat = pose if pose is not None else av.getBasePositionAndOrientation(av.drones[0].Id)
        view, proj = self._camera(pos, quat)
        _, _, rgba, _, seg = av.getCameraImage(
            width=w, height=h, viewMatrix=view, projectionMatrix=proj, renderer=p.ER_TINY_RENDERER
        )
        img = np.asarray(rgba, np.uint8).reshape(h, w, 4)[..., :3].copy()
        sky = np.asarray(seg).reshape(h, w) < 0
        img[sky] = self._factor("environment.sky_color").astype(np.uint8)
        return img

    def _draw_landed(self) -> np.ndarray:
        """The frame of the rocket standing upright on the pad, engine off."""
        av = self.aviary
        rocket = av.drones[0].Id
        saved = av.saveState()
        flame = self._flame
        self._show_flame(False)
        pose = ([self._pad[0], self._pad[1], REST_HEIGHT], [0.0, 0.0, 0.0, 1.0])
        av.resetBasePositionAndOrientation(rocket, *pose)
        img = self._draw(pose)
        av.restoreState(stateId=saved)
        av.removeState(saved)
        self._show_flame(bool(flame))
        return img

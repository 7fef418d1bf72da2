"""``swm/Fetch<Task>[Dense|Dict]-v3``: upstream's Gymnasium-Robotics Fetch envs, with factors of variation.

Tasks: ``Reach`` (gripper to a point), ``Push`` (block to a point on the table, gripper closed),
``Slide`` (puck slid to a point beyond reach, gripper closed), ``PickAndPlace`` (block to a
point on the table or in the air). Same ids and meaning as upstream's main, whose envs wrap
Gymnasium-Robotics' ``Fetch<Task>[Dense]-v4``:

- ``swm/Fetch<Task>-v3``: sparse reward ``-1`` unless the achieved goal is within 0.05 of the
  desired goal (then ``0``); observation = Gymnasium-Robotics' ``observation`` followed by the
  ``desired_goal``, one float32 vector (13 numbers for Reach, 28 with an object).
- ``swm/Fetch<Task>Dense-v3``: the same with reward ``-distance``.
- ``swm/Fetch<Task>Dict-v3``: sparse reward, Gymnasium-Robotics' Dict observation
  (``observation``, ``achieved_goal``, ``desired_goal``, float64), as goal-conditioned
  algorithms (hindsight relabelling) expect, plus ``state`` (the flat vector above, which the
  other ids give in the info: World merges observation and info, and refuses a key in both).

Action ``(dx, dy, dz, grip)`` in ``[-1, 1]`` (see :mod:`._sim`); 50 steps per episode (the
registry's time limit, as Gymnasium-Robotics); never terminated (a continuing task, as upstream).

Info (reset and step): upstream's ``env_name`` (the Gymnasium-Robotics id), ``is_success``
(1.0 when the achieved goal is within 0.05 of the desired goal, Gymnasium-Robotics' rule), ``state``
(the flat observation: observation then desired goal), ``proprio`` (the observation);
plus ``goal`` (the goal scene rendered like the frames), ``goal_state`` and ``goal_proprio``
(the state and observation of the goal scene, whose achieved goal is the desired goal). The goal
scene: Reach, the gripper on the goal; Push and Slide, the object on the goal (the gripper where it
starts); Pick-and-place, the object on the goal, held by the gripper when the goal is in the air.

Factors (``variation_space``, upstream's names, ranges and defaults; Box spaces of float64):

==========================  =======  ====================================================
``table.color``             (3,)     RGB in [0, 1] of the table
``object.color``            (3,)     RGB of the block / puck (not in Reach: no object)
``background.color``        (3,)     RGB of the floor and the sky
``light.intensity``         (1,)     diffuse intensity of the light
``camera.angle_delta``      (1, 2)   degrees added to the camera's azimuth and elevation
``agent.start_position``    (2,)     gripper start x, y
``goal.start_position``     (3,)     the desired goal
``block.start_position``    (2,)     object start x, y (object tasks)
``block.angle``             (1,)     object start yaw (object tasks)
``object.size``             (1,)     half-width of the block / radius of the puck (ours)
``object.mass``             (1,)     mass of the object, kg (ours)
``object.friction``         (1,)     sliding friction of the object and the table geoms (ours)
==========================  =======  ====================================================

As upstream, every reset without ``options["variation"]`` resamples the visual factors
(:data:`DEFAULT_VARIATIONS`: table, object and background colors, light, camera), and the four
position factors act only when named in ``options["variation"]`` (or ``["all"]``) or set in
``options["variation_values"]``; otherwise the gripper starts where Gymnasium-Robotics puts it,
and the object and goal are drawn from the reset seed by Gymnasium-Robotics' rules (so with the
default factors an episode is Gymnasium-Robotics' episode of the same seed, to float32 precision).
Size, mass and friction keep Gymnasium-Robotics' values unless resampled or set (MuJoCo takes the
larger friction of two touching geoms, hence both geoms). An object placed within 0.07 of the
gripper's start (``block.start_position``) starts with the gripper lifted 0.04 above it.

Reset options: ``state`` (a flat observation, as ``info["state"]``) starts from its gripper
position, finger opening and object pose (velocities zero) with its desired goal;
``goal_state`` (a state, whose achieved goal is used, or three numbers) sets the goal.
``eval_state(goal_state, state)`` is the success rule on those.

Rendering: :class:`~stable_worldmodel.envs.mujoco_render.MjRenderer` at ``render_size`` (``224 x
224``; ``resolution`` as upstream), from Gymnasium-Robotics' Fetch view (distance 2.5, azimuth
132, elevation -14, looking at (1.3, 0.75, 0.55); the frames equal its free camera's), headless;
``render_quality`` as the other MuJoCo envs (``"low"`` / ``"medium"`` draw decimated meshes, as
OGBench's arm, when ``fast-simplification`` is installed). The envs of one task share a GL context
per frame size, quality and thread (:class:`SharedRenderer`: making one costs ~0.5 s on a CPU) for
their first :data:`SHARED_FRAMES` frames, then draw with one of their own; up to
:data:`IDLE_RENDERERS` shared ones are kept after their envs close.

Deliberate differences from upstream's main (whose wrapper cannot be built under mujoco 3.17, see
:mod:`._sim`): the simulation is ours (Gymnasium-Robotics' models and rules); ``camera.angle_delta``
turns the camera (upstream samples it and uses it nowhere); ``agent.start_position`` moves the
gripper (upstream only shifts where the object and goal are later drawn, and keeps the shift
across resets); Reach has no ``object.color``; Slide's position factors have ranges around its
own start and goal regions (upstream uses Push's for every task), Reach's goal box spans heights
0.42 to 0.69 and Pick-and-place's up to 0.45 above the table (upstream: on the table); the Dict
ids carry ``state`` in the observation (see above); ``goal_state`` is the goal
scene's state (upstream: the desired goal, 3 numbers, which ``eval_state`` and the
``goal_state`` option also take); the object's size, mass and friction are added factors; frames are
drawn at the requested size (upstream draws 480 x 480 and resizes with OpenCV).
"""

from __future__ import annotations

import re
import threading
import weakref
from collections.abc import Mapping
from typing import Any

from ...errors import ConfigError


def setup_robotics() -> str | None:
    """Check the ``robotics`` extra and choose the GL backend before ``mujoco`` is imported
    (:func:`~stable_worldmodel.envs.mujoco_render.setup_gl` for this extra: these envs need neither
    dm_control nor ogbench)."""
    from ..mujoco_render import setup_gl

    return setup_gl("robotics", "the Fetch environments")


setup_robotics()

import gymnasium as gym  # noqa: E402
import mujoco  # noqa: E402
import numpy as np  # noqa: E402

from ... import keys, spaces  # noqa: E402
from ...errors import unknown_name  # noqa: E402
from ..base import DatasetResetMixin, check_render_size, checked_reset_options, flatten_values  # noqa: E402
from ..mujoco_render import MjRenderer, check_render_quality  # noqa: E402
from . import _sim  # noqa: E402
from ._sim import CAMERA, DISTANCE_THRESHOLD, TASKS, FetchSim, euler2quat  # noqa: E402

IMG_SIZE = 224
ENV_ID = re.compile(r"^Fetch(Reach|Push|Slide|PickAndPlace)(Dense)?-v4$")
ENV_IDS = [f"Fetch{t}{d}-v4" for t in TASKS for d in ("", "Dense")]
#: upstream's: the factors every reset resamples unless ``options["variation"]`` is given (Reach: no object)
DEFAULT_VARIATIONS = ("table.color", "object.color", "light.intensity", "background.color", "camera.angle_delta")
#: what object.size scales: the block's half-width, or the puck's radius (its half-height follows)
DEFAULT_SIZE = 0.025
PUCK_HEIGHT_RATIO = 0.8
#: an object placed (by block.start_position) within CLEARANCE (xy) of the gripper start lifts the gripper
#: to CLEARANCE_HEIGHT above the object's top (the fingers reach 0.019 below the grip point)
CLEARANCE, CLEARANCE_HEIGHT = 0.07, 0.04
FINGER_INNER = 0.00075  # a finger's inner face is this far from the centre line at opening 0 (measured)
#: per task: gripper start box, goal box (low, high), object start box (Push's for the others but Slide)
_UPSTREAM_AGENT = ((1.25, 0.6), (1.45, 0.9))
_UPSTREAM_BLOCK = ((1.15, 0.6), (1.45, 0.9))
_BOXES = {
    "Reach": {"agent": _UPSTREAM_AGENT, "goal": ((1.15, 0.6, 0.42), (1.45, 0.9, 0.69)), "goal_init": (1.3, 0.74, 0.55)},
    "Push": {"agent": _UPSTREAM_AGENT, "goal": ((1.15, 0.6, 0.0), (1.45, 0.9, 0.0)), "goal_init": (1.3, 0.74, 0.0)},
    "PickAndPlace": {
        "agent": _UPSTREAM_AGENT,
        "goal": ((1.15, 0.6, 0.0), (1.45, 0.9, 0.45)),
        "goal_init": (1.3, 0.74, 0.0),
    },
    "Slide": {
        "agent": ((0.92, 0.6), (1.12, 0.9)),
        "goal": ((1.11, 0.45, 0.0), (1.71, 1.05, 0.0)),
        "goal_init": (1.41, 0.75, 0.0),
        "block": ((1.06, 0.65), (1.16, 0.85)),
        "block_init": (1.11, 0.75),
    },
}
_FRICTION = {"Slide": (0.1, 0.05, 0.2)}  # default, low, high (others: 1.0 in [0.5, 1.5])


def _box(low, high, init) -> spaces.Box:
    return spaces.Box(
        low=np.asarray(low, np.float64),
        high=np.asarray(high, np.float64),
        dtype=np.float64,
        init_value=np.asarray(init, np.float64),
    )


def build_variation_space(task: str, gripper_xy: np.ndarray, height: float) -> spaces.Dict:
    """The factors of ``task`` (see the module docstring); ``gripper_xy`` is the gripper's start,
    ``height`` the object's resting height (the goal height of the table tasks)."""
    has_object = TASKS[task].has_object
    b = _BOXES[task]
    lift = np.array([0.0, 0.0, height])
    goal_low, goal_high = np.add(b["goal"][0], lift), np.add(b["goal"][1], lift)
    if not has_object:
        goal_low, goal_high = np.asarray(b["goal"][0]), np.asarray(b["goal"][1])
    entries: dict[str, spaces.Dict] = {
        "table": spaces.Dict({"color": _box([0.0] * 3, [1.0] * 3, [0.3, 0.3, 0.3])}),
    }
    if has_object:
        friction, f_low, f_high = _FRICTION.get(task, (1.0, 0.5, 1.5))
        entries["object"] = spaces.Dict(
            {
                "color": _box([0.0] * 3, [1.0] * 3, [0.8, 0.1, 0.1]),
                "size": _box([0.018], [0.035], [DEFAULT_SIZE]),
                "mass": _box([0.5], [4.0], [2.0]),
                "friction": _box([f_low], [f_high], [friction]),
            }
        )
    entries["background"] = spaces.Dict({"color": _box([0.0] * 3, [1.0] * 3, [0.1, 0.1, 0.1])})
    entries["light"] = spaces.Dict({"intensity": _box([0.0], [1.0], [0.7])})
    entries["camera"] = spaces.Dict({"angle_delta": _box([[-10.0, -10.0]], [[10.0, 10.0]], [[0.0, 0.0]])})
    entries["agent"] = spaces.Dict({"start_position": _box(*b["agent"], np.round(gripper_xy, 4))})
    entries["goal"] = spaces.Dict(
        {"start_position": _box(goal_low, goal_high, np.add(b["goal_init"], lift if has_object else 0.0))}
    )
    if has_object:
        block = b.get("block", _UPSTREAM_BLOCK)
        entries["block"] = spaces.Dict(
            {
                "start_position": _box(*block, b.get("block_init", (1.3, 0.74))),
                "angle": _box([-np.pi], [np.pi], [0.0]),
            }
        )
    return spaces.Dict(entries, sampling_order=list(entries))


class FetchEnv(DatasetResetMixin, gym.Env):
    """One Fetch task (see the module docstring); ``env_id`` is the Gymnasium-Robotics id, as upstream."""

    metadata = {"render_modes": ["rgb_array"], "render_fps": 25}

    def __init__(
        self,
        env_id: str = "FetchReach-v4",
        init_value: Mapping[str, Any] | None = None,
        resolution: int | tuple[int, int] = IMG_SIZE,
        render_mode: str | None = "rgb_array",
        flatten: bool = True,
        render_quality: str = "medium",
    ):
        owner = type(self).__name__
        match = ENV_ID.match(env_id) if isinstance(env_id, str) else None
        if match is None:
            raise unknown_name(f"{owner} env_id", str(env_id), ENV_IDS)
        if render_mode not in (None, "rgb_array"):
            raise ConfigError(f"{owner} requires render_mode 'rgb_array' or None, got {render_mode!r}")
        if not isinstance(flatten, (bool, np.bool_)):
            raise ConfigError(f"{owner} requires flatten to be True or False, got {flatten!r}")
        self.render_quality = check_render_quality(owner, render_quality)
        size = (resolution, resolution) if isinstance(resolution, (int, np.integer)) else resolution
        self.render_size = check_render_size(owner, size)
        self.env_name, self.task = env_id, match.group(1)
        self.reward_type = "dense" if match.group(2) else "sparse"
        self.render_mode, self.flatten = render_mode, bool(flatten)
        self._sim = sim = FetchSim(self.task)
        self._init_model_ids()
        self.variation_space = build_variation_space(self.task, sim.initial_gripper_xpos[:2], sim.height_offset)
        default = self.variation_space.value.get("object", {})
        # the size, mass, friction the model holds (Gymnasium-Robotics': written only when a value differs)
        self._physical = (
            tuple(float(np.asarray(default[k]).reshape(-1)[0]) for k in ("size", "mass", "friction"))
            if default
            else None
        )
        self._lift = 0.0  # how much higher the object's centre rests than with the default size
        if init_value is not None:
            self.variation_space.set_init_value(init_value)
        self.default_variations = tuple(v for v in DEFAULT_VARIATIONS if v in self.variation_space.names())
        obs, _ = sim.observation()
        self.obs_dim = obs.shape[0]
        self.state_dim = self.obs_dim + 3
        self._achieved = slice(3, 6) if sim.spec.has_object else slice(0, 3)
        self.action_space = gym.spaces.Box(-1.0, 1.0, (4,), np.float32)
        if self.flatten:
            self.observation_space = gym.spaces.Box(-np.inf, np.inf, (self.state_dim,), np.float32)
        else:
            goal_box = gym.spaces.Box(-np.inf, np.inf, (3,), np.float64)
            self.observation_space = gym.spaces.Dict(
                {
                    "observation": gym.spaces.Box(-np.inf, np.inf, (self.obs_dim,), np.float64),
                    "achieved_goal": goal_box,
                    "desired_goal": goal_box,
                    keys.STATE: gym.spaces.Box(-np.inf, np.inf, (self.state_dim,), np.float32),
                }
            )
        self._goal_data = mujoco.MjData(sim.model)
        self._goal = np.zeros(3)
        self._goal_obs = np.zeros(self.obs_dim)
        self._goal_image: np.ndarray | None = None
        self._render_keys: set[tuple] = set()  # the shared renderers this env has drawn with
        self._frames = 0  # frames drawn (goal images included)

    def _init_model_ids(self) -> None:
        m = self._sim.model
        self._mat = {name: m.material(name).id for name in ("floor_mat", "table_mat", "block_mat", "puck_mat")}
        self._light = m.light("light0").id
        self._camera = m.camera(CAMERA).id
        self._table_geoms = [g for g in range(m.ngeom) if m.geom_bodyid[g] == m.body("table0").id]
        skies = [t for t in range(m.ntex) if int(m.tex_type[t]) == int(mujoco.mjtTexture.mjTEXTURE_SKYBOX)]
        self._sky = skies[0] if skies else None
        self._sky_color: tuple[float, ...] | None = None  # the background colour written into the sky texture
        if self._sim.spec.has_object:
            g, body = self._sim.object_geom, m.geom_bodyid[self._sim.object_geom]
            self._object_body = body
            self._object_size0 = m.geom_size[g].copy()
            self._friction0 = {i: m.geom_friction[i].copy() for i in [g, *self._table_geoms]}

    # -- protocol hooks -----------------------------------------------------------------------
    def set_render_size(self, size: tuple[int, int]) -> None:
        """Draw frames and the goal image at ``size`` = (H, W)."""
        size = check_render_size(type(self).__name__, size)
        if size != self.render_size:
            self.render_size, self._goal_image = size, None

    def eval_state(self, goal_state: np.ndarray, cur_state: np.ndarray) -> tuple[bool, float]:
        """``(success, distance)``: the achieved goal of ``cur_state`` within 0.05 of ``goal_state``'s
        (a state's achieved goal, or three numbers: upstream's goal_state)."""
        cur = self._as_state("eval_state cur_state", cur_state)
        goal = self._goal_point("eval_state goal_state", goal_state)
        dist = float(np.linalg.norm(cur[self._achieved] - goal))
        return dist < DISTANCE_THRESHOLD, dist

    # -- gym API --------------------------------------------------------------------------------
    def reset(self, *, seed: int | None = None, options: Mapping[str, Any] | None = None):
        gym.Env.reset(self, seed=seed)
        options = self._check_options(options)
        sim, spec = self._sim, self._sim.spec
        object_xy = self._sample_object_xy(sim.initial_gripper_xpos[:2]) if spec.has_object else None
        goal = self._sample_goal()
        vseed = int(self.np_random.integers(0, 2**31 - 1))
        spaces.reset_variation_space(self.variation_space, vseed, options, self.default_variations)
        named = self._named(options)
        v = self.variation_space.value
        self._apply_looks(v)
        lift = self._lift = self._apply_physical(v) if spec.has_object else 0.0
        sim.reset()
        agent_xy = np.asarray(v["agent"]["start_position"], np.float64) if "agent.start_position" in named else None
        if spec.has_object:
            if "block.start_position" in named:
                object_xy = np.asarray(v["block"]["start_position"], np.float64)
            elif agent_xy is not None:
                tries = 0
                while np.linalg.norm(object_xy - agent_xy) < 0.1 and tries < 100:
                    object_xy, tries = self._sample_object_xy(sim.initial_gripper_xpos[:2]), tries + 1
            q = sim.data.qpos[sim.object_qpos]
            q[:2] = object_xy
            q[2] += lift
            if "block.angle" in named:
                q[3:] = euler2quat([0.0, 0.0, float(np.asarray(v["block"]["angle"]).reshape(-1)[0])])
            sim.data.qpos[sim.object_qpos] = q
            goal[2] += lift
        mujoco.mj_forward(sim.model, sim.data)
        grip = (
            sim.initial_gripper_xpos.copy() if agent_xy is None else np.array([*agent_xy, sim.initial_gripper_xpos[2]])
        )
        if spec.has_object and np.linalg.norm(grip[:2] - object_xy) < CLEARANCE:  # object placed under the gripper
            top = sim.data.qpos[sim.object_qpos][2] + float(sim.model.geom_aabb[sim.object_geom, 5])
            grip[2] = max(grip[2], top + CLEARANCE_HEIGHT)
        if agent_xy is not None or grip[2] != sim.initial_gripper_xpos[2]:
            sim.move_gripper(grip)
        if "goal.start_position" in named:
            goal = np.asarray(v["goal"]["start_position"], np.float64).copy()
        if options.get(keys.STATE) is not None:
            state = options[keys.STATE]
            self._set_state(state)
            goal = state[-3:].copy()
        if options.get(keys.GOAL_STATE) is not None:
            goal = self._goal_point(f"reset option {keys.GOAL_STATE!r}", options[keys.GOAL_STATE])
        self._goal = np.asarray(goal, np.float64).copy()
        sim.show_target(self._goal)
        mujoco.mj_forward(sim.model, sim.data)
        sim.place_mocap_on_gripper()
        mujoco.mj_kinematics(sim.model, sim.data)
        self._build_goal_scene()
        obs, achieved = sim.observation()
        return self._observation(obs, achieved), self._info(obs, achieved)

    def step(self, action):
        a = np.asarray(action, np.float64).reshape(-1)
        if a.shape[0] != 4 or not np.all(np.isfinite(a)):
            raise ConfigError(f"{type(self).__name__}.step requires 4 finite action values, got {action!r}")
        self._sim.step(np.clip(a, -1.0, 1.0))
        obs, achieved = self._sim.observation()
        dist = float(np.linalg.norm(achieved - self._goal))
        if self.reward_type == "sparse":
            reward = -1.0 if dist > DISTANCE_THRESHOLD else 0.0
        else:
            reward = -dist
        return self._observation(obs, achieved), reward, False, False, self._info(obs, achieved)

    def render(self) -> np.ndarray:
        """The current frame, ``render_size`` (H, W, 3) uint8."""
        return self._render(self._sim.data)

    def close(self) -> None:
        """Free the renderers (the env stays usable: they are made again when needed)."""
        for key in self._render_keys:
            _release_renderer(key, self)
        self._render_keys = set()

    # -- reset parts ----------------------------------------------------------------------------
    def _check_options(self, options: Any) -> dict[str, Any]:
        owner = type(self).__name__
        if options is None:
            return {}
        out = checked_reset_options(owner, options, self.variation_space.names())
        if out.get(keys.STATE) is not None:
            out[keys.STATE] = self._as_state(f"reset option {keys.STATE!r}", out[keys.STATE])
        return out

    def _named(self, options: Mapping[str, Any]) -> set[str]:
        """The factors named in ``options["variation"]`` (``"all"`` and prefixes expanded) or set
        in ``options["variation_values"]``."""
        names = self.variation_space.names()
        requested = list(options.get(keys.VARIATION) or ())
        requested += list(flatten_values(options.get(keys.VARIATION_VALUES) or {}))
        if "all" in requested:
            return set(names)
        return {n for n in names if any(n == r or n.startswith(r + ".") for r in requested)}

    def _sample_object_xy(self, center: np.ndarray) -> np.ndarray:
        """Gymnasium-Robotics' draw: uniform within ``obj_range`` of the gripper start, at least 0.1 from it."""
        r = self._sim.spec.obj_range
        xy = center.copy()
        while np.linalg.norm(xy - center) < 0.1:
            xy = center + self.np_random.uniform(-r, r, size=2)
        return xy

    def _sample_goal(self) -> np.ndarray:
        """Gymnasium-Robotics' goal draw for the task."""
        spec, sim = self._sim.spec, self._sim
        goal = sim.initial_gripper_xpos[:3] + self.np_random.uniform(-spec.target_range, spec.target_range, size=3)
        if spec.has_object:
            goal += np.asarray(spec.target_offset)
            goal[2] = sim.height_offset
            if spec.target_in_the_air and self.np_random.uniform() < 0.5:
                goal[2] += self.np_random.uniform(0, 0.45)
        return goal.copy()

    def _apply_looks(self, v: Mapping[str, Any]) -> None:
        m = self._sim.model
        m.mat_rgba[self._mat["table_mat"], :3] = v["table"]["color"]
        background = np.asarray(v["background"]["color"], np.float64)
        m.mat_rgba[self._mat["floor_mat"], :3] = background
        if "object" in v:
            m.mat_rgba[[self._mat["block_mat"], self._mat["puck_mat"]], :3] = v["object"]["color"]
        m.light_diffuse[self._light] = float(np.asarray(v["light"]["intensity"]).reshape(-1)[0])
        d_az, d_el = np.asarray(v["camera"]["angle_delta"], np.float64).reshape(-1)[:2]
        m.cam_pos[self._camera], m.cam_quat[self._camera] = _sim.camera_pose(
            _sim.CAMERA_AZIMUTH + d_az, _sim.CAMERA_ELEVATION + d_el
        )
        if self._sky is not None and self._sky_color != tuple(background):
            start, nc = int(m.tex_adr[self._sky]), int(m.tex_nchannel[self._sky])
            count = int(m.tex_width[self._sky]) * int(m.tex_height[self._sky]) * nc
            texels = m.tex_data[start : start + count].reshape(-1, nc)
            texels[:, : min(nc, 3)] = (np.clip(background, 0.0, 1.0) * 255.0).astype(np.uint8)[: min(nc, 3)]
            self._sky_color = tuple(background)

    def _apply_physical(self, v: Mapping[str, Any]) -> float:
        """Write the object's size, mass and friction into the model (when they changed); returns how
        much higher the object's centre rests than with the default size."""
        sim, m = self._sim, self._sim.model
        obj = v["object"]
        size, mass, friction = (float(np.asarray(obj[k]).reshape(-1)[0]) for k in ("size", "mass", "friction"))
        puck = int(m.geom_type[sim.object_geom]) == int(mujoco.mjtGeom.mjGEOM_CYLINDER)
        half_height = PUCK_HEIGHT_RATIO * size if puck else size
        lift = half_height - float(self._object_size0[1] if puck else self._object_size0[2])
        if self._physical == (size, mass, friction):
            return lift
        g, body = sim.object_geom, self._object_body
        if puck:
            m.geom_size[g, :2] = (size, half_height)
            inertia = (mass * (3 * size**2 + 4 * half_height**2) / 12.0,) * 2 + (mass * size**2 / 2.0,)
            m.geom_rbound[g] = np.hypot(size, half_height)
            m.geom_aabb[g, 3:] = (size, size, half_height)
        else:
            m.geom_size[g] = size
            inertia = (2.0 * mass * size**2 / 3.0,) * 3
            m.geom_rbound[g] = np.sqrt(3.0) * size
            m.geom_aabb[g, 3:] = size
        m.body_mass[body] = mass
        m.body_inertia[body] = inertia
        for i, f0 in self._friction0.items():
            m.geom_friction[i] = (friction, f0[1], f0[2])
        weld = m.eq_data.copy()  # mj_setConst recomputes the weld's relative pose from qpos0: keep the mocap's
        mujoco.mj_setConst(m, sim.data)
        m.eq_data[:] = weld
        self._physical = (size, mass, friction)
        return lift

    def _set_state(self, state: np.ndarray) -> None:
        """Start from a flat observation: gripper position, finger opening, object pose (velocities zero)."""
        sim, d = self._sim, self._sim.data
        fingers = state[9:11] if sim.spec.has_object else state[3:5]
        d.qpos[sim.finger_qpos] = fingers
        if sim.spec.has_object:
            q = d.qpos[sim.object_qpos]
            q[:3] = state[3:6]  # the object's site is its body's origin
            q[3:] = euler2quat(state[11:14])
            d.qpos[sim.object_qpos] = q
        d.qvel[:] = 0.0
        mujoco.mj_forward(sim.model, d)
        sim.move_gripper(state[:3])

    def _build_goal_scene(self) -> None:
        """The goal scene in a scratch copy of the data: its observation, and (later) its image."""
        sim, gd = self._sim, self._goal_data
        mujoco.mj_copyData(gd, sim.model, sim.data)
        goal = self._goal
        if not sim.spec.has_object:
            sim.move_gripper(goal, gd)
        else:
            resting = sim.height_offset + self._lift
            held = not sim.spec.block_gripper and goal[2] > resting + 0.01
            if held:
                half = float(sim.model.geom_size[sim.object_geom, 0])
                gd.qpos[sim.finger_qpos] = np.clip(half - FINGER_INNER, 0.0, 0.05)
                sim.move_gripper(goal, gd)
            q = gd.qpos[sim.object_qpos]
            q[:3] = goal
            gd.qpos[sim.object_qpos] = q
            gd.qvel[:] = 0.0
            mujoco.mj_forward(sim.model, gd)
        self._goal_obs, _ = sim.observation(gd)
        if not sim.spec.has_object:  # the gripper settles within 1 mm of the goal: its state says "on the goal"
            self._goal_obs[self._achieved] = goal
        self._goal_image = None

    # -- observation / info ---------------------------------------------------------------------
    def _observation(self, obs: np.ndarray, achieved: np.ndarray):
        state = np.concatenate([obs, self._goal]).astype(np.float32)
        if self.flatten:
            return state
        return {
            "observation": obs.copy(),
            "achieved_goal": achieved.copy(),
            "desired_goal": self._goal.copy(),
            keys.STATE: state,
        }

    def _info(self, obs: np.ndarray, achieved: np.ndarray) -> dict[str, Any]:
        if self._goal_image is None:  # the goal scene only changes on reset
            self._goal_image = self._render(self._goal_data)
        dist = float(np.linalg.norm(achieved - self._goal))
        info = {
            "env_name": self.env_name,
            "is_success": float(dist < DISTANCE_THRESHOLD),
            keys.PROPRIO: obs.astype(np.float32),
            keys.GOAL: self._goal_image.copy(),
            keys.GOAL_STATE: np.concatenate([self._goal_obs, self._goal]).astype(np.float32),
            keys.GOAL_PROPRIO: self._goal_obs.astype(np.float32),
        }
        if self.flatten:  # the Dict observation holds it (World merges observation and info)
            info[keys.STATE] = np.concatenate([obs, self._goal]).astype(np.float32)
        return info

    def _as_state(self, what: str, value: Any) -> np.ndarray:
        try:
            arr = np.asarray(value, np.float64).reshape(-1)
        except (TypeError, ValueError) as exc:
            raise ConfigError(f"{type(self).__name__} requires {what} as numbers, got {value!r}") from exc
        if arr.shape[0] != self.state_dim or not np.all(np.isfinite(arr)):
            raise ConfigError(
                f"{type(self).__name__} requires {what} of {self.state_dim} finite numbers (the observation, then "
                f"the desired goal, as info[{keys.STATE!r}]), got shape {np.shape(value)}"
            )
        return arr

    def _goal_point(self, what: str, value: Any) -> np.ndarray:
        """The goal position of ``value``: a state's achieved goal, or three numbers."""
        try:
            arr = np.asarray(value, np.float64).reshape(-1)
        except (TypeError, ValueError) as exc:
            raise ConfigError(f"{type(self).__name__} requires {what} as numbers, got {value!r}") from exc
        if arr.shape[0] not in (3, self.state_dim) or not np.all(np.isfinite(arr)):
            raise ConfigError(
                f"{type(self).__name__} requires {what} of {self.state_dim} finite numbers (a state) or 3 (a goal "
                f"position), got shape {np.shape(value)}"
            )
        return arr.copy() if arr.shape[0] == 3 else arr[self._achieved].copy()

    # -- rendering ------------------------------------------------------------------------------
    def _render(self, data: mujoco.MjData) -> np.ndarray:
        h, w = self.render_size
        self._frames += 1
        key = (self.task, h, w, self.render_quality, threading.get_ident())
        if self._frames > SHARED_FRAMES:  # a long run: a context of its own, no sky uploads between envs
            key += (id(self),)
        shared = _shared_renderer(key, self._sim.model, self._sky_color)
        shared.users.add(self)
        self._render_keys.add(key)
        if self._sky is not None and shared.sky != self._sky_color:
            shared.renderer.upload_texture(self._sim.model, self._sky)
            shared.sky = self._sky_color
        return shared.renderer.render_model(self._sim.model, data, CAMERA)


class SharedRenderer(MjRenderer):
    """An :class:`~stable_worldmodel.envs.mujoco_render.MjRenderer` that draws any copy of the
    model it was made from: the envs of one task (same meshes and textures, their own colours, light,
    camera, object size) share one GL context per frame size, quality and thread, since making a
    context with the Fetch meshes costs ~0.5 s on a CPU renderer."""

    def render_model(self, model, data, camera: int | str) -> np.ndarray:
        """The frame of ``data`` with ``model``'s scene (a copy of the model this renderer was made from)."""
        self._model = model
        return self.render(data, camera)


class _Shared:
    def __init__(self, renderer: SharedRenderer, sky: tuple[float, ...] | None):
        self.renderer, self.sky = renderer, sky
        self.users: weakref.WeakSet = weakref.WeakSet()


_RENDERERS: dict[tuple, _Shared] = {}  # oldest first
#: frames an env draws with the shared renderer before it gets one of its own: envs of one task share
#: a GL context, but each switch between envs of different background colours uploads the sky
#: texture again (~4 ms on a CPU, about a 64 x 64 frame's cost), which a long run should not pay
SHARED_FRAMES = 200
IDLE_RENDERERS = 12  # one per task and frame size of a typical session (4 tasks x 3 sizes)


def _shared_renderer(key: tuple, model, sky: tuple[float, ...] | None) -> _Shared:
    """The renderer of ``key`` = (task, H, W, quality, thread[, env id]), made from ``model`` (whose sky
    texture holds the background colour ``sky``) on first use."""
    shared = _RENDERERS.pop(key, None)
    if shared is None:
        task, h, w, quality = key[:4]
        shared = _Shared(SharedRenderer(model, h, w, quality, mesh_model=_sim.mesh_model(task, quality)), sky)
    _RENDERERS[key] = shared  # the most recently used last
    return shared


def _release_renderer(key: tuple, env: FetchEnv) -> None:
    """``env`` no longer draws with ``key``'s renderer. Renderers nobody draws with are kept for the
    next envs (a World made again, the next test), at most :data:`IDLE_RENDERERS` of them."""
    shared = _RENDERERS.get(key)
    if shared is None:
        return
    shared.users.discard(env)
    if len(key) > 5 and not len(shared.users):  # an env's own renderer: of no use to another
        _RENDERERS.pop(key).renderer.close()
    idle = [k for k, s in _RENDERERS.items() if not len(s.users)]
    for k in idle[: max(0, len(idle) - IDLE_RENDERERS)]:
        _RENDERERS.pop(k).renderer.close()

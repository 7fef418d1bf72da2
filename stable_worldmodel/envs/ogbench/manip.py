"""What the OGBench envs share (:class:`ManipMixin`, put before OGBench's env class in the bases).

- **Reset**: ``reset(seed)`` seeds ``np_random`` (Gymnasium), then the variation space from it, then
  runs OGBench's episode set-up (build / compile / ``initialize_episode``) with no seed of its
  own, so one seed fixes factors, arm yaw and scene draws alike and ``reset()`` without a seed
  continues the stream. Options: ``variation`` / ``variation_values`` (factors), ``state``,
  ``goal_state`` (arrays as in ``info["state"]``).
- **Compilation**: one compiled model per configuration and process, deep-copied into each env
  (compiling costs ~0.3 s); factors never recompile: colours, light, camera and cube sizes are
  written into the compiled model (:class:`.factors.VisualFactors`, :class:`.factors.CubeSizes`).
- **Rendering** goes through :class:`~stable_worldmodel.envs.mujoco_render.MjRenderer`,
  created on the first ``render()`` (never in ``__init__``, so envs built in forked workers are
  safe), rebuilt when the size or the model changes (a new floor texture is uploaded to the live
  context), freed by :meth:`close`. Below ``render_quality="high"`` it draws the arm's decimated
  meshes (:mod:`.meshes`: ``"medium"`` keeps 10 % of the faces of each large mesh, ``"low"`` 5 %,
  physics untouched) and the floor with a coarser grid of quads, and leaves the floor out of the
  shadow map (nothing is below it); ``"high"`` draws the exact meshes, upstream's picture.
- **Goal**: the goal scene is built, settled for 2 zero-action steps and captured once per reset
  (``info["goal"]`` image, ``goal_state``, ``goal_proprio``, upstream's ``target`` = its
  observation), then the start scene is set.
- **Info**: OGBench's ``proprio/*``, ``privileged/*`` (named ``proprio.*``, ``privileged.*``:
  :mod:`.infokeys`), ``qpos`` ... plus ``env_name``,
  ``target``, ``success``, ``state`` (``qpos ++ qvel`` [``++ button_states``]), ``proprio`` (the
  19 proprioceptive numbers of OGBench's observation), ``goal``, ``goal_state``, ``goal_proprio``.
- **Data collection** (``mode="data_collection"``, as upstream 0.1.1's collection scripts use it):
  the episode has one subtask at a time instead of a goal scene. The start scene is the factors'
  (as in task mode); then :meth:`set_new_target` draws the first target (OGBench's rules, from
  ``np_random``: see the envs' ``_draw_target``), and the expert (or any caller) draws the next
  one with ``set_new_target(p_stack=...)`` when a subtask is done, each new target redrawing
  ``cube.goal_position`` / ``cube.goal_yaw``. ``success`` (and ``terminated`` with
  ``terminate_at_goal``) is OGBench's: the current subtask only. Infos add OGBench's
  ``privileged.target_task`` (``"cube"``, Scene also ``"button"`` / ``"drawer"`` / ``"window"``),
  ``privileged.target_block`` and the single-target entries (``target_block_pos`` ...);
  ``target`` is zeros (upstream's: no goal observation); ``goal`` / ``goal_state`` /
  ``goal_proprio`` are the current scene with the subtask done (captured at each new target).
  Cube targets other than the subtask's are moved out of sight (z = -0.3), as OGBench.
  ``options["goal_state"]`` is refused in this mode.
"""

from __future__ import annotations

import copy
from collections.abc import Mapping
from typing import Any

import gymnasium as gym
import numpy as np

from ... import keys, spaces
from ..._optional import require
from ...errors import ConfigError, did_you_mean
from ..base import DatasetResetMixin, check_render_size, checked_reset_options
from ..mujoco_render import MjRenderer, OwnsRenderer, check_render_quality, setup_gl
from . import infokeys, meshes
from .factors import RENDER_CAMERA, CubeSizes, VisualFactors, tint

setup_gl()  # before mujoco is imported
mujoco = require("mujoco", purpose="the OGBench envs")
lie = require("ogbench.manipspace.lie", extra="mujoco", purpose="the OGBench envs")
mjcf_utils = require("ogbench.manipspace.mjcf_utils", extra="mujoco", purpose="the OGBench envs")
CustomMuJoCoEnv = require("ogbench.manipspace.envs.env", extra="mujoco").CustomMuJoCoEnv

XYZ_CENTER = np.array([0.425, 0.0, 0.0])  # OGBench's observation normalisation
XYZ_SCALE, GRIPPER_SCALE = 10.0, 3.0
PROPRIO_DIM = 19
SUCCESS_DISTANCE = 0.04  # OGBench's task rule: every cube within 4 cm of its target
SETTLE_STEPS = 2
TASK, DATA_COLLECTION = "task", "data_collection"
MODES = (TASK, DATA_COLLECTION)
AWAY = np.array([0.0, 0.0, -0.3])  # OGBench's place for the targets not in play (data collection)
COVER_XY = 0.02  # OGBench: a cube within 2 cm (xy) below another is covered
P_STACK = 0.5  # OGBench's default probability of a stacking target
_MODELS: dict[tuple, Any] = {}  # compiled models, one per configuration (process-wide)
_MESH_MODELS: dict[tuple, Any] = {}  # their decimated twins for drawing, per configuration and ratio


def proprio_vector(ob_info: Mapping[str, np.ndarray]) -> np.ndarray:
    """OGBench's 19 proprioceptive observation numbers from ``compute_ob_info()``."""
    yaw = ob_info["proprio/effector_yaw"]
    return np.concatenate(
        [
            ob_info["proprio/joint_pos"],
            ob_info["proprio/joint_vel"],
            (ob_info["proprio/effector_pos"] - XYZ_CENTER) * XYZ_SCALE,
            np.cos(yaw),
            np.sin(yaw),
            ob_info["proprio/gripper_opening"] * GRIPPER_SCALE,
            ob_info["proprio/gripper_contact"],
        ]
    )


def yaw_quat(yaw: float) -> np.ndarray:
    return np.asarray(lie.SO3.from_z_radians(float(yaw)).wxyz, np.float64)


class ManipMixin(OwnsRenderer, DatasetResetMixin):
    """Reset flow, compilation cache, rendering, goal capture and infos (module docstring)."""

    metadata = {"render_modes": ["rgb_array"], "render_fps": 20}
    ENV_NAME = ""
    DEFAULT_VARIATIONS = ("cube.start_position", "cube.start_yaw", "cube.goal_position", "cube.goal_yaw")
    OGB_CAMERAS: dict[str, dict] = {}  # the cameras OGBench adds ("front", "front_pixels")
    CAMERAS: dict[str, dict] = {}  # the cameras we add

    # -- construction ---------------------------------------------------------------------------
    @classmethod
    def _check_args(cls, ob_type: str, render_quality: str, render_mode: str | None, kwargs: Mapping[str, Any]) -> None:
        """Validate the constructor arguments before OGBench builds anything."""
        owner = cls.__name__
        if ob_type not in ("states", "pixels"):
            raise ConfigError(f"{owner} requires ob_type 'states' or 'pixels', got {ob_type!r}")
        if render_mode not in (None, "rgb_array"):
            raise ConfigError(f"{owner} requires render_mode 'rgb_array' or None, got {render_mode!r}")
        check_render_quality(owner, render_quality)
        mode = kwargs.get("mode", TASK)
        if mode not in MODES:
            raise ConfigError(f"{owner} requires mode in {list(MODES)}, got {mode!r}.{did_you_mean(str(mode), MODES)}")

    def _setup(self, multiview: bool, render_quality: str, render_mode: str | None) -> None:
        self.render_quality = render_quality
        self.render_mode = render_mode
        self._multiview = bool(multiview)
        self.env_name = self.ENV_NAME
        self._mjr: MjRenderer | None = None
        self._visual: VisualFactors | None = None
        self._sizes: CubeSizes | None = None
        self._options: dict[str, Any] = {}
        self._goal: dict[str, Any] = {}
        self._action_space = gym.spaces.Box(-1.0, 1.0, shape=(5,), dtype=np.float32)
        self._observation_space = self._make_observation_space()
        self._cube_colors = self._cube_colors.copy()
        self._cube_success_colors = self._cube_success_colors.copy()

    @property
    def cameras(self) -> dict[str, dict]:
        """Camera name -> ``pos`` / ``xyaxes`` (as upstream lists them)."""
        return {**self.OGB_CAMERAS, **self.CAMERAS}

    @property
    def action_space(self) -> gym.spaces.Box:  # one object, so that seeding it sticks
        return self._action_space

    @property
    def observation_space(self) -> gym.spaces.Box:
        return self._observation_space

    def _make_observation_space(self) -> gym.spaces.Box:
        if self._ob_type == "pixels":  # frames at the render size
            return gym.spaces.Box(0, 255, (self._render_height, self._render_width, 3), np.uint8)
        return gym.spaces.Box(-np.inf, np.inf, (self._state_ob_dim(),), np.float64)

    def add_objects(self, arena_mjcf) -> None:
        super().add_objects(arena_mjcf)
        for name, kwargs in self.CAMERAS.items():
            arena_mjcf.worldbody.add("camera", name=name, **kwargs)

    # -- compilation ----------------------------------------------------------------------------
    def compile_model_and_data(self) -> None:
        """OGBench's compilation, from a per-process cache of compiled models."""
        key = self._model_key()
        if key not in _MODELS:
            mj = self._mjcf_model
            _MODELS[key] = mujoco.MjModel.from_xml_string(mjcf_utils.to_string(mj), mjcf_utils.get_assets(mj))
        self._model = copy.deepcopy(_MODELS[key])
        self._model.opt.timestep = self._physics_timestep
        self._data = mujoco.MjData(self._model)
        mujoco.mj_forward(self._model, self._data)
        self._close_renderer()
        self.post_compilation()
        self._dirty = False

    def _model_key(self) -> tuple:
        return (
            type(self).__module__,
            type(self).__qualname__,
            self._env_type,
            self._ob_type,
            self._pixel_transparent_arm,
        )

    def _mesh_model(self):
        """The model whose (decimated) meshes the renderer draws, or None for the exact ones
        (``render_quality="high"``, or fast-simplification missing): :mod:`.meshes`."""
        ratio, grid = meshes.MESH_DETAIL[self.render_quality], meshes.PLANE_GRID[self.render_quality]
        if ratio is None or not meshes.available():
            return None
        key = (*self._model_key(), ratio, grid)
        if key not in _MESH_MODELS:
            mj = self._mjcf_model
            _MESH_MODELS[key] = meshes.render_mesh_model(
                _MODELS[self._model_key()], mjcf_utils.to_string(mj), mjcf_utils.get_assets(mj), ratio, plane_grid=grid
            )
        return _MESH_MODELS[key]

    def _floor_geoms(self) -> list[int]:
        """The ground planes (static, facing up): nothing lies below them, so below ``"high"`` they
        are left out of the shadow map (they could only shadow themselves)."""
        m = self._model
        return [
            g
            for g in range(m.ngeom)
            if m.geom_type[g] == mujoco.mjtGeom.mjGEOM_PLANE
            and m.geom_bodyid[g] == 0
            and self._data.geom_xmat[g, 8] > 0.999
        ]

    def post_compilation_objects(self) -> None:
        super().post_compilation_objects()
        m = self._model
        self._visual = VisualFactors(m, mujoco)
        self._sizes = CubeSizes(m, mujoco, self._cube_geom_ids_list, self._cube_target_geom_ids_list)
        self._cube_qpos = [m.jnt_qposadr[m.joint(f"object_joint_{i}").id] for i in range(self._num_cubes)]

    def _apply_factors(self) -> None:
        v = self.variation_space.value
        agent, camera = v["agent"]["color"], v["camera"]["angle_delta"]
        if self._visual.apply(agent, v["floor"]["color"], v["light"]["intensity"], camera):
            self._upload_texture(self._visual.floor_texture)
        colors = np.asarray(v["cube"]["color"], np.float64)
        self._cube_colors[: self._num_cubes, :3] = colors
        self._cube_success_colors[: self._num_cubes, :3] = tint(colors)
        for i in range(self._num_cubes):
            self._model.geom_rgba[self._cube_geom_ids_list[i], :3] = colors[i]
            self._model.geom_rgba[self._cube_target_geom_ids_list[i], :3] = colors[i]
        self._sizes.apply(v["cube"]["size"])

    # -- reset / step ---------------------------------------------------------------------------
    def reset(self, *, seed: int | None = None, options: Mapping[str, Any] | None = None):
        gym.Env.reset(self, seed=seed)
        self._options = self._check_options(options)
        vseed = int(self.np_random.integers(0, 2**31 - 1))
        spaces.reset_variation_space(self.variation_space, vseed, self._options, self.DEFAULT_VARIATIONS)
        ob, info = CustomMuJoCoEnv.reset(self)  # no seed: np_random is already set
        info["success"] = False
        return ob, info

    def _check_options(self, options: Any) -> dict[str, Any]:
        owner = type(self).__name__
        if options is None:
            return {}
        out = checked_reset_options(owner, options, self.variation_space.names())
        if self._mode == DATA_COLLECTION and out.get(keys.GOAL_STATE) is not None:
            raise ConfigError(
                f"{owner}.reset takes no {keys.GOAL_STATE!r} option in mode 'data_collection' "
                "(its targets are drawn subtask by subtask); use mode 'task'"
            )
        for key in (keys.STATE, keys.GOAL_STATE):
            if out.get(key) is not None:
                out[key] = self._check_state(f"reset option {key!r}", out[key])
        return out

    def _check_state(self, what: str, value: Any) -> np.ndarray:
        """``value`` as a flat state vector; ConfigError naming ``what`` unless it has the state's length."""
        try:
            arr = np.asarray(value, np.float64).reshape(-1)
        except (TypeError, ValueError) as exc:
            raise ConfigError(f"{type(self).__name__} requires {what} as numbers, got {value!r}") from exc
        dim = self._state_dim()
        if arr.shape[0] != dim or not np.all(np.isfinite(arr)):
            parts = "qpos, qvel, button states" if self._extra_state_dim() else "qpos, qvel"
            raise ConfigError(
                f"{type(self).__name__} requires {what} of {dim} finite numbers ({parts}, as info[{keys.STATE!r}]), "
                f"got shape {np.shape(value)}"
            )
        return arr

    def initialize_episode(self) -> None:
        self._apply_factors()
        self._data.qpos[self._arm_joint_ids] = self._home_qpos
        mujoco.mj_kinematics(self._model, self._data)
        if self._mode == TASK:
            self._build_goal(self._options.get(keys.GOAL_STATE))
        start = self._options.get(keys.STATE)
        if start is None:
            self._place_scene("start")
        else:
            self._set_state_vector(start)
        if self._mode == DATA_COLLECTION:
            self._clear_targets()
            self._draw_target(P_STACK)
        self._finish_placement()
        if self._mode == DATA_COLLECTION:
            self._capture_subtask_goal()
        self._success = False

    def _finish_placement(self) -> None:
        self.pre_step()
        mujoco.mj_forward(self._model, self._data)
        self.post_step()

    def _build_goal(self, goal_state: np.ndarray | None = None) -> None:
        """Build the goal scene (factors, or ``goal_state``), aim the targets at it, capture it, restore."""
        saved = self._snapshot()
        if goal_state is None:
            self._place_scene("goal")
            for _ in range(SETTLE_STEPS):
                self._finish_placement()
                self.set_control(np.zeros(5))
                mujoco.mj_step(self._model, self._data, nstep=self._n_steps)
                mujoco.mj_rnePostConstraint(self._model, self._data)
        else:
            self._set_state_vector(goal_state)
        self._aim_targets()
        self._finish_placement()
        ob_info = self.compute_ob_info()
        self._goal = {
            keys.STATE: self._state_vector(),
            keys.PROPRIO: proprio_vector(ob_info),
            "ob": self.compute_oracle_observation() if self._use_oracle_rep else self.compute_observation(),
            "image": self.render(),
        }
        self._restore(saved)

    def set_new_target(self, return_info: bool = True, p_stack: float = P_STACK):
        """A new goal, keeping the current state; returns ``(obs, info)`` when ``return_info``.

        Mode ``task``: new ``cube.goal_position`` / ``cube.goal_yaw`` (Scene: new button, drawer and
        window goals too) and a new goal scene; ``p_stack`` is unused (goals follow the layout rules).
        Mode ``data_collection``: the next subtask, drawn by OGBench's rules (a cube target stacks
        on another free cube with probability ``p_stack``), the goal factors redrawn first.
        """
        owner = type(self).__name__
        if self._model is None:
            raise ConfigError(f"{owner}.set_new_target requires reset() first")
        if isinstance(p_stack, bool) or not isinstance(p_stack, (int, float, np.number)) or not 0 <= p_stack <= 1:
            raise ConfigError(f"{owner}.set_new_target requires p_stack in [0, 1], got {p_stack!r}")
        self.variation_space.update(["cube.goal_position", "cube.goal_yaw"])
        if self._mode == DATA_COLLECTION:
            self._draw_target(float(p_stack))
            self._finish_placement()
            self._capture_subtask_goal()
        else:
            self._build_goal()
            self._finish_placement()
        return (self.compute_observation(), self._info()) if return_info else None

    # -- data collection ------------------------------------------------------------------------
    def _clear_targets(self) -> None:
        """No subtask yet: every cube target out of sight (the envs add their other targets)."""
        self._target_block = 0
        for mocap in self._cube_target_mocap_ids:
            self._data.mocap_pos[mocap] = AWAY
            self._data.mocap_quat[mocap] = (1.0, 0.0, 0.0, 0.0)

    def _cube_xyz(self) -> np.ndarray:
        return np.array([self._data.qpos[a : a + 3] for a in self._cube_qpos])

    def _free_cubes(self, among: list[int]) -> list[int]:
        """The cubes of ``among`` with no cube above them (OGBench's "top blocks")."""
        xyz = self._cube_xyz()
        return [
            i
            for i in among
            if not any(
                j != i and xyz[j, 2] > xyz[i, 2] and np.hypot(*(xyz[i, :2] - xyz[j, :2])) < COVER_XY
                for j in range(self._num_cubes)
            )
        ]

    def _draw_cube_target(self, among: list[int], p_stack: float, drawer_xyz: np.ndarray | None = None) -> None:
        """OGBench's cube subtask: a free cube of ``among`` goes into the drawer (``drawer_xyz``,
        when given), onto another free cube (probability ``p_stack``, two free cubes needed) or to
        its ``cube.goal_position`` row, turned to its ``cube.goal_yaw``; other targets out of sight."""
        rng = self.np_random
        v = self.variation_space["cube"]
        sizes = np.asarray(v["size"].value, np.float64)
        free = self._free_cubes(among)
        target = int(rng.choice(free))
        others = [i for i in free if i != target]
        if drawer_xyz is not None:
            xyz = np.asarray(drawer_xyz, np.float64).copy()
        elif len(others) >= 1 and rng.uniform() < p_stack:
            below = int(rng.choice(others))
            base = self._cube_xyz()[below]
            xyz = np.array([base[0], base[1], base[2] + sizes[below] + sizes[target]])
        else:
            xyz = np.array([*np.asarray(v["goal_position"].value)[target], sizes[target]])
        self._target_block = target
        for i, mocap in enumerate(self._cube_target_mocap_ids):
            self._data.mocap_pos[mocap] = xyz if i == target else AWAY
            self._data.mocap_quat[mocap] = (
                yaw_quat(np.asarray(v["goal_yaw"].value)[target]) if i == target else (1.0, 0.0, 0.0, 0.0)
            )

    def _draw_target(self, p_stack: float) -> None:
        """Draw the next data-collection subtask (the envs define it)."""
        raise NotImplementedError

    def _complete_subtask(self) -> None:
        """Put the scene in the state the current subtask asks for (default: the target cube on its target)."""
        adr = self._cube_qpos[self._target_block]
        mocap = self._cube_target_mocap_ids[self._target_block]
        self._data.qpos[adr : adr + 3] = self._data.mocap_pos[mocap]
        self._data.qpos[adr + 3 : adr + 7] = self._data.mocap_quat[mocap]
        dof = self._model.jnt_dofadr[self._model.joint(f"object_joint_{self._target_block}").id]
        self._data.qvel[dof : dof + 6] = 0.0

    def _capture_subtask_goal(self) -> None:
        """``goal`` / ``goal_state`` / ``goal_proprio``: the current scene with the subtask done."""
        saved = self._snapshot()
        self._complete_subtask()
        mujoco.mj_forward(self._model, self._data)
        ob_info = self.compute_ob_info()
        self._goal = {
            keys.STATE: self._state_vector(),
            keys.PROPRIO: proprio_vector(ob_info),
            "ob": np.zeros(self.observation_space.shape, self.observation_space.dtype),
            "image": self.render(),
        }
        self._restore(saved)

    def _place_arm(self, pos: np.ndarray, yaw: float) -> None:
        """The arm's joints by IK for the effector at ``pos`` pointing down with ``yaw`` (OGBench's pose)."""
        rot = lie.SO3.from_z_radians(float(yaw)) @ self._effector_down_rotation
        pose = lie.SE3.from_rotation_and_translation(rot, np.asarray(pos, np.float64)) @ self._T_pa
        qpos = self._ik.solve(pos=pose.translation(), quat=pose.rotation().wxyz, curr_qpos=self._home_qpos)
        self._data.qpos[self._arm_joint_ids] = qpos
        mujoco.mj_forward(self._model, self._data)

    def _place_cubes(self, xy: np.ndarray, yaws: np.ndarray) -> np.ndarray:
        """Cubes at ``xy`` (N, 2) with ``yaws``, on the floor or stacked in index order; returns (N, 3)."""
        sizes = np.asarray(self.variation_space["cube"]["size"].value, np.float64)
        xyz = np.zeros((self._num_cubes, 3))
        for i in range(self._num_cubes):
            below = [xyz[j, 2] + sizes[j] for j in range(i) if np.hypot(*(xy[i] - xy[j])) < sizes[i] + sizes[j]]
            xyz[i] = (*xy[i], max(below, default=0.0) + sizes[i])
            adr = self._cube_qpos[i]
            self._data.qpos[adr : adr + 3] = xyz[i]
            self._data.qpos[adr + 3 : adr + 7] = yaw_quat(yaws[i])
        return xyz

    def _aim_targets(self) -> None:
        """Cube targets (mocap bodies) at the cubes of the current (goal) scene."""
        for i, mocap in enumerate(self._cube_target_mocap_ids):
            adr = self._cube_qpos[i]
            self._data.mocap_pos[mocap] = self._data.qpos[adr : adr + 3]
            self._data.mocap_quat[mocap] = self._data.qpos[adr + 3 : adr + 7]

    def _snapshot(self) -> tuple:
        return self._data.qpos.copy(), self._data.qvel.copy(), self._data.time

    def _restore(self, saved: tuple) -> None:
        self._data.qpos[:], self._data.qvel[:], self._data.time = saved[0], saved[1], saved[2]
        self._data.ctrl[:] = 0.0
        mujoco.mj_forward(self._model, self._data)

    def _state_vector(self) -> np.ndarray:
        return np.concatenate([self._data.qpos, self._data.qvel])

    def _set_state_vector(self, state: np.ndarray) -> None:
        nq, nv = self._model.nq, self._model.nv
        self._data.qpos[:] = state[:nq]
        self._data.qvel[:] = state[nq : nq + nv]
        mujoco.mj_forward(self._model, self._data)

    def _state_dim(self) -> int:
        self._ensure_model()
        return self._model.nq + self._model.nv + self._extra_state_dim()

    def _extra_state_dim(self) -> int:
        return 0

    def _ensure_model(self) -> None:
        if self._model is None:
            if self._mjcf_model is None:
                self._mjcf_model = self.build_mjcf_model()
            self.compile_model_and_data()
            self._never_compiled = False

    # -- infos ----------------------------------------------------------------------------------
    def add_object_info(self, ob_info: dict) -> None:
        super().add_object_info(ob_info)
        for i, mocap in enumerate(self._cube_target_mocap_ids):  # what the expert aims at
            ob_info[f"privileged/target_block_{i}_pos"] = self._data.mocap_pos[mocap].copy()
            yaw = lie.SO3(wxyz=self._data.mocap_quat[mocap]).compute_yaw_radians()
            ob_info[f"privileged/target_block_{i}_yaw"] = np.array([yaw])

    def _info(self) -> dict[str, Any]:
        ob_info = self.compute_ob_info()
        info = infokeys.to_ours(ob_info)  # proprio/joint_pos -> proprio.joint_pos (see .infokeys)
        goal = self._goal
        info.update(
            {
                "env_name": self.env_name,
                "target": np.array(goal["ob"], copy=True),
                keys.STATE: self._state_vector(),
                keys.PROPRIO: proprio_vector(ob_info),
                keys.GOAL: goal["image"].copy(),
                keys.GOAL_STATE: goal[keys.STATE].copy(),
                keys.GOAL_PROPRIO: goal[keys.PROPRIO].copy(),
            }
        )
        return info

    def get_reset_info(self) -> dict[str, Any]:
        return self._info()

    def get_step_info(self) -> dict[str, Any]:
        return self._info()

    def eval_state(self, goal_state: np.ndarray, cur_state: np.ndarray) -> tuple[bool, float]:
        """``(success, distance)`` by OGBench's task rule (see the env's docstring)."""
        goal = self._check_state("eval_state's goal_state", goal_state)
        cur = self._check_state("eval_state's cur_state", cur_state)
        errors = [float(np.linalg.norm(cur[a : a + 3] - goal[a : a + 3])) for a in self._cube_qpos]
        ok, extra = self._extra_success(goal, cur)
        return bool(ok and max(errors) <= SUCCESS_DISTANCE), float(np.linalg.norm(errors) + extra)

    def _extra_success(self, goal: np.ndarray, cur: np.ndarray) -> tuple[bool, float]:
        return True, 0.0

    def reset_options_from_dataset(self, start_row, goal_row) -> dict[str, Any]:
        """Start at ``start_row``'s state with ``goal_row``'s as goal; rows recorded by upstream
        (``qpos`` / ``qvel`` [/ ``button_states``] columns, no ``state``) work too."""
        return super().reset_options_from_dataset(self._with_state(start_row), self._with_state(goal_row))

    def _with_state(self, row: Mapping[str, Any]) -> Mapping[str, Any]:
        parts = ["qpos", "qvel", *(["button_states"] if self._extra_state_dim() else [])]
        if keys.STATE in row or not all(p in row for p in parts):
            return row
        return {**row, keys.STATE: np.concatenate([np.asarray(row[p], np.float64).reshape(-1) for p in parts])}

    # -- rendering ------------------------------------------------------------------------------
    def set_render_size(self, size: tuple[int, int]) -> None:
        """Draw frames (and goal images, from the next reset) at ``size`` = (H, W)."""
        h, w = check_render_size(type(self).__name__, size)
        if (h, w) != (self._render_height, self._render_width):
            self._render_height, self._render_width = h, w
            self._observation_space = self._make_observation_space()
            self._close_renderer()

    def _initialize_renderer(self) -> None:
        if self._model is None:
            raise ConfigError(f"{type(self).__name__} requires reset() before rendering")
        self._close_renderer()
        self._mjr = MjRenderer(
            self._model,
            self._render_height,
            self._render_width,
            self.render_quality,
            mesh_model=self._mesh_model(),
            shadowless=self._floor_geoms() if self.render_quality != "high" else (),
        )

    def render(self, camera: str | None = None) -> np.ndarray:
        """The ``(H, W, 3)`` uint8 frame from ``camera`` (default ``front_pixels``, as upstream)."""
        if self._mjr is None:
            self._initialize_renderer()
        return self._mjr.render(self._data, camera or RENDER_CAMERA, self._scene_option)

    def render_multiview(self) -> np.ndarray | dict[str, np.ndarray]:
        """Every camera (name -> frame) when built with ``multiview=True``, else :meth:`render`."""
        if not self._multiview:
            return self.render()
        return {name: self.render(name) for name in self.cameras}

    def close(self) -> None:
        """Free the GL renderer (the env can be reset and rendered again afterwards)."""
        self._close_renderer()
        super().close()

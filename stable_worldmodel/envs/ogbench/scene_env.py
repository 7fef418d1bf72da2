"""``swm/OGBScene-v0``: OGBench's Scene (a cube, two lock buttons, a drawer and a window), as
upstream 0.1.1 exposes it, on top of ``ogbench.manipspace`` (this class subclasses OGBench's
``SceneEnv``; shared machinery in :mod:`.manip`, factors in :mod:`.factors`).

- **Constructor**: ``SceneEnv(env_type='scene', ob_type='states', permute_blocks=True,
  multiview=False, *args, height=200, width=200, render_quality='medium', render_mode='rgb_array',
  **kwargs)``.
- **Spaces**: observation ``Box(40)`` float64 (OGBench's: arm, cube, per button its one-hot
  state, position and velocity, drawer and window positions and velocities) or the frame for
  ``ob_type='pixels'``; action ``Box(-1, 1, (5,), float32)``. ``env_name`` is ``'Scene'``.
- **Factors**: those of :mod:`.factors` for one cube (cube area ``[0.3, 0.45] x [-0.07, 0.18]``,
  camera within +-5 degrees, light 0.6) plus ``lock_color`` (2, 3): the colour of the drawer's
  (row 0) and the window's (row 1) handle and button while locked (white when unlocked, as
  OGBench). A reset resamples the cube's start and goal poses by default.
- **Episode**: drawn from ``np_random`` (so from the reset seed). Start: each button locked or
  unlocked with probability 1/2 (button 0 locks the drawer, button 1 the window), drawer slide
  uniform in ``[-0.16, 0]``, window slide in ``[0, 0.2]``. Goal: buttons drawn the same way,
  drawer closed (0) or open (-0.16), window closed (0) or open (0.2), the cube at its goal pose.
- **Success** (OGBench's task rule): cube within 4 cm of its target, both button states equal to
  the goal's, drawer and window slides within 4 cm of theirs; ``terminated`` then, never
  truncated by the env (the swm tools cut at 750 steps, OGBench's length). ``state`` is
  ``qpos ++ qvel ++ button_states``; :meth:`eval_state` applies the rule to two states (distance:
  cube position error + drawer and window errors + number of wrong buttons).
- **Rendering**: ``front_pixels`` at 200 x 200 by default; ``multiview=True`` gives
  ``{front, front_pixels, side_pixels}``. ``render_quality`` as for Cube: ``"high"`` exact,
  ``"medium"`` / ``"low"`` draw the arm's decimated meshes and a coarser floor grid (:mod:`.meshes`)
  and keep the floor out of the shadow map.

Deliberate differences from upstream 0.1.1: the cube factors place the cube and the
start / goal of buttons, drawer and window are drawn from the reset seed (upstream: OGBench's
five task presets drawn from the global ``np.random``, cube factors unused, resets not
reproducible); ``cube.start_position`` / ``cube.goal_position`` default to ``[0.4, -0.05]`` /
``[0.4, 0.15]`` (both the area's centre upstream, never used); every factor applies to its own
reset (upstream's Scene keeps a ``camera.angle_delta`` for all later resets and leaves the
gripper purple whatever ``agent.color`` says); and the differences listed in
:mod:`.cube_env` (goal-scene arm, colour tint, no recompilation, extra infos:
``privileged.target_block_0_*``, ``privileged.button_<i>_top_pos``,
``privileged.target_button_states``, ``privileged.target_drawer_pos`` / ``_handle_pos``,
``privileged.target_window_pos`` / ``_handle_pos``; OGBench's entries named with ``.``).

``mode='data_collection'`` (:mod:`.manip`): the start scene as in task mode (buttons, drawer and
window drawn as OGBench's data collection draws them); each subtask is drawn by OGBench's Scene
rules: ``cube`` (weight 1 when a cube is outside the drawer), ``button`` (1), ``drawer`` /
``window`` (1, or 0.25 while locked); a cube goes into the open drawer with probability 0.3,
else to ``cube.goal_position`` / ``cube.goal_yaw``; a button subtask toggles one random button;
a drawer / window subtask opens it when closed and closes it when open. At each reset the
button, drawer and window targets start equal to the current scene (upstream keeps them from the
previous episode).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..._optional import require
from ...errors import ConfigError
from .factors import box, common_space, cube_space
from .manip import PROPRIO_DIM, ManipMixin, mujoco

_OGBSceneEnv = require("ogbench.manipspace.envs.scene_env", extra="mujoco", purpose="swm/OGBScene-v0").SceneEnv

CUBE_BOUNDS = ((0.3, -0.07), (0.45, 0.18))
ARM_BOUNDS = np.array([[0.25, -0.2, 0.2], [0.6, 0.2, 0.35]])
DRAWER_RANGE, WINDOW_RANGE = (-0.16, 0.0), (0.0, 0.2)
DRAWER_GOALS, WINDOW_GOALS = (0.0, -0.16), (0.0, 0.2)
LOCK_COLOR = (0.96, 0.26, 0.33)  # OGBench's red
START, GOAL = [[0.4, -0.05]], [[0.4, 0.15]]  # defaults of cube.start_position / cube.goal_position
HANDLES = ("drawer_handle", "window_handle")
SLIDE_TOLERANCE = 0.04
SUBTASKS = ("cube", "button", "drawer", "window")
LOCKED_WEIGHT = 0.25  # OGBench: weight of a drawer / window subtask while its button locks it
P_INTO_DRAWER, DRAWER_OPEN = 0.3, -0.12  # OGBench: a cube goes into the drawer when it is open past -0.12
DRAWER_CLOSED, WINDOW_CLOSED = -0.08, 0.1  # OGBench: closer to closed than these counts as closed
DRAWER_JITTER = 0.005


class SceneEnv(ManipMixin, _OGBSceneEnv):
    """OGBench's Scene with factors of variation (see the module docstring)."""

    ENV_NAME = "Scene"
    OGB_CAMERAS = {
        "front": {"pos": (1.139, 0.000, 0.821), "xyaxes": (0.000, 1.000, 0.000, -0.627, 0.000, 0.779)},
        "front_pixels": {"pos": (0.905, 0.000, 0.762), "xyaxes": (0.000, 1.000, 0.000, -0.771, 0.000, 0.637)},
    }
    CAMERAS = {"side_pixels": {"pos": (0.4, -0.505, 0.762), "xyaxes": (1.0, 0.0, 0.0, 0.0, 0.771, 0.637)}}

    def __init__(
        self,
        env_type: str = "scene",
        ob_type: str = "states",
        permute_blocks: bool = True,
        multiview: bool = False,
        *args: Any,
        height: int = 200,
        width: int = 200,
        render_quality: str = "medium",
        render_mode: str | None = "rgb_array",
        **kwargs: Any,
    ):
        if env_type != "scene":
            raise ConfigError(f"SceneEnv requires env_type 'scene' (its only layout), got {env_type!r}")
        self._check_args(ob_type, render_quality, render_mode, kwargs)
        super().__init__(env_type, permute_blocks, *args, ob_type=ob_type, height=height, width=width, **kwargs)
        self._setup(multiview, render_quality, render_mode)
        self._lock_colors = np.array([LOCK_COLOR, LOCK_COLOR])
        cube = cube_space(1, self._cube_colors, *CUBE_BOUNDS, START, GOAL)
        self.variation_space = common_space(
            cube, ARM_BOUNDS, camera_limit=5.0, light=0.6, extra={"lock_color": box(0.0, 1.0, [LOCK_COLOR, LOCK_COLOR])}
        )

    def _state_ob_dim(self) -> int:
        return PROPRIO_DIM + 9 + 4 * self._num_buttons + 4  # + cube, buttons, drawer and window

    def _extra_state_dim(self) -> int:
        return self._num_buttons

    def post_compilation_objects(self) -> None:
        super().post_compilation_objects()
        m = self._model
        self._slide_qpos = [m.jnt_qposadr[m.joint(name).id] for name in ("drawer_slide", "window_slide")]
        self._handle_mats = [m.material(name).id for name in HANDLES]

    def _apply_factors(self) -> None:
        self._lock_colors = np.asarray(self.variation_space["lock_color"].value, np.float64)
        super()._apply_factors()

    def _apply_button_states(self) -> None:
        super()._apply_button_states()  # OGBench: damping locks, white / red colours
        for i, state in enumerate(self._cur_button_states):
            if state == 0:
                self._model.geom_rgba[self._button_geom_ids_list[i], :3] = self._lock_colors[i]
                self._model.mat_rgba[self._handle_mats[i], :3] = self._lock_colors[i]

    def _place_scene(self, which: str) -> None:
        """Arm, cube, buttons, drawer and window of the ``which`` ("start" / "goal") scene."""
        v = self.variation_space.value
        rng = self.np_random
        self._place_arm(v["agent"]["ee_start_position"], rng.uniform(-np.pi, np.pi))
        self._place_cubes(v["cube"][f"{which}_position"], v["cube"][f"{which}_yaw"])
        buttons = rng.integers(0, self._num_button_states, size=self._num_buttons)
        if which == "start":
            slides = (rng.uniform(*DRAWER_RANGE), rng.uniform(*WINDOW_RANGE))
        else:
            slides = (DRAWER_GOALS[rng.integers(2)], WINDOW_GOALS[rng.integers(2)])
        for adr, pos in zip(self._slide_qpos, slides, strict=True):
            self._data.qpos[adr] = pos
        self._cur_button_states = buttons.astype(np.int64)
        self._apply_button_states()

    def _aim_targets(self) -> None:
        super()._aim_targets()
        self._target_button_states = self._cur_button_states.copy()
        self._target_drawer_pos, self._target_window_pos = (float(self._data.qpos[a]) for a in self._slide_qpos)
        self._model.site("drawer_handle_center_target").pos[1] = self._target_drawer_pos
        self._model.site("window_handle_center_target").pos[0] = self._target_window_pos
        mujoco.mj_kinematics(self._model, self._data)

    # -- data collection (see :mod:`.manip`) -------------------------------------------------------
    def _set_slide_targets(self, drawer: float, window: float) -> None:
        self._target_drawer_pos, self._target_window_pos = float(drawer), float(window)
        self._model.site("drawer_handle_center_target").pos[1] = self._target_drawer_pos
        self._model.site("window_handle_center_target").pos[0] = self._target_window_pos
        mujoco.mj_kinematics(self._model, self._data)

    def _clear_targets(self) -> None:
        super()._clear_targets()
        self._target_task, self._target_button = "cube", 0
        self._target_button_states = self._cur_button_states.copy()
        self._set_slide_targets(*(float(self._data.qpos[a]) for a in self._slide_qpos))

    def _draw_target(self, p_stack: float) -> None:
        """OGBench's Scene subtask (module docstring), drawn from ``np_random``."""
        rng = self.np_random
        drawer, window = (float(self._data.qpos[a]) for a in self._slide_qpos)
        xyz = self._cube_xyz()
        loose = [i for i in range(self._num_cubes) if not self._is_in_drawer(xyz[i])]
        locked = [self._cur_button_states[k] == 0 for k in range(2)]
        weights = np.array([1.0 if loose else 0.0, 1.0, *(LOCKED_WEIGHT if lock else 1.0 for lock in locked)])
        task = self._target_task = str(rng.choice(SUBTASKS, p=weights / weights.sum()))
        if task == "cube":
            spot = None
            if drawer < DRAWER_OPEN and rng.uniform() < P_INTO_DRAWER:
                spot = self._drawer_center.copy()
                spot[:2] += rng.uniform(-DRAWER_JITTER, DRAWER_JITTER, size=2)
            self._draw_cube_target(loose, p_stack, spot)
        elif task == "button":
            k = self._target_button = int(rng.choice(self._num_buttons))
            self._target_button_states[k] = (self._cur_button_states[k] + 1) % self._num_button_states
        elif task == "drawer":
            self._set_slide_targets(
                DRAWER_GOALS[1] if drawer >= DRAWER_CLOSED else DRAWER_GOALS[0], self._target_window_pos
            )
        else:
            self._set_slide_targets(
                self._target_drawer_pos, WINDOW_GOALS[1] if window <= WINDOW_CLOSED else WINDOW_GOALS[0]
            )
        mujoco.mj_kinematics(self._model, self._data)

    def _complete_subtask(self) -> None:
        task = self._target_task
        if task == "cube":
            super()._complete_subtask()
        elif task == "button":
            k = self._target_button
            self._cur_button_states[k] = self._target_button_states[k]
            self._apply_button_states()
        elif task == "drawer":
            self._data.qpos[self._slide_qpos[0]] = self._target_drawer_pos
        else:
            self._data.qpos[self._slide_qpos[1]] = self._target_window_pos

    def _snapshot(self) -> tuple:
        return (*super()._snapshot(), self._cur_button_states.copy())

    def _restore(self, saved: tuple) -> None:
        self._cur_button_states = saved[3].copy()
        self._apply_button_states()
        super()._restore(saved)

    def _state_vector(self) -> np.ndarray:
        return np.concatenate([super()._state_vector(), self._cur_button_states.astype(np.float64)])

    def _set_state_vector(self, state: np.ndarray) -> None:
        buttons = np.rint(state[-self._num_buttons :]).astype(np.int64)
        if np.any((buttons < 0) | (buttons >= self._num_button_states)):
            raise ConfigError(
                f"SceneEnv requires button states of 0 or 1 at the end of the state, got {state[-self._num_buttons :]}"
            )
        self._cur_button_states = buttons
        self._apply_button_states()
        super()._set_state_vector(state[: -self._num_buttons])

    def _extra_success(self, goal: np.ndarray, cur: np.ndarray) -> tuple[bool, float]:
        k = self._num_buttons
        wrong = int(np.sum(np.rint(goal[-k:]) != np.rint(cur[-k:])))
        slides = [abs(float(cur[a] - goal[a])) for a in self._slide_qpos]
        return wrong == 0 and max(slides) <= SLIDE_TOLERANCE, float(sum(slides) + wrong)

    def add_object_info(self, ob_info: dict) -> None:
        super().add_object_info(ob_info)
        for i, site in enumerate(self._button_site_ids):
            ob_info[f"privileged/button_{i}_top_pos"] = self._data.site_xpos[site].copy()
        ob_info["privileged/target_button_states"] = np.asarray(self._target_button_states).copy()
        ob_info["privileged/target_drawer_pos"] = np.array([self._target_drawer_pos])
        ob_info["privileged/target_drawer_handle_pos"] = self._data.site_xpos[self._drawer_target_site_id].copy()
        ob_info["privileged/target_window_pos"] = np.array([self._target_window_pos])
        ob_info["privileged/target_window_handle_pos"] = self._data.site_xpos[self._window_target_site_id].copy()

"""``swm/OGBCube-v0``: OGBench's Cube (a UR5e arm with a Robotiq gripper moves 1-4 cubes to
their goals), as upstream 0.1.1 exposes it, on top of ``ogbench.manipspace`` (this class
subclasses OGBench's ``CubeEnv``; the shared machinery is :mod:`.manip`, the factors
:mod:`.factors`).

- **Constructor**: ``CubeEnv(env_type='single', ob_type='states', permute_blocks=True,
  multiview=False, height=224, width=224, *args, render_quality='medium', render_mode='rgb_array',
  **kwargs)``; ``env_type`` is one of single / double / triple / quadruple (1-4 cubes), other
  keywords go to OGBench's env (``terminate_at_goal``, ``visualize_info``, ``reward_task_id``...).
- **Spaces**: observation ``Box(19 + 9 N)`` float64 (OGBench's state observation: arm
  proprioception, then per cube its position, quaternion and yaw cos / sin), or the
  ``(H, W, 3)`` frame for ``ob_type='pixels'``; action ``Box(-1, 1, (5,), float32)`` (effector
  dx, dy, dz, dyaw, gripper). ``env_name`` is ``'Cube'``.
- **Factors**: :mod:`.factors` (upstream's names, bounds and defaults). A reset resamples
  ``cube.start_position / start_yaw / goal_position / goal_yaw`` unless ``options["variation"]``
  names the factors to resample.
- **Episode**: the arm starts with its effector at ``agent.ee_start_position`` pointing down with a
  random yaw, each cube at its start position and yaw (on the floor, or stacked when positions
  coincide). The goal scene has the cubes at their goal positions / yaws; each cube's target
  (the translucent cube) is where its goal-scene cube rests.
- **Success** (OGBench's task rule): every cube within 4 cm of its target; ``terminated`` then
  (``terminate_at_goal``), reward 1.0 on success else 0.0, never truncated by the env (the swm
  tools cut episodes at 200 steps, OGBench's length). :meth:`eval_state` applies the same rule
  to two states (distance: the norm of the cube position errors).
- **Rendering**: ``render()`` draws the ``front_pixels`` camera at the render size
  (``set_render_size``); ``multiview=True`` makes ``render_multiview()`` return
  ``{front, front_pixels, side_pixels, side}``. ``render_quality="high"`` is upstream's picture;
  ``"medium"`` (default) draws nearly the same picture (mean absolute difference ~0.7/255 at
  64x64) several times faster: a smaller shadow map, the arm's meshes decimated to 10 % of
  their faces and the floor drawn with a 3 cm grid instead of 1 cm, both for drawing only
  (:mod:`.meshes`), and no floor in the shadow map; ``"low"`` also drops shadows and multisampling.

Deliberate differences from upstream 0.1.1:

- The cube factors place the cubes. Upstream samples ``cube.start_*`` / ``cube.goal_*`` but
  places the cubes by one of OGBench's five task presets, drawn from the global ``np.random``, so
  its resets are not reproducible from the seed; here ``reset(seed)`` fixes everything. The
  defaults of ``cube.start_position`` / ``cube.goal_position`` (both ``[0.3, 0]`` upstream, where
  they were never used) are a row of cubes at x = 0.35 and their goals at x = 0.5, so an episode
  that keeps the defaults is not solved at its first step.
- Sampled layouts follow the rules of :mod:`.factors` (cubes apart, goal >= 8 cm from start and
  clear of other cubes' starts); ``octuple`` (8 cubes) is refused: 8 starts and 8 goals do not
  fit those rules on the table.
- The goal scene's arm is at ``agent.ee_start_position`` (random yaw) and settles with two
  zero actions (OGBench: a random arm pose and two random actions).
- A cube of a ``cube.color`` on its target is tinted 80 % towards white, as OGBench's own colours.
- Factors are applied to the compiled model: no recompilation per reset (upstream recompiles
  every reset).
- The ``side`` view (upstream: looking past the table into the sky) looks at the table from the
  side like ``side_pixels``, from the ``front`` camera's distance.
- OGBench's info entries are named with ``.`` instead of ``/`` (``proprio.joint_pos``,
  ``privileged.block_0_pos``): our HDF5 datasets cannot hold ``proprio/joint_pos`` next to the
  ``proprio`` column (:mod:`.infokeys`). Infos add ``goal`` / ``state`` / ``proprio`` /
  ``goal_state`` / ``goal_proprio`` and ``privileged.target_block_<i>_pos`` / ``_yaw`` (for the
  expert).
- ``render_mode`` defaults to ``'rgb_array'``; ``set_new_target()`` also works in ``mode='task'``
  (a new goal scene mid-episode; OGBench's needs its data-collection mode).
- ``mode='data_collection'`` (:mod:`.manip`): the cubes start at ``cube.start_position`` (stacked
  where positions coincide; upstream puts every cube on the floor), the arm at
  ``agent.ee_start_position``; a cube subtask's target is ``cube.goal_position`` /
  ``cube.goal_yaw`` of *that* cube's row (upstream: row 0 whatever the cube) and both are redrawn
  for each new target (upstream keeps the reset's values, so a single cube gets the same target
  again and again); a stacking target rests on the cube below by the two cubes' sizes (upstream:
  4 cm, the default sizes). Everything is drawn from the reset seed.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..._optional import require
from ...errors import ConfigError, did_you_mean
from .factors import common_space, cube_space
from .manip import PROPRIO_DIM, ManipMixin, mujoco

_OGBCubeEnv = require("ogbench.manipspace.envs.cube_env", extra="mujoco", purpose="swm/OGBCube-v0").CubeEnv

ENV_TYPES = {"single": 1, "double": 2, "triple": 3, "quadruple": 4}
CUBE_BOUNDS = ((0.3, -0.3), (0.55, 0.3))
ARM_BOUNDS = np.array([[0.25, -0.35, 0.2], [0.6, 0.35, 0.35]])
START_X, GOAL_X, ROW_STEP = 0.35, 0.5, 0.1  # default layout: a row of cubes, goals in a parallel row


class CubeEnv(ManipMixin, _OGBCubeEnv):
    """OGBench's Cube with factors of variation (see the module docstring)."""

    ENV_NAME = "Cube"
    OGB_CAMERAS = {
        "front": {"pos": (1.287, 0.000, 0.509), "xyaxes": (0.000, 1.000, 0.000, -0.342, 0.000, 0.940)},
        "front_pixels": {"pos": (1.053, -0.014, 0.639), "xyaxes": (0.000, 1.000, 0.000, -0.628, 0.001, 0.778)},
    }
    CAMERAS = {
        "side_pixels": {"pos": (0.414, -0.753, 0.639), "xyaxes": (1.000, 0.000, 0.000, -0.001, 0.628, 0.778)},
        "side": {"pos": (0.425, -0.862, 0.509), "xyaxes": (1.000, 0.000, 0.000, 0.000, 0.342, 0.940)},
    }

    def __init__(
        self,
        env_type: str = "single",
        ob_type: str = "states",
        permute_blocks: bool = True,
        multiview: bool = False,
        height: int = 224,
        width: int = 224,
        *args: Any,
        render_quality: str = "medium",
        render_mode: str | None = "rgb_array",
        **kwargs: Any,
    ):
        if env_type not in ENV_TYPES:
            raise ConfigError(
                f"CubeEnv requires env_type in {list(ENV_TYPES)}, got {env_type!r}."
                f"{did_you_mean(str(env_type), ENV_TYPES)}"
            )
        self._check_args(ob_type, render_quality, render_mode, kwargs)
        super().__init__(env_type, permute_blocks, *args, ob_type=ob_type, height=height, width=width, **kwargs)
        self._setup(multiview, render_quality, render_mode)
        n = self._num_cubes
        rows = (np.arange(n) - (n - 1) / 2) * ROW_STEP
        cube = cube_space(
            n,
            self._cube_colors,
            *CUBE_BOUNDS,
            np.stack([np.full(n, START_X), rows], 1),
            np.stack([np.full(n, GOAL_X), rows], 1),
        )
        self.variation_space = common_space(cube, ARM_BOUNDS, camera_limit=10.0, light=0.7)

    def _state_ob_dim(self) -> int:
        return PROPRIO_DIM + 9 * self._num_cubes  # + per cube: position, quaternion, yaw cos / sin

    def _draw_target(self, p_stack: float) -> None:
        """OGBench's Cube subtask: a free cube to its goal, or onto another free cube."""
        self._draw_cube_target(list(range(self._num_cubes)), p_stack)

    def _place_scene(self, which: str) -> None:
        """Arm at the effector start (random yaw) and cubes at their ``which`` ("start"/"goal") poses."""
        v = self.variation_space.value
        self._place_arm(v["agent"]["ee_start_position"], self.np_random.uniform(-np.pi, np.pi))
        self._place_cubes(v["cube"][f"{which}_position"], v["cube"][f"{which}_yaw"])
        mujoco.mj_forward(self._model, self._data)

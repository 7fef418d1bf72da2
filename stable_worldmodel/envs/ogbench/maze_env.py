"""``swm/OGBMaze-v0``: OGBench's locomotion mazes (a point mass, an ant or a humanoid walks to a
goal cell; or the ant dribbles a ball to it), as upstream's main exposes them, with factors of
variation. The physics are OGBench's locomotion envs (``ogbench.locomaze.point`` / ``ant`` /
``humanoid``, stepped as OGBench does); the maze, its tasks and the goal logic are OGBench's
``make_maze_env`` rules, written here so that one seed fixes every draw (:mod:`.maze_layout`
holds the maps and tasks).

- **Constructor**: ``MazeEnv(loco_env_type='point', maze_env_type='maze', maze_type='large',
  ob_type='states', width=224, height=224, *, render_quality='medium', render_mode='rgb_array',
  camera_name=None, maze_unit=4.0, maze_height=0.5, terminate_at_goal=True,
  success_timing='post', add_noise_to_goal=True, reward_task_id=None, use_oracle_rep=False,
  reset_noise_scale=...)``. ``loco_env_type``: point / ant / humanoid; ``maze_env_type``:
  ``'maze'`` (reach the goal) or ``'ball'`` (OGBench's soccer: bring the ball to the goal; ant
  only, arena / medium mazes); ``maze_type``: arena / medium / large / giant / teleport.
  ``reset_noise_scale`` (ant / humanoid) goes to OGBench's locomotion env.
- **Spaces**: observation as OGBench's: for ``ob_type='states'`` the locomotion env's state
  observation (point: x, y; ant: qpos ++ qvel, 29 numbers; humanoid: 69), for ``'pixels'`` the
  ``(H, W, 3)`` frame at the render size; action: point ``Box(-1, 1, (2,))`` (the position moves
  by ``0.2 * action``), ant ``(8,)``, humanoid ``(21,)`` (motor controls).
- **Factors** (upstream's names and ranges; none is resampled by default, as upstream)::

      agent.color          (3,)    material "self" of the agent          default (0.7, 0.5, 0.3)
      wall.color           (3,)    material "wall"                       default white (states), 0.6 grey (pixels)
      floor.color          (2, 3)  the two colours of the floor checker  default OGBench's dark blues
      floor.pixel_encoding {0, 1}  1: OGBench's position-encoding floor gradient (red: row, green: column)
      light.intensity      (1,)    diffuse intensity of the global light default 1.0

- **Episode** (OGBench's rules): a task is drawn (OGBench's five evaluation tasks of the maze,
  or ``options["task_id"]`` in 1..5, ``options["task_info"]``, or ``reward_task_id``); the start
  and the goal are the task's cell centres jittered by up to +-1 m per axis (the goal only with
  ``add_noise_to_goal``). The goal scene is the agent after a reset and 5 random actions (40 for
  the humanoid; the ball maze 10) moved to the goal (with the ball there too); its image is
  ``info["goal"]``. Then the agent (and ball) are reset to the start.
- **Success**: the agent (ball maze: the ball) within ``1.0`` m (point) or ``0.5`` m (ant,
  humanoid) of the goal, checked after the step (``success_timing='pre'``: before it);
  ``terminated`` then (``terminate_at_goal``), reward 1.0 on success else 0.0 (minus 1 in the
  single-task mode of ``reward_task_id``); never truncated by the env (the swm tools cut episodes
  at OGBench's 1000 steps). :meth:`eval_state` applies the same rule to two states.
- **Teleport maze**: an agent within 1.5 m of an inbound pad is moved to one of the three
  outbound pads, drawn from the env's seeded generator.
- **Info**: OGBench's ``xy``, ``prev_qpos``, ``prev_qvel``, ``qpos``, ``qvel``, ``success`` (also at
  reset), plus ``env_name`` (``PointMaze`` / ``AntMaze`` / ``HumanoidMaze``, ``AntSoccer`` for the
  ball), ``target`` (OGBench's goal observation: the goal scene's observation, or the goal xy with
  ``use_oracle_rep``), ``state`` (``qpos ++ qvel``), ``proprio`` (the agent's state observation:
  the ball's coordinates left out), ``goal`` (image), ``goal_state``, ``goal_proprio``.
- **Rendering**: OGBench's top-down view of the whole maze (a fixed camera ``maze_top`` placed as
  OGBench's custom free camera), or ``camera_name`` (e.g. the ant's tracking ``back`` camera, as
  OGBench's visual mazes); drawn headless through
  :class:`~stable_worldmodel.envs.mujoco_render.MjRenderer` at the render size
  (``set_render_size``, initially ``(height, width)``) and ``render_quality``.

Deliberate differences from upstream's main (which wraps ``make_maze_env`` and recompiles its
model when a factor changes):

- Everything is drawn from the reset seed: the task, the start / goal jitter, the settling
  actions, the teleport exits (OGBench draws them from the global ``np.random``, so upstream's
  resets are not reproducible).
- Factors are written into the compiled model (no recompilation); ``floor.pixel_encoding``
  works for ``ob_type='states'`` too (the gradient then spans the floor, as in pixel mode).
- Actions are clipped to the action space (the point moved by any action upstream; MuJoCo already
  clamps the ant's and humanoid's controls).
- After a teleport the step returns the observation of the teleported agent (OGBench: of the pad).
- Reset infos carry the step keys (OGBench's reset info has only ``goal``); ``info["goal"]`` is the
  goal image (upstream too) and OGBench's goal observation is ``info["target"]``. Reset option
  ``render_goal=False`` (upstream's) leaves the image out.
- Reset options ``state`` / ``goal_state`` (``qpos ++ qvel``) start from / aim at a given state
  (upstream: ``state`` only).
"""

from __future__ import annotations

import tempfile
import xml.etree.ElementTree as ET
from collections.abc import Mapping
from typing import Any

import gymnasium as gym
import numpy as np

from ... import keys, spaces
from ..._optional import require
from ...errors import ConfigError, check_int, did_you_mean, unknown_name
from ..base import DatasetResetMixin, check_render_size, checked_reset_options
from ..mujoco_render import MjRenderer, OwnsRenderer, check_render_quality, setup_gl
from .factors import box
from .maze_layout import (
    BALL_TASKS,
    DEFAULT_TASK,
    MAZE_TYPES,
    NOISE,
    TASKS,
    TELEPORT_IN,
    TELEPORT_OUT,
    TELEPORT_RADIUS,
    MazeLayout,
    check_maze_type,
)

setup_gl()  # before mujoco is imported
mujoco = require("mujoco", purpose="swm/OGBMaze-v0")
require("ogbench.locomaze", extra="mujoco", purpose="swm/OGBMaze-v0")

LOCO_TYPES = {
    "point": ("ogbench.locomaze.point", "PointEnv"),
    "ant": ("ogbench.locomaze.ant", "AntEnv"),
    "humanoid": ("ogbench.locomaze.humanoid", "HumanoidEnv"),
}
MAZE_ENV_TYPES = ("maze", "ball")
ENV_NAMES = {"point": "PointMaze", "ant": "AntMaze", "humanoid": "HumanoidMaze"}
GOAL_TOL = {"point": 1.0, "ant": 0.5, "humanoid": 0.5}  # OGBench's _goal_tol
SETTLE_ACTIONS = {"point": 5, "ant": 5, "humanoid": 40}  # random actions before the goal scene
BALL_SETTLE_ACTIONS = 10
LOCO_KWARGS = {"point": (), "ant": ("reset_noise_scale",), "humanoid": ("reset_noise_scale",)}
BALL_QPOS, BALL_QVEL = 7, 6  # the ball's free joint, last in qpos / qvel
TOP_CAMERA = "maze_top"
ENCODING_MAX = 192  # OGBench's floor gradient: red = row / height * 192, green = column / width * 192, blue 128
DEFAULT_VARIATIONS = ()  # as upstream: nothing is resampled unless options["variation"] names it
_ENCODINGS: dict[tuple[int, int], np.ndarray] = {}
FLOOR_COLORS = ((0.08, 0.11, 0.16), (0.15, 0.18, 0.25))  # rgb1 / rgb2 of OGBench's floor checker


def _encoding(h: int, w: int) -> np.ndarray:
    """OGBench's position-encoding floor texture ``(h, w, 3)`` uint8 (cached per size)."""
    if (h, w) not in _ENCODINGS:
        rows, cols = np.meshgrid(np.arange(h), np.arange(w), indexing="ij")
        red, green = (rows / h * ENCODING_MAX).astype(np.uint8), (cols / w * ENCODING_MAX).astype(np.uint8)
        _ENCODINGS[(h, w)] = np.stack([red, green, np.full((h, w), 128, np.uint8)], axis=-1)
    return _ENCODINGS[(h, w)]


def _texel(color) -> np.ndarray:
    """A colour as MuJoCo writes it into a builtin texture (``255 * c`` truncated)."""
    return (255.0 * np.asarray(color, np.float64)).astype(np.uint8)


class MazeEnv(OwnsRenderer, DatasetResetMixin, gym.Env):
    """OGBench's locomotion mazes with factors of variation (see the module docstring)."""

    metadata = {"render_modes": ["rgb_array"], "render_fps": 10}

    def __init__(
        self,
        loco_env_type: str = "point",
        maze_env_type: str = "maze",
        maze_type: str = "large",
        ob_type: str = "states",
        width: int = 224,
        height: int = 224,
        *,
        render_quality: str = "medium",
        render_mode: str | None = "rgb_array",
        camera_name: str | None = None,
        maze_unit: float = 4.0,
        maze_height: float = 0.5,
        terminate_at_goal: bool = True,
        success_timing: str = "post",
        add_noise_to_goal: bool = True,
        reward_task_id: int | None = None,
        use_oracle_rep: bool = False,
        **kwargs: Any,
    ):
        owner = type(self).__name__
        if loco_env_type not in LOCO_TYPES:
            raise ConfigError(
                f"{owner} requires loco_env_type in {list(LOCO_TYPES)}, got {loco_env_type!r}."
                f"{did_you_mean(str(loco_env_type), LOCO_TYPES)}"
            )
        if maze_env_type not in MAZE_ENV_TYPES:
            raise ConfigError(
                f"{owner} requires maze_env_type in {list(MAZE_ENV_TYPES)}, got {maze_env_type!r}."
                f"{did_you_mean(str(maze_env_type), MAZE_ENV_TYPES)}"
            )
        ball = maze_env_type == "ball"
        if ball and loco_env_type != "ant":
            raise ConfigError(
                f"{owner} requires loco_env_type 'ant' for maze_env_type 'ball' (OGBench's soccer), "
                f"got {loco_env_type!r}"
            )
        check_maze_type(owner, maze_type, tuple(BALL_TASKS) if ball else MAZE_TYPES)
        if ob_type not in ("states", "pixels"):
            raise ConfigError(f"{owner} requires ob_type 'states' or 'pixels', got {ob_type!r}")
        if success_timing not in ("pre", "post"):
            raise ConfigError(f"{owner} requires success_timing 'pre' or 'post', got {success_timing!r}")
        if render_mode not in (None, "rgb_array"):
            raise ConfigError(f"{owner} requires render_mode 'rgb_array' or None, got {render_mode!r}")
        self.render_quality = check_render_quality(owner, render_quality)
        h, w = check_int(owner, "height", height), check_int(owner, "width", width)
        for name, value in (("maze_unit", maze_unit), ("maze_height", maze_height)):
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not np.isfinite(value) or value <= 0:
                raise ConfigError(f"{owner} requires {name} > 0, got {value!r}")
        for name in kwargs:
            if name not in LOCO_KWARGS[loco_env_type]:
                raise unknown_name(f"keyword argument of {owner} (loco_env_type {loco_env_type!r})", name, [
                    *LOCO_KWARGS[loco_env_type], "render_quality", "render_mode", "camera_name", "maze_unit",
                    "maze_height", "terminate_at_goal", "success_timing", "add_noise_to_goal", "reward_task_id",
                    "use_oracle_rep",
                ])  # fmt: skip
        self.loco_env_type, self.maze_env_type, self.maze_type = loco_env_type, maze_env_type, maze_type
        self._ob_type, self._ball = ob_type, ball
        self.maze_layout = MazeLayout(maze_type, float(maze_unit))
        self._maze_height = float(maze_height)
        self._terminate_at_goal, self._success_timing = bool(terminate_at_goal), success_timing
        self._add_noise_to_goal, self._use_oracle_rep = bool(add_noise_to_goal), bool(use_oracle_rep)
        self.task_infos = self._task_infos()
        self.num_tasks = len(self.task_infos)
        if reward_task_id is not None:
            reward_task_id = self._check_task_id("reward_task_id", reward_task_id, allow_zero=True)
            reward_task_id = reward_task_id or DEFAULT_TASK[maze_env_type]
        self._reward_task_id = reward_task_id
        self._goal_tol = GOAL_TOL[loco_env_type]
        self.env_name = "AntSoccer" if ball else ENV_NAMES[loco_env_type]
        self.render_mode = render_mode
        self._render_height, self._render_width = h, w

        module, cls_name = LOCO_TYPES[loco_env_type]
        loco_cls = getattr(require(module, extra="mujoco", purpose="swm/OGBMaze-v0"), cls_name)
        with tempfile.TemporaryDirectory(prefix="swm_ogbmaze_") as tmp:  # OGBench's envs load a file
            path = f"{tmp}/maze.xml"
            with open(path, "w") as f:
                f.write(self._maze_xml(loco_cls))
            self._loco = loco_cls(xml_file=path, render_mode=None, width=w, height=h, **kwargs)
        self._model, self._data = self._loco.model, self._loco.data
        if camera_name is not None:
            names = [self._model.camera(i).name for i in range(self._model.ncam)]
            if camera_name not in names:
                raise ConfigError(
                    f"{owner} requires camera_name among the model's cameras {names}, got {camera_name!r}."
                    f"{did_you_mean(str(camera_name), names)}"
                )
        self._camera = camera_name or TOP_CAMERA
        self._target_geom = self._model.geom("target").id if ob_type == "states" else None
        self._look = _MazeLook(self._model)
        self.variation_space = self._make_variation_space()

        self._action_space = self._loco.action_space
        self._observation_space = self._make_observation_space()
        self._mjr: MjRenderer | None = None
        self._goal: dict[str, Any] | None = None
        self._goal_xy = np.zeros(2)
        self.cur_task_id: int | None = None
        self.cur_task_info: dict[str, Any] | None = None
        self._render_goal = True
        self._reset_done = False

    # -- construction ---------------------------------------------------------------------------
    def _task_infos(self) -> list[dict[str, Any]]:
        """OGBench's task list (``task_name``, start / goal cells and xy)."""
        L = self.maze_layout
        if self._ball:
            return [
                {
                    "task_name": f"task{k + 1}",
                    "agent_init_ij": a,
                    "agent_init_xy": tuple(L.ij_to_xy(a)),
                    "ball_init_ij": b,
                    "ball_init_xy": tuple(L.ij_to_xy(b)),
                    "goal_ij": g,
                    "goal_xy": tuple(L.ij_to_xy(g)),
                }
                for k, (a, b, g) in enumerate(BALL_TASKS[self.maze_type])
            ]
        return [
            {
                "task_name": f"task{k + 1}",
                "init_ij": s,
                "init_xy": tuple(L.ij_to_xy(s)),
                "goal_ij": g,
                "goal_xy": tuple(L.ij_to_xy(g)),
            }
            for k, (s, g) in enumerate(TASKS[self.maze_type])
        ]

    def _maze_xml(self, loco_cls) -> str:
        """The maze's MJCF: OGBench's locomotion asset plus walls, as OGBench's ``update_tree``."""
        tree = ET.parse(loco_cls.xml_file)
        self._build_maze(tree)
        return ET.tostring(tree.getroot(), encoding="unicode")

    def _build_maze(self, tree: ET.ElementTree) -> None:
        L, unit, height = self.maze_layout, self.maze_layout.unit, self._maze_height
        world = tree.find(".//worldbody")
        for i, j in L.wall_cells():
            x, y = L.ij_to_xy((i, j))
            ET.SubElement(world, "geom", name=f"block_{i}_{j}", pos=f"{x} {y} {height / 2 * unit}",
                          size=f"{unit / 2} {unit / 2} {height / 2 * unit}", type="box", contype="1",
                          conaffinity="1", material="wall")  # fmt: skip
        rows, cols = L.shape
        floor = tree.find(".//geom[@name='floor']")
        floor.set("pos", f"{2 * (cols - 3)} {2 * (rows - 3)} 0")
        floor.set("size", f"{2 * cols} {2 * rows} 0.2")
        # OGBench's custom view: looking straight down at the maze centre from 5 * (cols - 2) m
        ET.SubElement(world, "camera", name=TOP_CAMERA, pos=f"{2 * (cols - 3)} {2 * (rows - 3)} {5 * (cols - 2)}",
                      xyaxes="1 0 0 0 1 0")  # fmt: skip
        if self.maze_type == "teleport":
            for kind, cells in (("in", TELEPORT_IN), ("out", TELEPORT_OUT)):
                for k, ij in enumerate(cells):
                    x, y = L.ij_to_xy(ij)
                    ET.SubElement(world, "geom", name=f"teleport_{kind}_{k}", type="cylinder",
                                  size=f"{TELEPORT_RADIUS} .05", pos=f"{x} {y} .05", material=f"teleport_{kind}",
                                  contype="0", conaffinity="0")  # fmt: skip
        if self._ob_type == "pixels":  # OGBench's look for pixel observations
            tree.find(".//material[@name='wall']").set("rgba", ".6 .6 .6 1")
            tree.find(".//light[@name='global']").attrib.pop("ambient", None)
            parent = tree.find(".//light[@name='torso_light']/..")
            parent.remove(parent.find("light[@name='torso_light']"))
            tree.find(".//material[@name='grid']").set("texuniform", "false")
            if self.loco_env_type == "ant":  # one white leg breaks the symmetry
                for geom in ("aux_1_geom", "left_leg_geom", "left_ankle_geom"):
                    tree.find(f".//geom[@name='{geom}']").set("material", "self_white")
        else:  # the goal marker, for state observations only (as OGBench)
            ET.SubElement(world, "geom", name="target", type="cylinder", size=".5 .05", pos="0 0 .05",
                          material="target", contype="0", conaffinity="0")  # fmt: skip
        if self._ball:
            body = ET.SubElement(world, "body", name="ball", pos="0 0 0.5")
            ET.SubElement(body, "freejoint", name="ball_root")
            ET.SubElement(body, "geom", name="ball", size=".25", material="ball", priority="1", conaffinity="1",
                          condim="6")  # fmt: skip
            ET.SubElement(body, "light", name="ball_light", pos="0 0 4", mode="trackcom")

    def _make_variation_space(self) -> spaces.Dict:
        look = self._look
        return spaces.Dict(
            {
                "agent": spaces.Dict({"color": box(0.0, 1.0, look.agent_color0)}),
                "wall": spaces.Dict({"color": box(0.0, 1.0, look.wall_color0)}),
                "floor": spaces.Dict(
                    {"color": box(0.0, 1.0, look.floor_colors0), "pixel_encoding": spaces.Discrete(2, init_value=0)}
                ),
                "light": spaces.Dict({"intensity": box(0.0, 1.0, [look.intensity0])}),
            },
            sampling_order=["agent", "wall", "floor", "light"],
        )

    @property
    def action_space(self) -> gym.spaces.Box:  # one object, so that seeding it sticks
        return self._action_space

    @property
    def observation_space(self) -> gym.spaces.Box:
        return self._observation_space

    def _make_observation_space(self) -> gym.spaces.Box:
        if self._ob_type == "pixels":  # frames at the render size
            return gym.spaces.Box(0, 255, (self._render_height, self._render_width, 3), np.uint8)
        return gym.spaces.Box(-np.inf, np.inf, (len(self._loco.get_ob()),), np.float64)

    # -- reset ----------------------------------------------------------------------------------
    def reset(self, *, seed: int | None = None, options: Mapping[str, Any] | None = None):
        gym.Env.reset(self, seed=seed)
        opts = self._check_options(options)
        rng = self.np_random
        spaces.reset_variation_space(self.variation_space, int(rng.integers(0, 2**31 - 1)), opts, DEFAULT_VARIATIONS)
        self._apply_factors()
        loco_seed = int(rng.integers(0, 2**31 - 1))
        self._choose_task(opts)
        info = self.cur_task_info
        init_key = "agent_init_xy" if self._ball else "init_xy"
        init_xy = self._jitter(info[init_key])
        ball_xy = self._jitter(info["ball_init_xy"]) if self._ball else None
        goal_xy = np.asarray(info["goal_xy"], np.float64)
        if self._add_noise_to_goal:
            goal_xy = self._jitter(goal_xy)
        self._render_goal = bool(opts.get("render_goal", True))

        # the goal scene: settled by random actions, then moved to the goal
        self._loco.reset(seed=loco_seed)
        n_settle = BALL_SETTLE_ACTIONS if self._ball else SETTLE_ACTIONS[self.loco_env_type]
        low, high = self._action_space.low, self._action_space.high
        for _ in range(n_settle):
            self._loco.step(rng.uniform(low, high).astype(np.float32))
        goal_state = opts.get(keys.GOAL_STATE)
        if goal_state is None:
            self._set_goal(goal_xy)
            self._place(goal_xy, goal_xy if self._ball else None)
        else:
            self._set_state_vector(goal_state)
            self._set_goal(self._tracked_xy(goal_state))
        self._capture_goal()

        # the start
        self._loco.reset()  # continues the locomotion env's seeded stream
        self._set_goal(self._goal_xy)
        self._place(init_xy, ball_xy)
        if opts.get(keys.STATE) is not None:
            self._set_state_vector(opts[keys.STATE])
        self._reset_done = True
        qpos, qvel = self._data.qpos.copy(), self._data.qvel.copy()
        loco_info = {"xy": self._loco.get_xy(), "prev_qpos": qpos, "prev_qvel": qvel, "qpos": qpos, "qvel": qvel}
        return self._observation(), self._info(loco_info, False)

    def _check_options(self, options: Any) -> dict[str, Any]:
        owner = type(self).__name__
        if options is None:
            return {}
        out = checked_reset_options(owner, options, self.variation_space.names())
        for key in (keys.STATE, keys.GOAL_STATE):
            if out.get(key) is not None:
                out[key] = self._check_state(f"reset option {key!r}", out[key])
        if out.get("task_id") is not None:
            out["task_id"] = self._check_task_id("reset option 'task_id'", out["task_id"])
        task_info = out.get("task_info")
        if task_info is not None:
            need = ("agent_init_xy", "ball_init_xy", "goal_xy") if self._ball else ("init_xy", "goal_xy")
            if not isinstance(task_info, Mapping) or any(k not in task_info for k in need):
                raise ConfigError(
                    f"{owner}.reset requires options['task_info'] as a dict with {list(need)}, got {task_info!r}"
                )
        return out

    def _check_task_id(self, what: str, value: Any, allow_zero: bool = False) -> int:
        low = 0 if allow_zero else 1
        if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or not low <= value <= self.num_tasks:
            raise ConfigError(
                f"{type(self).__name__} requires {what} in [{low}, {self.num_tasks}] (the {self.maze_type} maze's "
                f"tasks), got {value!r}"
            )
        return int(value)

    def _check_state(self, what: str, value: Any) -> np.ndarray:
        """``value`` as a flat ``qpos ++ qvel`` vector; ConfigError naming ``what`` otherwise."""
        try:
            arr = np.asarray(value, np.float64).reshape(-1)
        except (TypeError, ValueError) as exc:
            raise ConfigError(f"{type(self).__name__} requires {what} as numbers, got {value!r}") from exc
        dim = self._model.nq + self._model.nv
        if arr.shape[0] != dim or not np.all(np.isfinite(arr)):
            raise ConfigError(
                f"{type(self).__name__} requires {what} of {dim} finite numbers (qpos, qvel, as "
                f"info[{keys.STATE!r}]), got shape {np.shape(value)}"
            )
        return arr

    def _choose_task(self, opts: Mapping[str, Any]) -> None:
        """OGBench's order: the single-task id, then ``task_id``, then ``task_info``, else a random task."""
        if self._reward_task_id is not None or opts.get("task_id") is not None:
            tid = self._reward_task_id if self._reward_task_id is not None else opts["task_id"]
            self.cur_task_id, self.cur_task_info = tid, self.task_infos[tid - 1]
        elif opts.get("task_info") is not None:
            self.cur_task_id, self.cur_task_info = None, dict(opts["task_info"])
        else:
            tid = int(self.np_random.integers(1, self.num_tasks + 1))
            self.cur_task_id, self.cur_task_info = tid, self.task_infos[tid - 1]

    def _jitter(self, xy) -> np.ndarray:
        """OGBench's noise: up to +-NOISE * unit / 4 per axis."""
        scale = NOISE * self.maze_layout.unit / 4
        return np.asarray(xy, np.float64)[:2] + self.np_random.uniform(-1.0, 1.0, 2) * scale

    def _set_goal(self, goal_xy) -> None:
        self._goal_xy = np.asarray(goal_xy, np.float64)[:2].copy()
        if self._target_geom is not None:
            self._model.geom_pos[self._target_geom, :2] = self._goal_xy

    def _place(self, agent_xy, ball_xy=None) -> None:
        qpos, qvel = self._data.qpos.copy(), self._data.qvel.copy()
        qpos[:2] = agent_xy
        if ball_xy is not None:
            qpos[-BALL_QPOS : -BALL_QPOS + 2] = ball_xy
        self._loco.set_state(qpos, qvel)

    def _set_state_vector(self, state: np.ndarray) -> None:
        nq = self._model.nq
        self._loco.set_state(state[:nq], state[nq:])

    def _tracked_xy(self, state: np.ndarray) -> np.ndarray:
        """What success measures in ``state``: the agent's xy (ball maze: the ball's)."""
        state = np.asarray(state, np.float64)
        if self._ball:
            start = self._model.nq - BALL_QPOS
            return state[start : start + 2]
        return state[:2]

    def _capture_goal(self) -> None:
        goal_ob = self._goal_xy.copy() if self._use_oracle_rep else self._loco_observation()
        image = None
        if self._render_goal:  # a pixel observation is that very frame
            image = goal_ob.copy() if self._ob_type == "pixels" and not self._use_oracle_rep else self.render()
        self._goal = {
            keys.STATE: self._state_vector(),
            keys.PROPRIO: self._proprio(),
            "ob": np.array(goal_ob, copy=True),
            "image": image,
        }

    # -- factors --------------------------------------------------------------------------------
    def _apply_factors(self) -> None:
        v = self.variation_space.value
        changed = self._look.apply(
            v["agent"]["color"],
            v["wall"]["color"],
            v["floor"]["color"],
            int(v["floor"]["pixel_encoding"]),
            v["light"]["intensity"],
        )
        if changed:
            self._upload_texture(self._look.floor_texture)

    # -- step -----------------------------------------------------------------------------------
    def step(self, action):
        if not self._reset_done:
            raise ConfigError(f"{type(self).__name__}.step requires reset() first")
        space = self._action_space
        action = np.clip(np.asarray(action, np.float32).reshape(space.shape), space.low, space.high)
        if self._success_timing == "pre":
            success = self._success_now()
        _, _, _, _, loco_info = self._loco.step(action)
        if self._success_timing == "post":
            success = self._success_now()
        if self.maze_type == "teleport":
            self._teleport()
        reward = 1.0 if success else 0.0
        if self._reward_task_id is not None:
            reward -= 1.0
        terminated = bool(success and self._terminate_at_goal)
        return self._observation(), reward, terminated, False, self._info(loco_info, success)

    def _success_now(self) -> bool:
        return bool(np.linalg.norm(self._tracked_xy(self._state_vector()) - self._goal_xy) <= self._goal_tol)

    def _teleport(self) -> None:
        L = self.maze_layout
        xy = self._loco.get_xy()
        for ij in TELEPORT_IN:
            if np.linalg.norm(xy - L.ij_to_xy(ij)) <= TELEPORT_RADIUS * 1.5:
                out = TELEPORT_OUT[int(self.np_random.integers(len(TELEPORT_OUT)))]
                self._loco.set_xy(L.ij_to_xy(out))
                break

    # -- observations and infos -----------------------------------------------------------------
    def _loco_observation(self) -> np.ndarray:
        return self.render() if self._ob_type == "pixels" else np.asarray(self._loco.get_ob(), np.float64)

    def _observation(self) -> np.ndarray:
        return self._loco_observation()

    def _state_vector(self) -> np.ndarray:
        return np.concatenate([self._data.qpos, self._data.qvel]).astype(np.float64)

    def _proprio(self) -> np.ndarray:
        """The agent's state observation (OGBench's locomotion observation; the ball left out)."""
        if self._ball:  # the ant's qpos ++ qvel without the ball's free joint
            return np.concatenate([self._data.qpos[:-BALL_QPOS], self._data.qvel[:-BALL_QVEL]]).astype(np.float64)
        return np.asarray(self._loco.get_ob(), np.float64).copy()

    def _info(self, loco_info: Mapping[str, Any], success: bool) -> dict[str, Any]:
        goal = self._goal
        info = {k: np.array(v, copy=True) for k, v in loco_info.items()}
        info.update(
            {
                "success": 1.0 if success else 0.0,
                "env_name": self.env_name,
                "target": goal["ob"].copy(),
                keys.STATE: self._state_vector(),
                keys.PROPRIO: self._proprio(),
                keys.GOAL_STATE: goal[keys.STATE].copy(),
                keys.GOAL_PROPRIO: goal[keys.PROPRIO].copy(),
            }
        )
        if goal["image"] is not None:
            info[keys.GOAL] = goal["image"].copy()
        return info

    def get_xy(self) -> np.ndarray:
        """The agent's position (OGBench's ``get_xy``)."""
        return self._loco.get_xy()

    @property
    def cur_goal_xy(self) -> np.ndarray:
        """The goal position (OGBench's name)."""
        return self._goal_xy.copy()

    def eval_state(self, goal_state: np.ndarray, cur_state: np.ndarray) -> tuple[bool, float]:
        """``(success, distance)``: the agent (ball maze: the ball) within the goal tolerance of where
        it is in ``goal_state`` (1.0 m for the point, 0.5 m otherwise)."""
        goal = self._check_state("eval_state's goal_state", goal_state)
        cur = self._check_state("eval_state's cur_state", cur_state)
        dist = float(np.linalg.norm(self._tracked_xy(cur) - self._tracked_xy(goal)))
        return dist <= self._goal_tol, dist

    def reset_options_from_dataset(self, start_row, goal_row) -> dict[str, Any]:
        """Start at ``start_row``'s state with ``goal_row``'s as goal; rows recorded by upstream
        (``qpos`` / ``qvel`` columns, no ``state``) work too."""
        return super().reset_options_from_dataset(self._with_state(start_row), self._with_state(goal_row))

    @staticmethod
    def _with_state(row: Mapping[str, Any]) -> Mapping[str, Any]:
        if keys.STATE in row or not all(p in row for p in ("qpos", "qvel")):
            return row
        parts = [np.asarray(row[p], np.float64).reshape(-1) for p in ("qpos", "qvel")]
        return {**row, keys.STATE: np.concatenate(parts)}

    # -- rendering ------------------------------------------------------------------------------
    def set_render_size(self, size: tuple[int, int]) -> None:
        """Draw frames (pixel observations and, from the next reset, goal images) at ``size`` = (H, W)."""
        h, w = check_render_size(type(self).__name__, size)
        if (h, w) != (self._render_height, self._render_width):
            self._render_height, self._render_width = h, w
            self._observation_space = self._make_observation_space()
            self._close_renderer()

    def render(self) -> np.ndarray:
        """The ``(H, W, 3)`` uint8 frame of the current scene (OGBench's top-down view by default)."""
        if self._mjr is None:
            floor = [self._model.geom("floor").id] if self.render_quality != "high" else []
            self._mjr = MjRenderer(
                self._model, self._render_height, self._render_width, self.render_quality, shadowless=floor
            )
        return self._mjr.render(self._data, self._camera)

    def close(self) -> None:
        """Free the GL renderer (the env can be reset and rendered again afterwards)."""
        self._close_renderer()
        loco = getattr(self, "_loco", None)
        if loco is not None:
            loco.close()
        super().close()


class _MazeLook:
    """Writes the visual factors into a compiled maze model (no recompilation).

    Built once per model: it keeps the model's own colours (the factors' defaults), the floor
    checker (two colours, found texel by texel) and the floor material's texture mapping.
    :meth:`apply` returns True when the floor texture changed (a live GL context must receive it).
    """

    def __init__(self, model):
        self.model = model
        self._agent = model.material("self").id
        self._wall = model.material("wall").id
        self._light = model.light("global").id
        self._grid = model.material("grid").id
        self.floor_texture = tex = model.texture("grid").id
        self.agent_color0 = model.mat_rgba[self._agent, :3].astype(np.float64).copy()
        self.wall_color0 = model.mat_rgba[self._wall, :3].astype(np.float64).copy()
        self.intensity0 = float(np.mean(model.light_diffuse[self._light]))
        self._uniform0 = int(model.mat_texuniform[self._grid])
        h, w = int(model.tex_height[tex]), int(model.tex_width[tex])
        channels = int(model.tex_nchannel[tex])
        start = int(model.tex_adr[tex])
        self._tex = model.tex_data[start : start + h * w * channels].reshape(h, w, channels)  # a view
        pristine = self._tex[..., :3].copy()
        # the checker's rgb1 / rgb2 as OGBench's assets give them (every texel is one of the two)
        self.floor_colors0 = np.asarray(FLOOR_COLORS, np.float64)
        self._masks = [np.all(pristine == _texel(c), axis=-1) for c in self.floor_colors0]
        if not (self._masks[0] | self._masks[1]).all():
            raise ConfigError(f"MazeEnv requires OGBench's two-colour floor checker {FLOOR_COLORS}")
        self._encoding = _encoding(h, w)
        self._floor_state: tuple | None = (0, *self.floor_colors0.reshape(-1).tolist())

    def apply(self, agent_color, wall_color, floor_colors, encoding: int, intensity) -> bool:
        m = self.model
        m.mat_rgba[self._agent, :3] = np.asarray(agent_color, np.float64)
        m.mat_rgba[self._wall, :3] = np.asarray(wall_color, np.float64)
        m.light_diffuse[self._light] = float(np.asarray(intensity, np.float64).reshape(-1)[0])
        floor = np.asarray(floor_colors, np.float64)
        state = (int(encoding), *floor.reshape(-1).tolist())
        if state == self._floor_state:
            return False
        if encoding:
            self._tex[..., :3] = self._encoding
            m.mat_texuniform[self._grid] = 0  # the gradient spans the floor once
        else:
            for mask, color in zip(self._masks, floor, strict=True):
                self._tex[mask, :3] = _texel(color)
            m.mat_texuniform[self._grid] = self._uniform0
        self._floor_state = state
        return True


__all__ = ["MAZE_TYPES", "MazeEnv"]

"""``swm/SimpleNavigation-v0``: release 0.0.3's SimpleNavigation, a MiniGrid maze (extra ``minigrid``).

Written from 0.0.3's observed behaviour; the env is a ``minigrid`` ``MiniGridEnv`` (so its
frames, moves and grid objects are MiniGrid's own) whose walls are a random perfect maze.

- **Constructor**: ``SimpleNavigationEnv(size=9, render_mode="rgb_array", **kwargs)``; ``size``
  (odd, >= 5) is the side of the square grid, outer walls included; other keywords go to
  ``MiniGridEnv`` (``tile_size=32``, ``highlight=True``, ``agent_view_size=7``, ``max_steps``
  ...).
- **Maze**: :func:`.maze.maze_walls` (Eller's algorithm, 0.0.3's ``ellers_maze``) with the
  factors ``maze.p_horizontal`` / ``maze.p_vertical``, seeded by the reset seed (a seed drawn
  from the env's generator on an unseeded reset). One path joins any two open cells.
- **Spaces**: observation ``Dict(proprio=MultiDiscrete([n, n, 4], start=[1, 1, 0]),
  state=MultiDiscrete([n, n, 4, n, n], start=[1, 1, 0, 1, 1]))`` with ``n = size - 2``: agent
  x, y, direction (MiniGrid's: 0 right, 1 down, 2 left, 3 up), then goal x, y; int64. Action
  ``Discrete(3)``: 0 turn left, 1 turn right, 2 forward (blocked by walls).
- **Step**: reward ``-d``, ``d`` the Manhattan distance from the agent to the goal square;
  ``terminated`` when ``d == 0``; never truncated (MiniGrid's step limit is ignored, as 0.0.3;
  the swm tools cut episodes at 100 steps, MiniGrid's ``max_steps``).
- **Factors**: ``agent.position`` / ``agent.direction`` (start), ``goal.position`` (the goal
  square), ``goal.agent.direction`` (the agent's direction in the goal state),
  ``maze.p_horizontal`` / ``maze.p_vertical``; all six are drawn on every reset unless
  ``options["variation"]`` names others. Positions are drawn on open cells, the goal apart from
  the start. Defaults: start ``(1, 1)`` facing right, goal ``(size - 4, size - 4)``, p = 0.5.
- **Goal**: ``goal_state = [gx, gy, goal direction, gx, gy]`` (the agent on the goal square),
  ``goal_proprio`` its first three numbers, ``goal`` its frame. ``eval_state(goal_state, state)``
  is ``(d == 0, d)`` with ``d`` the Manhattan distance between ``goal_state[3:5]`` and
  ``state[:2]``.
- **Info**: 0.0.3's ``pos_agent``, ``dir_agent``, ``pos_goal``, ``goal_state``,
  ``goal_proprio``, ``goal``, plus ``maze``: the ``(size, size)`` uint8 layout (1 = wall,
  indexed ``[y, x]``), which the expert reads and dataset resets restore.
- **Reset options**: ``variation`` / ``variation_values``; ``maze`` (a layout as in
  ``info["maze"]``: used instead of drawing one); ``state`` (``[x, y, direction, ...]``: the
  start); ``goal_state`` (``[.., .., direction, gx, gy]``: the goal square and direction).
  :meth:`reset_options_from_dataset` starts at a row's state in its maze with the goal square
  where the agent stands in the goal row.
- **Rendering**: MiniGrid's full-grid frame (the agent's field of view highlighted), ``size *
  tile_size`` pixels a side (288 x 288 by default); after ``set_render_size((H, W))`` it is drawn
  with tiles just large enough and resized to ``(H, W)`` (OpenCV, area filter).

Deliberate differences from 0.0.3: resets are reproducible (0.0.3 drew the maze with the
previous episode's ``maze.p_*`` values before resampling them, so the same seed gave different
mazes; here the episode's own values are used, so a fresh env's first ``reset(seed=s)`` with
the default p = 0.5 has 0.0.3's maze); ``options["variation"]`` with only some factors works
(0.0.3 failed its own check); ``render_mode`` is ``"rgb_array"`` or None (no ``"human"``
window); typed errors instead of asserts; the ``maze`` info and option; the expert follows the
maze's shortest path recomputed each step (0.0.3: the same path, planned once).
"""

from __future__ import annotations

import math
import os
from collections.abc import Mapping
from typing import Any

import gymnasium as gym
import numpy as np

from ... import keys, spaces
from ..._optional import require
from ...errors import ConfigError, SpaceError, did_you_mean, unknown_name
from ..base import check_render_size, check_variation_option, flatten_values
from .maze import ellers_maze, maze_walls

__all__ = ["DEFAULT_VARIATIONS", "MAZE", "SimpleNavigationEnv", "ellers_maze"]

os.environ.setdefault("PYGAME_HIDE_SUPPORT_PROMPT", "1")  # minigrid imports pygame at import time
_WHY = "swm/SimpleNavigation-v0"
MiniGridEnv = require("minigrid.minigrid_env", extra="minigrid", purpose=_WHY).MiniGridEnv
Grid = require("minigrid.core.grid", extra="minigrid", purpose=_WHY).Grid
MissionSpace = require("minigrid.core.mission", extra="minigrid", purpose=_WHY).MissionSpace
_objects = require("minigrid.core.world_object", extra="minigrid", purpose=_WHY)

DEFAULT_VARIATIONS = (
    "agent.position",
    "agent.direction",
    "goal.position",
    "goal.agent.direction",
    "maze.p_horizontal",
    "maze.p_vertical",
)
MAZE = "maze"  # info key and reset option: the (size, size) layout, 1 = wall
MISSION = "go to the goal square"
N_ACTIONS = 3  # MiniGrid's left, right, forward
MINIGRID_KWARGS = (
    "max_steps",
    "see_through_walls",
    "agent_view_size",
    "screen_size",
    "highlight",
    "tile_size",
    "agent_pov",
)


def _mission() -> str:
    return MISSION


class SimpleNavigationEnv(MiniGridEnv):
    """Release 0.0.3's maze navigation on MiniGrid (see the module docstring)."""

    metadata = {"render_modes": ["rgb_array"], "render_fps": 10}

    def __init__(self, size: int = 9, render_mode: str | None = "rgb_array", *args: Any, **kwargs: Any):
        owner = type(self).__name__
        if args:
            raise ConfigError(f"{owner} takes size and render_mode positionally, the rest by keyword; got {args!r}")
        if isinstance(size, bool) or not isinstance(size, (int, np.integer)) or size < 5 or size % 2 == 0:
            raise ConfigError(f"{owner} requires size to be an odd int >= 5 (walls included), got {size!r}")
        if render_mode not in (None, "rgb_array"):
            raise ConfigError(f"{owner} requires render_mode 'rgb_array' or None, got {render_mode!r}")
        for key in kwargs:
            if key not in MINIGRID_KWARGS:
                raise ConfigError(
                    f"{owner} requires keyword arguments among {list(MINIGRID_KWARGS)}, got {key!r}."
                    f"{did_you_mean(str(key), MINIGRID_KWARGS)}"
                )
        super().__init__(
            mission_space=MissionSpace(mission_func=_mission), grid_size=int(size), render_mode=render_mode, **kwargs
        )
        n = int(size) - 2
        self.observation_space = gym.spaces.Dict(
            {
                keys.PROPRIO: gym.spaces.MultiDiscrete([n, n, 4], start=[1, 1, 0]),
                keys.STATE: gym.spaces.MultiDiscrete([n, n, 4, n, n], start=[1, 1, 0, 1, 1]),
            }
        )
        self.action_space = gym.spaces.Discrete(N_ACTIONS)
        self.render_size: tuple[int, int] | None = None  # None: MiniGrid's size * tile_size
        self._maze_seed = 0
        self._maze_given: np.ndarray | None = None
        self._walls_key: tuple | None = None
        self._walls = np.zeros((self.height, self.width), bool)
        self._episode_walls = self._walls
        self._goal_state = np.zeros(5, np.int64)
        self._goal_img: np.ndarray | None = None
        self.variation_space = self._make_variation_space(n)

    def _make_variation_space(self, n: int) -> spaces.Dict:
        def cell(init, constrain_fn) -> spaces.MultiDiscrete:
            return spaces.MultiDiscrete(nvec=[n, n], start=[1, 1], init_value=init, constrain_fn=constrain_fn)

        def direction() -> spaces.Discrete:
            return spaces.Discrete(n=4, start=0, init_value=0)

        def probability() -> spaces.Box:
            return spaces.Box(0.0, 1.0, shape=(1,), dtype=np.float32, init_value=np.array([0.5], np.float32))

        return spaces.Dict(
            {
                "agent": spaces.Dict({"position": cell([1, 1], self._open), "direction": direction()}),
                "goal": spaces.Dict(
                    {
                        "position": cell([n - 2, n - 2], self._open_and_not_start),
                        "agent": spaces.Dict({"direction": direction()}),
                    }
                ),
                "maze": spaces.Dict({"p_horizontal": probability(), "p_vertical": probability()}),
            },
            sampling_order=["maze", "agent", "goal"],
        )

    # -- maze -------------------------------------------------------------------------------------
    def _layout(self) -> np.ndarray:
        """The walls of the current factors: the given maze, else the maze of (seed, p_horizontal, p_vertical)."""
        if self._maze_given is not None:
            return self._maze_given
        m = self.variation_space["maze"]
        p = tuple(
            float(np.clip(np.asarray(m[k].value).reshape(-1)[0], 0.0, 1.0)) for k in ("p_horizontal", "p_vertical")
        )
        key = (self._maze_seed, *p)
        if key != self._walls_key:
            self._walls, self._walls_key = maze_walls(self.width, self.height, *key), key
        return self._walls

    def _open(self, pos) -> bool:
        x, y = int(pos[0]), int(pos[1])
        return 0 <= x < self.width and 0 <= y < self.height and not self._layout()[y, x]

    def _open_and_not_start(self, pos) -> bool:
        start = np.asarray(self.variation_space["agent"]["position"].value).reshape(-1)
        return self._open(pos) and (int(pos[0]), int(pos[1])) != (int(start[0]), int(start[1]))

    def _gen_grid(self, width: int, height: int) -> None:
        """MiniGrid's hook: walls of the episode's maze, the goal square, the agent (set by :meth:`reset`)."""
        self.grid = Grid(width, height)
        for y, x in zip(*np.nonzero(self._episode_walls), strict=True):
            self.grid.set(int(x), int(y), _objects.Wall())
        gx, gy = (int(v) for v in self._goal_state[3:5])
        self.put_obj(_objects.Goal(), gx, gy)
        self.goal_pos = (gx, gy)
        self.mission = MISSION

    # -- gym API ----------------------------------------------------------------------------------
    def reset(self, *, seed: int | None = None, options: Mapping[str, Any] | None = None):
        gym.Env.reset(self, seed=seed)  # not MiniGrid's reset: the maze needs the factors first
        options = self._check_options(options)
        self._maze_seed = int(seed) if seed is not None else int(self.np_random.integers(0, 2**31 - 1))
        self._maze_given = options.get(MAZE)
        vseed = int(self.np_random.integers(0, 2**31 - 1))
        spaces.reset_variation_space(self.variation_space, vseed, options, DEFAULT_VARIATIONS)
        self._episode_walls = self._layout().copy()
        v = self.variation_space
        goal = [*np.asarray(v["goal"]["position"].value).tolist(), int(v["goal"]["agent"]["direction"].value)]
        if options.get(keys.GOAL_STATE) is not None:
            gs = options[keys.GOAL_STATE]
            goal = [int(gs[3]), int(gs[4]), int(gs[2])]
        start = [*np.asarray(v["agent"]["position"].value).tolist(), int(v["agent"]["direction"].value)]
        if options.get(keys.STATE) is not None:
            start = [int(s) for s in options[keys.STATE][:3]]
        for what, (x, y, _) in ((keys.GOAL_STATE, goal), (keys.STATE, start)):
            if not self._open((x, y)):
                raise ConfigError(f"{type(self).__name__} requires the {what} cell ({x}, {y}) to be open in the maze")
        gx, gy, gdir = goal
        self._goal_state = np.array([gx, gy, gdir, gx, gy], np.int64)
        self._gen_grid(self.width, self.height)
        self.agent_pos, self.agent_dir = (int(start[0]), int(start[1])), int(start[2])
        self.carrying, self.step_count = None, 0
        self._goal_img = None
        return self._obs(), self._info()

    def step(self, action):
        a = self._check_action(action)
        super().step(a)  # MiniGrid's move; its reward, termination and step limit are not used (as 0.0.3)
        state = self._state()
        success, distance = self.eval_state(self._goal_state, state)
        return self._obs(state), -distance, success, False, self._info()

    def render(self) -> np.ndarray:
        """The full-grid frame (``render_size`` when set, else ``size * tile_size`` a side)."""
        if self.render_size is None:
            return self.get_frame(self.highlight, self.tile_size, self.agent_pov)
        h, w = self.render_size
        cells = (self.agent_view_size,) * 2 if self.agent_pov else (self.height, self.width)
        tile = max(1, math.ceil(max(h / cells[0], w / cells[1])))
        frame = self.get_frame(self.highlight, tile, self.agent_pov)
        if frame.shape[:2] != (h, w):
            import cv2

            frame = cv2.resize(frame, (w, h), interpolation=cv2.INTER_AREA)
        return frame

    def set_render_size(self, size: tuple[int, int]) -> None:
        """Draw frames and the goal image at ``size`` = (H, W)."""
        size = check_render_size(type(self).__name__, size)
        if size != self.render_size:
            self.render_size, self._goal_img = size, None

    # -- goals ------------------------------------------------------------------------------------
    def eval_state(self, goal_state: np.ndarray, cur_state: np.ndarray) -> tuple[bool, float]:
        """``(d == 0, d)``: ``d`` the Manhattan distance from ``cur_state[:2]`` to ``goal_state[3:5]``."""
        g = np.asarray(goal_state, np.float64).reshape(-1)
        c = np.asarray(cur_state, np.float64).reshape(-1)
        if g.shape[0] < 5 or c.shape[0] < 2:
            raise ConfigError(
                f"{type(self).__name__}.eval_state requires a goal state of 5 numbers and a state of at least 2, "
                f"got {np.shape(goal_state)} and {np.shape(cur_state)}"
            )
        distance = float(np.abs(g[3:5] - c[:2]).sum())
        return distance == 0.0, distance

    def reset_options_from_dataset(
        self, start_row: Mapping[str, np.ndarray], goal_row: Mapping[str, np.ndarray]
    ) -> dict[str, Any]:
        """Start at ``start_row``'s state in its maze; the goal square is where the agent stands in ``goal_row``."""
        for row, what in ((start_row, "start"), (goal_row, "goal")):
            if keys.STATE not in row:
                raise ConfigError(
                    f"{type(self).__name__} requires a {keys.STATE!r} column in the {what} row, got {sorted(row)}"
                )
        if MAZE not in start_row:
            raise ConfigError(
                f"{type(self).__name__} requires a {MAZE!r} column (the maze layout) to start from a dataset row, "
                f"got {sorted(start_row)}"
            )
        g = np.asarray(goal_row[keys.STATE]).reshape(-1)
        options: dict[str, Any] = {
            keys.STATE: np.asarray(start_row[keys.STATE]).reshape(-1).copy(),
            keys.GOAL_STATE: np.array([g[0], g[1], g[2], g[0], g[1]], np.int64),
            MAZE: np.asarray(start_row[MAZE]).copy(),
        }
        prefix = keys.VARIATION + "."
        values = {k[len(prefix) :]: np.asarray(v) for k, v in start_row.items() if k.startswith(prefix)}
        if values:
            options[keys.VARIATION_VALUES] = values
        return options

    # -- internals --------------------------------------------------------------------------------
    def _check_options(self, options: Any) -> dict[str, Any]:
        owner = type(self).__name__
        if options is None:
            return {}
        if not isinstance(options, Mapping):
            raise ConfigError(f"{owner}.reset requires options as a dict, got {options!r}")
        out = dict(options)
        names = self.variation_space.names()
        check_variation_option(out, names)
        values = out.get(keys.VARIATION_VALUES)
        if values is not None and not isinstance(values, Mapping):
            raise ConfigError(f"{owner}.reset requires options[{keys.VARIATION_VALUES!r}] as a dict, got {values!r}")
        for name in flatten_values(values or {}):
            if name not in names:
                raise unknown_name("variation factor", name, names)
        if out.get(MAZE) is not None:
            out[MAZE] = self._check_maze(out[MAZE])
        for key, size in ((keys.STATE, 3), (keys.GOAL_STATE, 5)):
            if out.get(key) is None:
                continue
            arr = np.asarray(out[key], np.float64).reshape(-1)
            if arr.shape[0] < size or not np.all(np.isfinite(arr)) or not np.all(arr == np.round(arr)):
                raise ConfigError(
                    f"{owner} requires reset option {key!r} of at least {size} integers "
                    f"([x, y, direction{', goal x, goal y' if size == 5 else ''}]), got {out[key]!r}"
                )
            if not 0 <= arr[2] < 4:
                raise ConfigError(f"{owner} requires the direction in reset option {key!r} in 0..3, got {arr[2]:g}")
            out[key] = arr.astype(np.int64)
        return out

    def _check_maze(self, maze: Any) -> np.ndarray:
        arr = np.asarray(maze)
        shape = (self.height, self.width)
        if arr.shape != shape or not np.isin(arr, (0, 1)).all():
            raise ConfigError(
                f"{type(self).__name__} requires reset option {MAZE!r} as a {shape} array of 0 / 1 (1 = wall), "
                f"got shape {arr.shape}"
            )
        walls = arr.astype(bool)
        if not (walls[0].all() and walls[-1].all() and walls[:, 0].all() and walls[:, -1].all()):
            raise ConfigError(
                f"{type(self).__name__} requires reset option {MAZE!r} to have walls all around its border"
            )
        return walls

    def _check_action(self, action: Any) -> int:
        arr = np.asarray(action)
        if arr.size == 1 and arr.dtype.kind in "iuf":
            value = float(arr.reshape(-1)[0])
            if value.is_integer() and 0 <= value < N_ACTIONS:
                return int(value)
        raise SpaceError(
            f"{type(self).__name__}.step requires an action in 0..{N_ACTIONS - 1} "
            f"(0 turn left, 1 turn right, 2 forward), got {action!r}"
        )

    def _state(self) -> np.ndarray:
        x, y = (int(v) for v in self.agent_pos)
        gx, gy = (int(v) for v in self.goal_pos)
        return np.array([x, y, int(self.agent_dir), gx, gy], np.int64)

    def _obs(self, state: np.ndarray | None = None) -> dict[str, np.ndarray]:
        state = self._state() if state is None else state
        return {keys.PROPRIO: state[:3].copy(), keys.STATE: state}

    def _goal_image(self) -> np.ndarray:
        if self._goal_img is None:
            saved = self.agent_pos, self.agent_dir
            self.agent_pos = (int(self._goal_state[3]), int(self._goal_state[4]))
            self.agent_dir = int(self._goal_state[2])
            try:
                self._goal_img = self.render()
            finally:
                self.agent_pos, self.agent_dir = saved
        return self._goal_img

    def _info(self) -> dict[str, Any]:
        return {
            "pos_agent": np.array(self.agent_pos, np.int64),
            "dir_agent": np.array(self.agent_dir, np.int64),
            "pos_goal": np.array(self.goal_pos, np.int64),
            keys.GOAL_STATE: self._goal_state.copy(),
            keys.GOAL_PROPRIO: self._goal_state[:3].copy(),
            keys.GOAL: self._goal_image().copy(),
            MAZE: self._episode_walls.astype(np.uint8),
        }

"""Scripted expert of ``swm/OGBMaze-v0`` for the point agent: BFS over the maze cells, then a
P-controller along them.

Per env and step: the agent's cell and the goal's cell (from ``infos["state"]`` /
``infos["goal_state"]``, x and y first), a shortest path of free cells between them
(:meth:`.maze_layout.MazeLayout.path`, recomputed every step, so a push or a teleport only
changes the plan), then the waypoint: the farthest of the next :data:`LOOKAHEAD` cell centres (the
goal itself in its own cell) that the point reaches in a straight line clear of the walls grown by
its radius. The action moves straight at it: ``(waypoint - xy) / 0.2`` (the point moves by
``0.2 * action``), scaled down so that no component leaves [-1, 1]. In the teleport maze the
inbound pads are avoided whenever a path goes around them.

The maze comes from the env the policy is attached to (``World.set_policy``: each env's
``maze_layout``), else from ``maze_type`` / ``maze_unit`` (default: the id's registered ones).
The ant and the humanoid need a learned low-level controller (OGBench collects their data with a
pretrained walking policy, which is not distributed): this expert refuses them.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ... import keys
from ...errors import ConfigError
from ...policy import ExpertPolicy
from ..planar import grow_boxes, segment_clear
from .maze_layout import MAZE_TYPES, TELEPORT_IN, TELEPORT_RADIUS, MazeLayout, check_maze_type

POINT_STEP = 0.2  # the point moves by POINT_STEP * action per step
POINT_RADIUS = 0.7  # the point's sphere
CLEARANCE = 0.3  # kept between the sphere and a wall on straight-line shortcuts
LOOKAHEAD = 3
POINT_STATE_DIM = 4  # qpos (x, y) ++ qvel


class OGBMazeExpert(ExpertPolicy):
    """Batched point-maze expert (module docstring): ``get_action(infos) -> (B, 2)`` float32."""

    def __init__(
        self,
        env_id: str = "swm/OGBMaze-v0",
        maze_type: str | None = None,
        maze_unit: float | None = None,
        noise: float = 0.0,
        seed: int | None = None,
        **kwargs: Any,
    ):
        if not np.isfinite(noise) or noise < 0:
            raise ConfigError(f"OGBMazeExpert requires noise >= 0, got {noise!r}")
        registered = _registered_kwargs(env_id)
        maze_type = maze_type if maze_type is not None else registered.get("maze_type", "large")
        maze_unit = maze_unit if maze_unit is not None else registered.get("maze_unit", 4.0)
        check_maze_type("OGBMazeExpert", maze_type, MAZE_TYPES)
        if isinstance(maze_unit, bool) or not isinstance(maze_unit, (int, float)) or not maze_unit > 0:
            raise ConfigError(f"OGBMazeExpert requires maze_unit > 0, got {maze_unit!r}")
        super().__init__(env_id=env_id, noise=float(noise), seed=seed, **kwargs)
        self.rng = np.random.default_rng(seed)
        self.default_layout = MazeLayout(maze_type, float(maze_unit))
        self._layouts: list[MazeLayout] | None = None
        self._obstacles: dict[MazeLayout, np.ndarray] = {}

    def set_env(self, env: Any) -> None:
        super().set_env(env)
        self._layouts = None

    def get_action(self, infos: dict[str, Any], **kwargs: Any) -> np.ndarray:
        """``infos``: the World's batched infos, entries ``(B, T, ...)``; returns ``(B, 2)`` float32."""
        state = np.asarray(infos[keys.STATE], np.float64)[:, -1]
        goal = np.asarray(infos[keys.GOAL_STATE], np.float64)[:, -1]
        if state.shape[-1] != POINT_STATE_DIM:
            raise ConfigError(
                f"OGBMazeExpert drives the point agent only (a state of {POINT_STATE_DIM} numbers), got states of "
                f"{state.shape[-1]}: the ant and the humanoid need OGBench's pretrained walking policy, not included"
            )
        layouts = self._env_layouts(len(state))
        out = np.zeros((len(state), 2), np.float64)
        for b, (s, g) in enumerate(zip(state, goal, strict=True)):
            target = self._waypoint(layouts[b], s[:2], g[:2])
            a = (target - s[:2]) / POINT_STEP
            out[b] = a / max(1.0, float(np.abs(a).max()))
        if self.noise:
            out = np.clip(out + self.noise * self.rng.standard_normal(out.shape), -1.0, 1.0)
        return out.astype(np.float32)

    def _env_layouts(self, n: int) -> list[MazeLayout]:
        """Each env's maze (read once from the attached env), else the default one."""
        if self._layouts is None or len(self._layouts) != n:
            found = _layouts_of(self.env)
            self._layouts = found if found is not None and len(found) == n else [self.default_layout] * n
        return self._layouts

    def _waypoint(self, layout: MazeLayout, pos: np.ndarray, goal: np.ndarray) -> np.ndarray:
        avoid = TELEPORT_IN if layout.maze_type == "teleport" else ()
        cells = layout.path(layout.nearest_free(pos), layout.nearest_free(goal), avoid)
        if len(cells) <= 1:
            return goal
        points = [layout.ij_to_xy(c) for c in cells[1 : 1 + LOOKAHEAD]]
        if len(cells) <= 1 + LOOKAHEAD:
            points[-1] = goal
        obstacles = self._obstacles_of(layout)
        for point in reversed(points[1:]):
            if segment_clear(pos, point, obstacles):
                return point
        return points[0]

    def _obstacles_of(self, layout: MazeLayout) -> np.ndarray:
        if layout not in self._obstacles:
            boxes = grow_boxes(layout.wall_boxes(), POINT_RADIUS + CLEARANCE)
            if layout.maze_type == "teleport":  # the pads trigger within 1.5 radii of their centre
                half = 1.5 * TELEPORT_RADIUS + CLEARANCE
                pads = [(*(layout.ij_to_xy(c) - half), *(layout.ij_to_xy(c) + half)) for c in TELEPORT_IN]
                boxes = np.concatenate([boxes, np.asarray(pads, np.float64)])
            self._obstacles[layout] = boxes
        return self._obstacles[layout]


def _registered_kwargs(env_id: str) -> dict[str, Any]:
    import gymnasium as gym

    try:
        return dict(gym.spec(env_id).kwargs)
    except Exception:  # an id registered elsewhere, or none: the defaults
        return {}


def _layouts_of(env: Any) -> list[MazeLayout] | None:
    """``maze_layout`` of every env behind ``env`` (a World's batched env, or one gym env)."""
    if env is None:
        return None
    get_attr = getattr(env, "get_attr", None)
    try:
        if callable(get_attr):
            found = list(get_attr("maze_layout"))
        else:
            found = [getattr(env, "unwrapped", env).maze_layout]
    except Exception:  # not a maze env (or no such attribute): the default layout
        return None
    return found if all(isinstance(x, MazeLayout) for x in found) else None

"""``swm/SimplePointMaze-v1``: a point mass with friction driven through a grid maze to a goal.

World: a 7 x 7 grid of unit cells (x right, y down; cell ``(i, j)`` is row ``i``, column
``j`` and spans ``[j, j + 1] x [i, i + 1]``) taken from :data:`LAYOUTS` by the factor
``maze.layout`` (default 0); ``#`` cells are walls, the outer ring is always wall.

- Agent: a disk of radius ``agent.radius`` (cells). Action ``a`` in ``[-1, 1]^2`` is a force:
  ``v <- (1 - friction) v + ACCEL a``, then ``|v|`` is capped at ``max_speed``, then the
  position moves by ``v``, swept against the walls (exact, no tunnelling, see
  :mod:`stable_worldmodel.envs.planar`); a wall stops the velocity component normal to it.
- ``proprio`` = (x, y, vx, vy); ``state`` (5,) float32 = (x, y, vx, vy, layout index), so
  the expert (and any planner) knows the maze from the state alone. ``goal_state`` =
  (goal x, goal y, 0, 0, layout index); ``goal_proprio`` its first four entries.
- Success (``terminated``) when the agent centre is within :data:`SUCCESS_DISTANCE` (0.5
  cell, the maze2d convention) of the goal; reward = -distance.
- Per-seed factors: ``agent.position`` and ``goal.position`` are drawn from the reset seed
  on every reset: two distinct free cells at least :data:`MIN_PATH_CELLS` apart along the
  maze (when the maze allows), jittered by up to 0.2 around the cell centres. Setting them
  through ``"variation_values"`` (or ``"state"`` / ``"goal_state"``) overrides the draw; a
  position in a wall is moved to the nearest free cell. Every other factor keeps its default
  unless named in ``"variation"`` or ``"variation_values"``. A ``"state"`` also restores the
  layout index it carries.
- Drawn directly at ``render_size`` (default 224x224) with anti-aliasing; the maze layer and
  the goal image are drawn once per reset.
"""

from __future__ import annotations

import gymnasium as gym
import numpy as np

from ... import keys, spaces
from .. import utils as draw
from ..planar import grow_boxes, push_out, sweep
from ..point_env import PointEnv
from .layout import LAYOUTS, Maze

ACCEL = 0.1
SUCCESS_DISTANCE = 0.5
MIN_PATH_CELLS = 3
JITTER = 0.2
RADIUS_RANGE = (0.15, 0.3)
STATE_DIM = 5


def _rgb(r: int, g: int, b: int):
    return spaces.RGBBox(init_value=np.array([r, g, b], np.uint8))


def _scalar(low: float, high: float, init: float):
    return spaces.Box(low, high, shape=(), dtype=np.float32, init_value=np.float32(init))


def _point(init: tuple[float, float], size: float):
    return spaces.Box(0.0, size, shape=(2,), dtype=np.float32, init_value=np.array(init, np.float32))


def make_variation_space() -> spaces.Dict:
    """The 11 factors of variation of SimplePointMaze, with their defaults."""
    size = float(LAYOUTS[0].size)
    return spaces.Dict(
        {
            "maze": spaces.Dict({"layout": spaces.Discrete(len(LAYOUTS), init_value=0)}),
            "wall": spaces.Dict({"color": _rgb(60, 60, 90)}),
            "floor": spaces.Dict({"color": _rgb(235, 230, 215)}),
            "agent": spaces.Dict(
                {
                    "color": _rgb(220, 40, 40),
                    "radius": _scalar(*RADIUS_RANGE, 0.2),
                    "position": _point((1.5, 1.5), size),
                }
            ),
            "goal": spaces.Dict(
                {"color": _rgb(40, 170, 60), "radius": _scalar(0.15, 0.4, 0.25), "position": _point((5.5, 5.5), size)}
            ),
            "dynamics": spaces.Dict({"friction": _scalar(0.05, 0.5, 0.2), "max_speed": _scalar(0.15, 0.35, 0.25)}),
        },
        sampling_order=["maze", "wall", "floor", "agent", "goal", "dynamics"],
    )


class SimplePointMazeEnv(PointEnv):
    """A point mass in a grid maze (see the module docstring)."""

    success_distance = SUCCESS_DISTANCE
    proprio_dim = 4

    def __init__(self, render_mode: str | None = "rgb_array", render_size: tuple[int, int] = (224, 224)):
        super().__init__(render_mode, render_size)
        self._maze: Maze = LAYOUTS[0]
        self.world_size = float(self._maze.size)
        size, last = self.world_size, len(LAYOUTS) - 1
        low = np.array([0.0, 0.0, -1.0, -1.0, 0.0], np.float32)
        high = np.array([size, size, 1.0, 1.0, last], np.float32)
        self.observation_space = gym.spaces.Dict(
            {
                keys.PROPRIO: gym.spaces.Box(low[:4], high[:4], (4,), np.float32),
                keys.STATE: gym.spaces.Box(low, high, (STATE_DIM,), np.float32),
            }
        )
        self.action_space = gym.spaces.Box(-1.0, 1.0, (2,), np.float32)
        self.variation_space = make_variation_space()
        self._pos = self._goal = self._maze.centre((1, 1))
        self._vel = np.zeros(2)
        self._boxes = np.zeros((0, 4))

    def step(self, action):
        action = np.clip(np.asarray(action, np.float64).reshape(2), -1.0, 1.0)
        dyn = self.variation_space["dynamics"]
        vel = (1.0 - float(dyn["friction"].value)) * self._vel + ACCEL * action
        speed, cap = float(np.linalg.norm(vel)), float(dyn["max_speed"].value)
        if speed > cap:
            vel *= cap / speed
        self._pos, blocked = sweep(self._pos, vel, self._boxes, self._lo, self._hi)
        vel[blocked] = 0.0
        self._vel = vel
        return self._transition()

    # -- hooks -----------------------------------------------------------------------------
    def _setup(self, state: np.ndarray | None) -> None:
        """The maze of the ``maze.layout`` factor (or of ``state[4]``), its grown walls, the velocity."""
        self._vel = np.zeros(2)
        if state is not None and len(state) >= 4:
            self._vel = np.clip(state[2:4], -1.0, 1.0)
        if state is not None and len(state) >= STATE_DIM:
            self.variation_space.set_value({"maze.layout": int(round(state[4]))})
        self._maze = LAYOUTS[int(self.variation_space["maze"]["layout"].value)]
        radius = float(self.variation_space["agent"]["radius"].value)
        self._boxes = grow_boxes(self._maze.wall_boxes, radius)
        self._lo, self._hi = np.full(2, radius), np.full(2, self._maze.size - radius)

    def _draw_positions(self) -> tuple[np.ndarray, np.ndarray]:
        free = self._maze.free_cells
        start = int(self.np_random.integers(len(free)))
        dist = self._maze.distances[start]
        far = np.flatnonzero(dist >= min(MIN_PATH_CELLS, dist.max()))
        goal = int(far[self.np_random.integers(len(far))])
        jitter = self.np_random.uniform(-JITTER, JITTER, (2, 2))
        return self._maze.centre(free[start]) + jitter[0], self._maze.centre(free[goal]) + jitter[1]

    def _legal(self, pos: np.ndarray) -> np.ndarray:
        """``pos`` moved out of the walls (to the nearest free cell centre when it is inside one)."""
        pos = np.asarray(pos, np.float64)
        if self._maze.is_wall(pos):
            centres = np.array([self._maze.centre(c) for c in self._maze.free_cells])
            pos = centres[np.argmin(np.linalg.norm(centres - pos, axis=1))]
        return push_out(pos, self._boxes, self._lo, self._hi)

    def _state(self, goal: bool = False) -> np.ndarray:
        layout = float(self.variation_space["maze"]["layout"].value)
        pos, vel = (self._goal, np.zeros(2)) if goal else (self._pos, self._vel)
        return np.concatenate([pos, vel, [layout]]).astype(np.float32)

    def _draw_static(self) -> np.ndarray:
        v = self.variation_space.value
        img = draw.new_canvas(self.render_size, v["floor"]["color"])
        for x0, y0, x1, y1 in self._maze.wall_boxes:
            px = draw.world_to_pixels(np.array([[x0, y0], [x1, y1]]), self.world_size, self.render_size)
            draw.fill_rect(img, *px[0], *px[1], v["wall"]["color"])
        return img

"""``swm/TwoRoom-v2``: point navigation between two rooms joined by door(s) (the "Wall" task of DINO-WM and PLDM).

World (units, y down as in images): a ``64 x 64`` square framed by a border of thickness 2,
split by a vertical wall (centre ``wall.position``, thickness ``wall.thickness``) with
``door.number`` openings of height ``door.size`` centred at ``door.position[:number]``.

- Agent: a disk of radius ``agent.radius``. Action ``a`` in ``[-1, 1]^2`` moves it by
  ``agent.speed * a``; the move is swept against the border and the wall (see
  :mod:`stable_worldmodel.envs.planar`): it stops at the wall and slides along it, and goes
  through only where a door gap is at least the agent's diameter wide.
- ``proprio`` = agent (x, y); ``state`` (10,) float32 = agent (x, y), wall x, wall half
  thickness, then (centre y, half height) of up to 3 doors, ``(0, 0)`` for absent doors.
  ``goal_state`` is the same vector with the goal position; ``goal_proprio`` its first two.
- Success (``terminated``) when the agent centre is within :data:`SUCCESS_DISTANCE` (4 units,
  1/16 of the arena) of the goal; reward = -distance.
- Per-seed factors: ``agent.position`` and ``goal.position`` are drawn from the reset seed on
  every reset, the start in a random room and the goal in the other one (uniform over each
  room's reachable area). Setting them through ``"variation_values"`` (or the ``"state"`` /
  ``"goal_state"`` options) overrides the draw; positions inside the wall are pushed out.
  Every other factor keeps its default unless named in ``"variation"`` or
  ``"variation_values"``.
- Restoring a ``"state"`` also restores the geometry it encodes (wall and door factors).
- The goal disk is not drawn in the frames unless ``render_target=True`` (upstream's default
  and DINO-WM's: the goal is given only as the goal image, the agent drawn at the goal), so
  frames show the agent, the walls and the doors only.
- Drawn directly at ``render_size`` (default 224x224) with anti-aliasing; the static layer
  (background, border, wall, doors) and the goal image are drawn once per reset.
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np

from ... import keys, spaces
from .. import utils as draw
from ..planar import grow_boxes, push_out, sweep
from ..point_env import PointEnv

SIZE = 64.0
BORDER = 2.0
MAX_DOORS = 3
SUCCESS_DISTANCE = 4.0
RADIUS_RANGE = (1.5, 3.0)
SPEED_RANGE = (1.5, 3.0)
DOOR_SIZE_RANGE = (10.0, 20.0)
STATE_DIM = 4 + 2 * MAX_DOORS


def _rgb(r: int, g: int, b: int):
    return spaces.RGBBox(init_value=np.array([r, g, b], np.uint8))


def _scalar(low: float, high: float, init: float):
    return spaces.Box(low, high, shape=(), dtype=np.float32, init_value=np.float32(init))


def _point(init: tuple[float, float]):
    return spaces.Box(0.0, SIZE, shape=(2,), dtype=np.float32, init_value=np.array(init, np.float32))


def make_variation_space() -> spaces.Dict:
    """The 16 factors of variation of TwoRoom, with their defaults."""
    door_lo = BORDER + DOOR_SIZE_RANGE[1] / 2
    return spaces.Dict(
        {
            "agent": spaces.Dict(
                {
                    "color": _rgb(220, 40, 40),
                    "radius": _scalar(*RADIUS_RANGE, 2.0),
                    "position": _point((16.0, 32.0)),
                    "speed": _scalar(*SPEED_RANGE, 2.0),
                }
            ),
            "goal": spaces.Dict(
                {"color": _rgb(40, 170, 60), "radius": _scalar(2.0, 4.0, 3.0), "position": _point((48.0, 32.0))}
            ),
            "wall": spaces.Dict(
                {"color": _rgb(90, 90, 90), "position": _scalar(26.0, 38.0, 32.0), "thickness": _scalar(2.0, 6.0, 4.0)}
            ),
            "border": spaces.Dict({"color": _rgb(40, 40, 40)}),
            "door": spaces.Dict(
                {
                    "number": spaces.Discrete(MAX_DOORS, start=1, init_value=1),
                    "size": _scalar(*DOOR_SIZE_RANGE, 12.0),
                    "position": spaces.Box(
                        door_lo,
                        SIZE - door_lo,
                        shape=(MAX_DOORS,),
                        dtype=np.float32,
                        init_value=np.array([32.0, 16.0, 48.0], np.float32),
                    ),
                    "color": _rgb(190, 210, 240),
                }
            ),
            "background": spaces.Dict({"color": _rgb(240, 240, 240)}),
        }
    )


class TwoRoomEnv(PointEnv):
    """Two rooms, one wall, door(s) (see the module docstring)."""

    success_distance = SUCCESS_DISTANCE
    proprio_dim = 2

    def __init__(
        self,
        render_mode: str | None = "rgb_array",
        render_size: tuple[int, int] = (224, 224),
        render_target: bool = False,
    ):
        super().__init__(render_mode, render_size, render_target)
        self.world_size = SIZE
        self.observation_space = gym.spaces.Dict(
            {
                keys.PROPRIO: gym.spaces.Box(0.0, SIZE, (2,), np.float32),
                keys.STATE: gym.spaces.Box(0.0, SIZE, (STATE_DIM,), np.float32),
            }
        )
        self.action_space = gym.spaces.Box(-1.0, 1.0, (2,), np.float32)
        self.variation_space = make_variation_space()
        self._pos = self._goal = np.full(2, SIZE / 2)
        self._layout = np.zeros(STATE_DIM - 2)
        self._boxes = np.zeros((0, 4))

    def step(self, action):
        action = np.clip(np.asarray(action, np.float64).reshape(2), -1.0, 1.0)
        delta = float(self._factor("agent", "speed")) * action
        self._pos, _ = sweep(self._pos, delta, self._boxes, self._lo, self._hi)
        return self._transition()

    # -- geometry ------------------------------------------------------------------------
    def _factor(self, group: str, name: str) -> np.ndarray:
        return np.asarray(self.variation_space[group][name].value, np.float64)

    def _door_intervals(self) -> list[tuple[float, float]]:
        n = int(self.variation_space["door"]["number"].value)
        half = float(self._factor("door", "size")) / 2
        return [(float(c) - half, float(c) + half) for c in self._factor("door", "position")[:n]]

    def _setup(self, state: np.ndarray | None) -> None:
        """Free area, wall pieces (between door gaps) as grown boxes, and the layout part of the state."""
        if state is not None and len(state) >= STATE_DIM:
            self._set_layout_factors(state)
        r = float(self._factor("agent", "radius"))
        wx, ht = float(self._factor("wall", "position")), float(self._factor("wall", "thickness")) / 2
        self._lo, self._hi = np.full(2, BORDER + r), np.full(2, SIZE - BORDER - r)
        pieces, y = [], 0.0
        for y0, y1 in sorted(self._door_intervals()):
            if y0 > y:
                pieces.append((wx - ht, y, wx + ht, y0))
            y = max(y, y1)
        if y < SIZE:
            pieces.append((wx - ht, y, wx + ht, SIZE))
        self._boxes = grow_boxes(np.array(pieces).reshape(-1, 4), r)
        layout = np.zeros(STATE_DIM - 2)
        layout[:2] = wx, ht
        for k, (y0, y1) in enumerate(self._door_intervals()):
            layout[2 + 2 * k : 4 + 2 * k] = (y0 + y1) / 2, (y1 - y0) / 2
        self._layout = layout

    def _set_layout_factors(self, state: np.ndarray) -> None:
        """Set the wall and door factors from the layout part of a full ``state``."""
        doors = state[4:STATE_DIM].reshape(MAX_DOORS, 2)
        present = doors[:, 1] > 0
        positions = self._factor("door", "position")
        positions[: present.sum()] = doors[present, 0]
        values: dict[str, Any] = {"wall.position": state[2], "wall.thickness": 2 * state[3], "door.position": positions}
        if present.any():
            values.update({"door.number": int(present.sum()), "door.size": 2 * doors[present, 1].max()})
        self.variation_space.set_value(values)

    def _room_bounds(self, side: int) -> tuple[np.ndarray, np.ndarray]:
        """Reachable area of the left (``side=0``) or right (``side=1``) room for the agent centre."""
        r = float(self._factor("agent", "radius"))
        wx, ht = float(self._factor("wall", "position")), float(self._factor("wall", "thickness")) / 2
        lo, hi = self._lo.copy(), self._hi.copy()
        if side == 0:
            hi[0] = wx - ht - r
        else:
            lo[0] = wx + ht + r
        return lo, hi

    def _draw_positions(self) -> tuple[np.ndarray, np.ndarray]:
        side = int(self.np_random.integers(2))
        start = self.np_random.uniform(*self._room_bounds(side))
        goal = self.np_random.uniform(*self._room_bounds(1 - side))
        return start, goal

    def _legal(self, pos: np.ndarray) -> np.ndarray:
        return push_out(np.asarray(pos, np.float64), self._boxes, self._lo, self._hi)

    def _state(self, goal: bool = False) -> np.ndarray:
        return np.concatenate([self._goal if goal else self._pos, self._layout]).astype(np.float32)

    def _draw_static(self) -> np.ndarray:
        v = self.variation_space.value
        size = self.render_size
        img = draw.new_canvas(size, v["border"]["color"])
        px = draw.world_to_pixels(np.array([[BORDER, BORDER], [SIZE - BORDER, SIZE - BORDER]]), SIZE, size)
        draw.fill_rect(img, *px[0], *px[1], v["background"]["color"])
        wx, ht = self._layout[:2]
        (x0, y0), (x1, y1) = draw.world_to_pixels(np.array([[wx - ht, BORDER], [wx + ht, SIZE - BORDER]]), SIZE, size)
        draw.fill_rect(img, x0, y0, x1, y1, v["wall"]["color"])
        for lo, hi in self._door_intervals():
            ends = np.array([[0.0, max(lo, BORDER)], [0.0, min(hi, SIZE - BORDER)]])
            (_, d0), (_, d1) = draw.world_to_pixels(ends, SIZE, size)
            draw.fill_rect(img, x0, d0, x1, d1, v["door"]["color"])
        return img

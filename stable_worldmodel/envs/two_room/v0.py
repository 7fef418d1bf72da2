"""``swm/TwoRoom-v0``: the TwoRoom of release 0.0.3 (pymunk physics), kept so its datasets transfer.

``swm/TwoRoom-v2`` is our redesigned task; this module reproduces 0.0.3's ``TwoRoomEnv`` from
its observed behaviour (same pymunk world, same step, same observation and info):

- **World**: a 512 x 512 canvas (pixel units, y down). A border of four 9-px-thick static
  polygons along the canvas edges; a wall ``wall.thickness`` px thick at ``WALL_POS = 247``
  (vertical when ``wall.axis`` is 1, horizontal when 0) from ``t = 0`` to ``t = 494`` along it
  (canvas coordinate ``9 + t``). Door ``k`` is the gap ``[position_k, position_k + size_k]``
  in ``t`` (overlapping doors merge; door pieces are non-colliding sensors of ``door.color``).
- **Agent**: a dynamic pymunk disk (mass 1, radius ``agent.radius``, friction 0.8, elasticity
  0). A step sets its velocity to ``action * agent.speed / 0.1`` before each of 10 physics
  sub-steps of 0.01 s (30 solver iterations): ``action * agent.speed`` px per step in free
  space; walls stop it through contacts. Actions of norm above 2.45 are scaled down to 2.45.
- **Goal**: a disk of radius ``goal.radius`` at ``goal.position`` (no physics).
- **Observation**: ``state`` (6,) float64 = agent x, y, goal x, y, energy, speed;
  ``proprio`` (4,) = agent x, y, energy, speed. Energy starts at ``agent.max_energy`` and
  drops by 1 per step; ``truncated`` when it reaches 0.
- **Success** (``terminated``): the agent and goal disks (as 64-gons, as 0.0.3's shapely
  buffers) overlap by at least half of either's area. Reward 1 on success, else -0.01.
- **Reset**: ``agent.position``, ``goal.position``, ``door.number``, ``door.size`` and
  ``door.position`` are drawn on every reset unless ``options["variation"]`` says otherwise.
  ``options["state"]`` / ``options["goal_state"]`` place the agent / goal (their first two
  numbers). The agent is put at the goal, the physics stepped once and the goal image drawn,
  then put at its start and stepped once more (as 0.0.3).
- **Info**: 0.0.3's ``pos_agent``, ``pos_goal``, ``n_contacts``, ``goal_pos``, ``goal``,
  ``energy``, ``max_energy``, ``fraction_of_goal``, ``fraction_of_agent``, plus our
  ``goal_state`` (the state with the agent on the goal) and ``goal_proprio``.
- **Rendering**: see :mod:`.v0_render` (0.0.3's pygame look, drawn with OpenCV).
"""

from __future__ import annotations

import math
from typing import Any

import gymnasium as gym
import numpy as np
import pymunk

from ... import keys, spaces
from ...errors import ConfigError
from ..base import DatasetResetMixin, apply_variation_options, check_render_size
from .v0_overlap import overlap_fractions
from .v0_render import CANVAS, draw_frame

BORDER = 9
SIZE = CANVAS - 2 * BORDER  # 494
WALL_POS = math.ceil(SIZE / 2)  # 247
MAX_DOORS = 3
ENERGY_BOUND = 200
MAX_SPEED = 20.0
MAX_STEP_NORM = 2.45
DT = 0.01
N_SUBSTEPS = 10
SOLVER_ITERATIONS = 30
DEFAULT_VARIATIONS = ("agent.position", "goal.position", "door.number", "door.size", "door.position")
# info keys of 0.0.3's TwoRoom
POS_AGENT, POS_GOAL, GOAL_POS = "pos_agent", "pos_goal", "goal_pos"
N_CONTACTS, ENERGY, MAX_ENERGY = "n_contacts", "energy", "max_energy"
FRACTION_OF_GOAL, FRACTION_OF_AGENT = "fraction_of_goal", "fraction_of_agent"
LAYOUT = "_layout"  # private: (11,) axis, wall pos, half thickness, agent radius, n gaps, (lo, hi) x 3
_CONTACT_DIVISOR = 1000  # 0.0.3 divides the contact count by int(1 / dt * control_hz)


def _scalar(space) -> float:
    return float(np.asarray(space.value).reshape(-1)[0])


class TwoRoomV0Env(DatasetResetMixin, gym.Env):
    """Release 0.0.3's TwoRoom (see the module docstring)."""

    metadata = {"render_modes": ["rgb_array"], "render_fps": 10}

    def __init__(
        self,
        render_size: int | tuple[int, int] = 224,
        render_mode: str | None = "rgb_array",
        init_value: dict | None = None,
    ):
        if render_mode not in (None, "rgb_array"):
            raise ConfigError(f"TwoRoomV0Env requires render_mode 'rgb_array' or None, got {render_mode!r}")
        self.render_mode = render_mode
        self.render_size = (224, 224)
        self.set_render_size((render_size, render_size) if isinstance(render_size, (int, np.integer)) else render_size)
        bs = BORDER
        self.observation_space = gym.spaces.Dict(
            {
                keys.PROPRIO: gym.spaces.Box(
                    np.array([bs, bs, 0, 10], np.float64),
                    np.array([SIZE, SIZE, ENERGY_BOUND, MAX_SPEED], np.float64),
                    dtype=np.float64,
                ),
                keys.STATE: gym.spaces.Box(
                    np.array([bs, bs, bs, bs, 50, 0.5], np.float64),
                    np.array([SIZE] * 4 + [ENERGY_BOUND, MAX_SPEED], np.float64),
                    dtype=np.float64,
                ),
            }
        )
        self.action_space = gym.spaces.Box(-1.0, 1.0, (2,), np.float32)
        self.variation_space = self._build_variation_space()
        if init_value is not None:
            self.variation_space.set_init_value(init_value)
        self.space = self.agent = None
        self.walls: list = []
        self.doors: list = []
        self.border: list = []
        self._goal_pos = (0.0, 0.0)
        self._goal_agent = (0.0, 0.0)  # where the agent was drawn in the goal image
        self._goal_img: np.ndarray | None = None
        self.energy = 0
        self.n_contact_points = 0
        self._fractions = (0.0, 0.0)

    # -- variation space --------------------------------------------------------------------
    def _build_variation_space(self) -> spaces.Dict:
        def rgb(c):
            return spaces.RGBBox(init_value=np.array(c, np.uint8))

        def radius():
            return spaces.Box(
                np.array([15], np.float32),
                np.array([30], np.float32),
                shape=(1,),
                dtype=np.float32,
                init_value=np.array([15], np.float32),
            )

        def position(init, entity):
            return spaces.Box(
                np.array([BORDER] * 2, np.float32),
                np.array([SIZE] * 2, np.float32),
                shape=(2,),
                dtype=np.float32,
                init_value=np.array(init, np.float32),
                constrain_fn=lambda x: not self.check_collide(x, entity=entity),
            )

        return spaces.Dict(
            {
                "agent": spaces.Dict(
                    {
                        "color": rgb([255, 0, 0]),
                        "radius": radius(),
                        "position": position([50.0, 50.0], "agent"),
                        "max_energy": spaces.Discrete(ENERGY_BOUND - 50, start=50, init_value=100),
                        "speed": spaces.Box(
                            np.array([10], np.float32),
                            np.array([MAX_SPEED], np.float32),
                            shape=(1,),
                            dtype=np.float32,
                            init_value=np.array([10.0], np.float32),
                        ),
                    },
                    sampling_order=["color", "radius", "position", "max_energy", "speed"],
                ),
                "goal": spaces.Dict(
                    {"color": rgb([0, 255, 0]), "radius": radius(), "position": position([450.0, 450.0], "goal")},
                    sampling_order=["color", "radius", "position"],
                ),
                "wall": spaces.Dict(
                    {
                        "color": rgb([115, 127, 145]),
                        "thickness": spaces.Discrete(25, start=9, init_value=19),
                        "axis": spaces.Discrete(2, init_value=1),  # 0: horizontal, 1: vertical
                        "border_color": rgb([180, 189, 204]),
                    },
                    sampling_order=["color", "border_color", "thickness", "axis"],
                ),
                "door": spaces.Dict(
                    {
                        "color": rgb([255, 255, 255]),
                        "number": spaces.Discrete(MAX_DOORS, start=1, init_value=1),
                        "size": spaces.MultiDiscrete(
                            nvec=[50] * MAX_DOORS,
                            start=[35] * MAX_DOORS,
                            init_value=np.array([75] * MAX_DOORS),
                            constrain_fn=self.check_one_door_fit,
                        ),
                        "position": spaces.MultiDiscrete(
                            nvec=[SIZE] * MAX_DOORS, init_value=np.array([SIZE // 2] * MAX_DOORS)
                        ),
                    },
                    sampling_order=["color", "number", "size", "position"],
                ),
                "background": spaces.Dict({"color": rgb([255, 255, 255])}),
            },
            sampling_order=["background", "wall", "agent", "door", "goal"],
        )

    def _value(self, group: str, name: str):
        return self.variation_space[group][name].value

    def check_one_door_fit(self, sizes) -> bool:
        """At least one of the first ``door.number`` doors is 2.5 agent radii wide."""
        r = _scalar(self.variation_space["agent"]["radius"])
        return bool(any(float(s) >= 2.5 * r for s in np.asarray(sizes)[: int(self._value("door", "number"))]))

    def check_collide(self, x, entity: str = "agent") -> bool:
        """Whether a disk of ``entity``'s radius at ``x`` touches the border band or the wall (doors ignored)."""
        cx, cy = float(x[0]), float(x[1])
        r = _scalar(self.variation_space[entity]["radius"])
        if cx - r <= BORDER or cx + r >= SIZE or cy - r <= BORDER or cy + r >= SIZE:
            return True
        reach = float(self._value("wall", "thickness")) / 2 + r
        along = cy if int(self._value("wall", "axis")) == 0 else cx
        return abs(along - WALL_POS) <= reach

    # -- protocol hooks ---------------------------------------------------------------------
    def set_render_size(self, size: tuple[int, int]) -> None:
        self.render_size = check_render_size("TwoRoomV0Env", size)
        self._goal_img = None

    def eval_state(self, goal_state: np.ndarray, cur_state: np.ndarray) -> tuple[bool, float]:
        """``(success, distance)`` of the agent at ``cur_state[:2]`` to a goal disk at ``goal_state[:2]``."""
        g, c = np.asarray(goal_state, np.float64)[:2], np.asarray(cur_state, np.float64)[:2]
        fog, foa = overlap_fractions(
            c, _scalar(self.variation_space["agent"]["radius"]), g, _scalar(self.variation_space["goal"]["radius"])
        )
        return bool(fog >= 0.5 or foa >= 0.5), float(np.linalg.norm(g - c))

    # -- gym API ----------------------------------------------------------------------------
    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None):
        super().reset(seed=seed)
        options = dict(options or {})
        if options.get(keys.VARIATION) is None:
            options[keys.VARIATION] = list(DEFAULT_VARIATIONS)
        apply_variation_options(self.variation_space, options, self.np_random)
        if not self.variation_space.check(debug=True):
            raise ConfigError(
                "TwoRoomV0Env requires variation values inside the variation space (the log says which failed)"
            )
        self._setup()
        goal = self._position_option(options, keys.GOAL_STATE, self._value("goal", "position"))
        self._set_position(goal, goal)
        self._goal_agent = tuple(self.agent.position)
        self._goal_img = None
        start = self._position_option(options, keys.STATE, self._value("agent", "position"))
        self._set_position(start, goal)
        self._fractions = (0.0, 0.0)
        return self._obs(), self._info()

    def step(self, action):
        self.n_contact_points = 0
        action = np.asarray(action)
        norm = np.linalg.norm(action)
        if norm > MAX_STEP_NORM:
            action = (action / norm) * MAX_STEP_NORM
        velocity = action / (N_SUBSTEPS * DT)  # kept in the action's dtype, as 0.0.3
        speed = _scalar(self.variation_space["agent"]["speed"])
        self.space.iterations = SOLVER_ITERATIONS
        for _ in range(N_SUBSTEPS):
            v = velocity * speed
            self.agent.velocity = (float(v[0]), float(v[1]))
            self.space.step(DT)
        self.energy -= 1
        self._fractions = overlap_fractions(
            self.agent.position,
            _scalar(self.variation_space["agent"]["radius"]),
            self._goal_pos,
            _scalar(self.variation_space["goal"]["radius"]),
        )
        terminated = self._fractions[0] >= 0.5 or self._fractions[1] >= 0.5
        return self._obs(), 1.0 if terminated else -0.01, terminated, self.energy <= 0, self._info()

    def render(self) -> np.ndarray:
        return self._draw(self.agent.position)

    def close(self) -> None:
        self.space = self.agent = None

    # -- physics ------------------------------------------------------------------------------
    @staticmethod
    def _position_option(options: dict[str, Any], key: str, default) -> list[float]:
        if options.get(key) is None:
            return np.asarray(default).tolist()
        value = np.asarray(options[key]).reshape(-1)
        if value.shape[0] < 2:
            raise ConfigError(
                f"TwoRoomV0Env requires reset option {key!r} with at least 2 numbers, got {options[key]!r}"
            )
        return value[:2].tolist()

    def _set_position(self, agent_position, goal_position) -> None:
        """Place the agent and the goal, then take one physics step (0.0.3's ``_set_position``)."""
        self.agent.position = tuple(np.asarray(agent_position).tolist())
        self._goal_pos = tuple(np.asarray(goal_position).tolist())
        self.space.step(DT)

    def _count_contacts(self, arbiter, space, data) -> None:
        self.n_contact_points += len(arbiter.contact_point_set.points)

    def _door_gaps(self) -> list[tuple[int, int]]:
        """``(position, size)`` of the doors along the wall, sorted, overlapping ones merged."""
        n = int(self._value("door", "number"))
        positions, sizes = self._value("door", "position")[:n].tolist(), self._value("door", "size")[:n].tolist()
        doors = sorted(zip(positions, sizes, strict=False), key=lambda d: d[0])
        merged: list[tuple[int, int]] = []
        for pos, size in doors:
            pos, size = int(pos), int(size)
            if merged and pos <= merged[-1][0] + merged[-1][1]:
                start, length = merged[-1]
                merged[-1] = (start, max(start + length, pos + size) - start)
            else:
                merged.append((pos, size))
        return merged

    def _wall_spans(self) -> tuple[list[tuple[int, int]], list[tuple[int, int]]]:
        """Wall and door spans ``(t0, t1)`` along the wall (each at least 1 px long)."""

        def clamp(t):
            return int(max(0, min(SIZE, int(t))))

        walls, doors, current = [], [], 0
        for pos, size in self._door_gaps():
            d0, d1 = clamp(pos), clamp(pos + size)
            w0, w1 = clamp(current), clamp(d0 - 1)
            if w1 - w0 >= 1:
                walls.append((w0, w1))
            if d1 - d0 >= 1:
                doors.append((d0, d1))
            current = d1 + 1
        w0, w1 = clamp(current), clamp(SIZE)
        if w1 - w0 >= 1:
            walls.append((w0, w1))
        return walls, doors

    def _slab(self, a, b, width: float, sensor: bool = False):
        """A static polygon ``width`` thick around segment a-b, or None when a == b."""
        a, b = pymunk.Vec2d(*a), pymunk.Vec2d(*b)
        if (b - a).length < 1e-6:
            return None
        perp = (b - a).normalized().perpendicular() * (width / 2)
        shape = pymunk.Poly(self.space.static_body, [a + perp, b + perp, b - perp, a - perp])
        shape.sensor = sensor
        return shape

    def _setup(self) -> None:
        """A fresh pymunk space: wall pieces, door sensors, border, agent (in 0.0.3's order)."""
        self.space = pymunk.Space()
        self.space.gravity = (0, 0)
        self.space.damping = 0
        thickness = float(self._value("wall", "thickness"))
        vertical = int(self._value("wall", "axis")) == 1

        def pt(t):
            return (WALL_POS, BORDER + t) if vertical else (BORDER + t, WALL_POS)

        wall_spans, door_spans = self._wall_spans()
        self.walls = [s for s in (self._slab(pt(t0), pt(t1), thickness) for t0, t1 in wall_spans) if s is not None]
        doors = (self._slab(pt(t0), pt(t1), thickness, sensor=True) for t0, t1 in door_spans)
        self.doors = [s for s in doors if s is not None]
        if self.walls:
            self.space.add(*self.walls)
        if self.doors:
            self.space.add(*self.doors)
        ends = (  # bottom, left, right, top, as 0.0.3 (the right one slightly slanted)
            ((0, 0), (CANVAS - 1, 0)),
            ((0, 0), (0, CANVAS)),
            ((CANVAS, 0), (CANVAS - 1, CANVAS)),
            ((0, CANVAS), (CANVAS, CANVAS)),
        )
        self.border = [s for s in (self._slab(a, b, BORDER) for a, b in ends) if s is not None]
        self.space.add(*self.border)
        r = _scalar(self.variation_space["agent"]["radius"])
        self.agent = pymunk.Body(1.0, pymunk.moment_for_circle(1.0, 0, r), body_type=pymunk.Body.DYNAMIC)
        self.agent.position = tuple(self._value("agent", "position").tolist())
        disk = pymunk.Circle(self.agent, r)
        disk.friction, disk.elasticity = 0.8, 0.0
        self.space.add(self.agent, disk)
        self._goal_pos = tuple(self._value("goal", "position").tolist())
        self.energy = int(self._value("agent", "max_energy"))
        if hasattr(self.space, "on_collision"):  # pymunk >= 7
            self.space.on_collision(0, 0, post_solve=self._count_contacts)
        else:
            self.space.add_collision_handler(0, 0).post_solve = self._count_contacts
        self.n_contact_points = 0
        self._layout = self._layout_vector(wall_spans, door_spans, thickness, r)

    def _layout_vector(self, wall_spans, door_spans, thickness: float, radius: float) -> np.ndarray:
        out = np.zeros(5 + 2 * MAX_DOORS)
        out[:5] = int(self._value("wall", "axis")), WALL_POS, thickness / 2, radius, len(door_spans)
        for k, (t0, t1) in enumerate(door_spans[:MAX_DOORS]):
            out[5 + 2 * k : 7 + 2 * k] = BORDER + t0, BORDER + t1
        return out

    # -- observation, info, drawing --------------------------------------------------------------
    def _state(self, agent_xy) -> np.ndarray:
        speed = _scalar(self.variation_space["agent"]["speed"])
        return np.array([*agent_xy, *self._goal_pos, self.energy, speed], np.float64)

    def _obs(self) -> dict[str, np.ndarray]:
        state = self._state(tuple(self.agent.position))
        return {keys.PROPRIO: state[[0, 1, 4, 5]], keys.STATE: state}

    def _info(self) -> dict[str, Any]:
        if self._goal_img is None:
            self._goal_img = self._draw(self._goal_agent)
        goal_state = self._state(self._goal_pos)
        goal_state[4] = int(self._value("agent", "max_energy"))
        return {
            POS_AGENT: np.array(tuple(self.agent.position)),
            POS_GOAL: np.array(self._goal_pos),
            N_CONTACTS: int(np.ceil(self.n_contact_points / _CONTACT_DIVISOR)),
            GOAL_POS: self._value("goal", "position"),
            keys.GOAL: self._goal_img.copy(),
            ENERGY: self.energy,
            MAX_ENERGY: int(self._value("agent", "max_energy")),
            FRACTION_OF_GOAL: float(self._fractions[0]),
            FRACTION_OF_AGENT: float(self._fractions[1]),
            keys.GOAL_STATE: goal_state,
            keys.GOAL_PROPRIO: goal_state[[0, 1, 4, 5]],
            LAYOUT: self._layout.copy(),
        }

    def _draw(self, agent_xy) -> np.ndarray:
        v = self.variation_space

        def polys(shapes, color):
            return [(np.array([tuple(p) for p in s.get_vertices()]), color) for s in shapes]

        return draw_frame(
            self.render_size,
            v["background"]["color"].value,
            polys(self.walls, v["wall"]["color"].value),
            polys(self.doors, v["door"]["color"].value),
            polys(self.border, v["wall"]["border_color"].value),
            (self._goal_pos, _scalar(v["goal"]["radius"]), v["goal"]["color"].value),
            (agent_xy, _scalar(v["agent"]["radius"]), v["agent"]["color"].value),
        )

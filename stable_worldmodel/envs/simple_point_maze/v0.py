"""``swm/SimplePointMaze-v0``: release 0.1.1's SimplePointMaze (a disk among random rectangles).

Our grid maze with a friction point mass is ``swm/SimplePointMaze-v1`` (:mod:`.env`). This
module keeps the id's original meaning, written from the observed behaviour of 0.1.1:

- **World**: the square ``[0, 5]^2`` (y up). ``walls.number`` (4 to 6, default 5) axis-aligned
  rectangles with lower-left corner ``walls.positions[k]`` and size ``walls.shape[k]`` (each
  side in ``[0.5, 1.5]``); a wall layout is valid when every rectangle lies inside the square and
  neither the agent nor the goal disk touches one.
- **Step**: the action is clipped to ``[-0.2, 0.2]^2``; the agent moves to
  ``position + agent.speed * action`` unless its disk (radius ``agent.radius``) would touch a
  wall there, in which case it stays where it is; then the position is clipped to the square.
- **Observation**: the agent position, a flat ``Box(2)`` float32 on ``[0, 5]^2``.
- **Success** (``terminated``): the distance from the agent centre to ``goal.position`` is
  below ``goal.radius``. Reward 1 on success, else -0.01. Never truncated by the env.
- **Reset**: the variation space is seeded with the reset seed itself (as 0.1.1; a reset
  without a seed draws one from the env's generator), reset to its defaults, then the factors
  named in ``options["variation"]`` (default ``["agent.position"]``) are resampled.
  ``options["variation_values"]`` sets factors; ``options["state"]`` / ``options["goal_state"]``
  place the agent / the goal (first two numbers).
- **Info**: 0.1.1's ``goal``, a frame with the goal disk and the agent drawn at a freshly
  sampled ``agent.position`` (at the goal state when ``options["goal_state"]`` is given), plus
  our ``state`` / ``proprio`` (agent position), ``goal_state`` / ``goal_proprio`` (goal
  position) and the private ``_layout`` read by the expert.
- **Rendering**: :mod:`.v0_render` (matplotlib, 500 x 500 px native, ``set_render_size``
  shrinks it); matplotlib draws what does not move once per episode and each frame blends the
  agent in (within 0.005/255 mean absolute difference of matplotlib's frames, ~50x faster).

One deliberate difference: actions are cast to float32 before use, so the position stays
float32 (0.1.1 promotes it to float64 when given float64 actions; the values agree to float32
rounding).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import gymnasium as gym
import numpy as np

from ... import keys, spaces
from ...errors import ConfigError, unknown_name
from ..base import DatasetResetMixin, check_render_size, flatten_values, point_option
from .v0_render import NATIVE, MazeCanvas

WIDTH = HEIGHT = 5.0
MAX_ACTION = 0.2
DEFAULT_VARIATIONS = ("agent.position",)
SUCCESS_REWARD, STEP_REWARD = 1.0, -0.01
LAYOUT = "_layout"  # private: (4 + 4 * max_walls,) speed, agent radius, goal radius, n walls, (x, y, w, h) per wall
_WALL_INIT_SEED = 234232  # 0.1.1 draws the default wall layout from this generator


class SimplePointMazeV0Env(DatasetResetMixin, gym.Env):
    """Release 0.1.1's SimplePointMaze (see the module docstring)."""

    metadata = {"render_modes": ["rgb_array"], "render_fps": 10}

    def __init__(
        self,
        max_walls: int = 6,
        min_walls: int = 4,
        wall_min_size: float = 0.5,
        wall_max_size: float = 1.5,
        render_mode: str | None = "rgb_array",
        show_goal: bool = True,
        render_size: int | tuple[int, int] = NATIVE,
    ):
        if render_mode not in (None, "rgb_array"):
            raise ConfigError(f"SimplePointMazeV0Env requires render_mode 'rgb_array' or None, got {render_mode!r}")
        if not 1 <= min_walls <= max_walls:
            raise ConfigError(
                f"SimplePointMazeV0Env requires 1 <= min_walls <= max_walls, got {min_walls}, {max_walls}"
            )
        self.render_mode = render_mode
        self.show_goal = bool(show_goal)
        self.width, self.height = WIDTH, HEIGHT
        self.max_walls = int(max_walls)
        self.render_size = (NATIVE, NATIVE)
        self.set_render_size((render_size, render_size) if isinstance(render_size, (int, np.integer)) else render_size)
        self.observation_space = gym.spaces.Box(
            np.zeros(2, np.float32), np.array([WIDTH, HEIGHT], np.float32), shape=(2,), dtype=np.float32
        )
        self.action_space = gym.spaces.Box(
            np.full(2, -MAX_ACTION, np.float32), np.full(2, MAX_ACTION, np.float32), shape=(2,), dtype=np.float32
        )
        self.variation_space = self._build_variation_space(int(min_walls), float(wall_min_size), float(wall_max_size))
        self.state = self.variation_space["agent"]["position"].value.copy()
        if not self.variation_space.check():
            raise ConfigError("SimplePointMazeV0Env requires default factor values inside the variation space")
        self._canvas: MazeCanvas | None = None
        self._goal_agent = self.state.copy()
        self._goal_img: np.ndarray | None = None

    # -- variation space --------------------------------------------------------------------
    def _build_variation_space(self, min_walls: int, wall_min: float, wall_max: float) -> spaces.Dict:
        n = self.max_walls
        size_low, size_high = np.full((n, 2), wall_min, np.float32), np.full((n, 2), wall_max, np.float32)
        rng = np.random.default_rng(_WALL_INIT_SEED)
        init_shape = rng.uniform(size_low, size_high, (n, 2)).astype(np.float32)
        init_positions = rng.uniform(1, 3.5, (n, 2)).astype(np.float32)
        corner = np.array([WIDTH, HEIGHT], np.float32)

        def rgb(c):
            return spaces.RGBBox(init_value=np.array(c, np.uint8))

        def scalar(low, high, init):
            return spaces.Box(low, high, shape=(), dtype=np.float32, init_value=np.array(init, np.float32))

        def position(init, entity):
            return spaces.Box(
                np.zeros(2, np.float32),
                corner,
                shape=(2,),
                dtype=np.float32,
                init_value=np.array(init, np.float32),
                constrain_fn=lambda v: not self._collides(v, entity=entity),
            )

        # Keys in alphabetical order, as Gymnasium sorts 0.1.1's plain dicts: the per-key seeds
        # (and the sampling order where none is given) follow this order. Each Dict re-checks its
        # leaves' constraints after a draw (0.1.1's Dict.sample does), redrawing the group if one fails.
        walls = {
            "color": rgb([0, 0, 0]),
            "number": spaces.Discrete(n - min_walls + 1, start=min_walls, init_value=min(5, n)),
            "positions": spaces.Box(
                np.zeros((n, 2), np.float32),
                np.tile(corner, (n, 1)),
                shape=(n, 2),
                dtype=np.float32,
                init_value=init_positions,
                constrain_fn=self._check_walls,
            ),
            "shape": spaces.Box(size_low, size_high, shape=(n, 2), dtype=np.float32, init_value=init_shape),
        }
        return spaces.Dict(
            {
                "agent": spaces.Dict(
                    {
                        "color": rgb([255, 0, 0]),
                        "position": position([0.5, 0.5], "agent"),
                        "radius": scalar(0.05, 0.5, 0.1),
                        "speed": scalar(0.05, 2, 1.0),
                    },
                    constrain_fn=lambda v: not self._collides(v["position"], entity="agent"),
                ),
                "background": spaces.Dict({"color": rgb([255, 255, 255])}),
                "goal": spaces.Dict(
                    {
                        "color": rgb([0, 255, 0]),
                        "position": position([4.5, 4.5], "goal"),
                        "radius": scalar(0.05, 0.5, 0.2),
                    },
                    constrain_fn=lambda v: not self._collides(v["position"], entity="goal"),
                ),
                "walls": spaces.Dict(
                    walls,
                    sampling_order=["number", "color", "shape", "positions"],
                    constrain_fn=lambda v: self._check_walls(v["positions"]),
                ),
            },
            sampling_order=["agent", "goal", "walls", "background"],
            constrain_fn=lambda v: self._check_walls(v["walls"]["positions"]),
        )

    def _walls(self, positions=None) -> np.ndarray:
        """(n, 4) ``x, y, w, h`` of the active walls (``positions`` replaces the stored corners)."""
        v = self.variation_space["walls"]
        n = int(v["number"].value)
        corners = v["positions"].value if positions is None else np.asarray(positions)
        return np.concatenate([corners[:n], v["shape"].value[:n]], axis=1)

    def _collides(self, pos, walls=None, entity: str = "agent") -> bool:
        """Whether ``entity``'s disk at ``pos`` touches an active wall (``walls``: replacement corners)."""
        x, y = pos[0], pos[1]
        radius = self.variation_space[entity]["radius"].value
        boxes = self._walls(walls)
        x1, y1, x2, y2 = boxes[:, 0], boxes[:, 1], boxes[:, 0] + boxes[:, 2], boxes[:, 1] + boxes[:, 3]
        left, right = np.minimum(x1, x2), np.maximum(x1, x2)
        low, high = np.minimum(y1, y2), np.maximum(y1, y2)
        if radius <= 0:
            return bool(np.any((left <= x) & (x <= right) & (low <= y) & (y <= high)))
        dx, dy = np.clip(x, left, right) - x, np.clip(y, low, high) - y
        return bool(np.any(dx**2 + dy**2 <= radius**2))

    def _check_walls(self, corners) -> bool:
        """Walls inside the square and clear of the agent and goal disks."""
        n = int(self.variation_space["walls"]["number"].value)
        xy, wh = np.asarray(corners)[:n], self.variation_space["walls"]["shape"].value[:n]
        inside = bool(np.all((xy >= 0) & (xy <= [WIDTH, HEIGHT]) & (xy + wh <= [WIDTH, HEIGHT])))
        value = self.variation_space.value
        return inside and not (
            self._collides(value["agent"]["position"], walls=corners, entity="agent")
            or self._collides(value["goal"]["position"], walls=corners, entity="goal")
        )

    # -- protocol hooks ---------------------------------------------------------------------
    def set_render_size(self, size: tuple[int, int]) -> None:
        self.render_size = check_render_size("SimplePointMazeV0Env", size)
        self._goal_img = None

    def eval_state(self, goal_state: np.ndarray, cur_state: np.ndarray) -> tuple[bool, float]:
        """``(success, distance)``: the agent at ``cur_state[:2]`` within ``goal.radius`` of ``goal_state[:2]``."""
        g = np.asarray(goal_state, np.float32).reshape(-1)[:2]
        c = np.asarray(cur_state, np.float32).reshape(-1)[:2]
        dist = float(np.linalg.norm(c - g))
        return bool(dist < float(self.variation_space["goal"]["radius"].value)), dist

    # -- gym API ----------------------------------------------------------------------------
    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None):
        super().reset(seed=seed)
        options = dict(options or {})
        vs = self.variation_space
        vs.seed(int(seed) if seed is not None else int(self.np_random.integers(0, 2**31 - 1)))
        vs.reset()
        variations = options.get(keys.VARIATION)
        variations = DEFAULT_VARIATIONS if variations is None else variations
        if isinstance(variations, str) or not isinstance(variations, Sequence):
            raise ConfigError(
                f"SimplePointMazeV0Env requires reset option 'variation' as a list of factor names, got {variations!r}"
            )
        names = vs.names()
        for name in variations:
            if name != "all" and name not in names and not any(n.startswith(name + ".") for n in names):
                raise unknown_name("variation factor", name, ["all", *names])
        vs.update(list(variations))
        if options.get(keys.VARIATION_VALUES):
            flat = flatten_values(options[keys.VARIATION_VALUES])
            for name in flat:
                if name not in names:
                    raise unknown_name("variation factor", name, names)
            vs.set_value(flat)
        if not vs.check(debug=True):
            raise ConfigError(
                "SimplePointMazeV0Env requires factor values inside the variation space (the log says which failed)"
            )
        goal_option = point_option("SimplePointMazeV0Env", options, keys.GOAL_STATE)
        if goal_option is None:  # 0.1.1 draws the goal image with the agent at a fresh sample
            self._goal_agent = np.asarray(vs["agent"]["position"].sample(set_value=False), np.float32).copy()
        else:
            vs["goal"]["position"].set_value(goal_option)
            self._goal_agent = goal_option
        self._goal_img = None
        start = point_option("SimplePointMazeV0Env", options, keys.STATE)
        if start is not None:
            vs["agent"]["position"].set_value(start)
        self.state = vs["agent"]["position"].value.copy()
        return self.state.copy(), self._info()

    def step(self, action):
        action = np.clip(np.asarray(action, np.float32), self.action_space.low, self.action_space.high)
        moved = self.state + self.variation_space["agent"]["speed"].value * action
        if self._collides(moved, entity="agent"):
            moved = self.state
        self.state = np.clip(moved, self.observation_space.low, self.observation_space.high)
        self.variation_space["agent"]["position"]._value = self.state.copy()
        goal = self.variation_space["goal"]
        terminated = bool(np.linalg.norm(self.state - goal["position"].value) < goal["radius"].value)
        reward = SUCCESS_REWARD if terminated else STEP_REWARD
        return self.state.copy(), reward, terminated, False, self._info()

    def render(self) -> np.ndarray:
        return self._draw(self.state)

    def close(self) -> None:
        if self._canvas is not None:
            self._canvas.close()
            self._canvas = None

    # -- info and drawing ---------------------------------------------------------------------
    def _layout(self) -> np.ndarray:
        v = self.variation_space
        out = np.zeros(4 + 4 * self.max_walls, np.float32)
        walls = self._walls()
        out[:4] = v["agent"]["speed"].value, v["agent"]["radius"].value, v["goal"]["radius"].value, len(walls)
        out[4 : 4 + walls.size] = walls.reshape(-1)
        return out

    def _info(self) -> dict[str, Any]:
        if self._goal_img is None:
            self._goal_img = self._draw(self._goal_agent)
        agent = self.state.astype(np.float32)
        goal = np.asarray(self.variation_space["goal"]["position"].value, np.float32)
        return {
            keys.GOAL: self._goal_img.copy(),
            keys.STATE: agent.copy(),
            keys.PROPRIO: agent.copy(),
            keys.GOAL_STATE: goal.copy(),
            keys.GOAL_PROPRIO: goal.copy(),
            LAYOUT: self._layout(),
        }

    def _draw(self, agent_xy) -> np.ndarray:
        if self._canvas is None:
            self._canvas = MazeCanvas(WIDTH, HEIGHT)
        v = self.variation_space
        goal = (v["goal"]["position"].value, v["goal"]["radius"].value, v["goal"]["color"].value)
        scene = {
            "background": v["background"]["color"].value,
            "walls": [tuple(w) for w in self._walls()],
            "wall_color": v["walls"]["color"].value,
            "goal": goal if self.show_goal else None,
            "agent": (np.asarray(agent_xy), v["agent"]["radius"].value, v["agent"]["color"].value),
        }
        return self._canvas.draw(scene, self.render_size)

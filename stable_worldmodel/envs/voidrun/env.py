"""``swm/VoidRun-v0``: walk across a crumbling floor to the goal without falling into the void.

Rules
-----
- The world is a ``grid_size`` x ``grid_size`` grid of floor cells (constructor argument >= 4,
  default 8; not a factor, since it sets the shape of ``state``) floating in the void. Cells are
  written ``(x, y)`` = (column, row); ``y`` grows downwards, as in the image.
- Actions are ``Discrete(4)``: ``0`` LEFT (x - 1), ``1`` RIGHT (x + 1), ``2`` DOWN (y + 1),
  ``3`` UP (y - 1). Every action moves the agent by one cell; there is no "stay".
- When the agent steps off a cell, that cell breaks with probability ``prob_break`` (a factor of
  variation; the goal cell never breaks). At reset a fraction ``floor.holes`` of the cells is
  already missing, never the goal, the start or the start's neighbours (so the first move off an
  inner start cannot fall); the layout is drawn from the reset seed and always leaves a path from
  start to goal. Default start ``(1, 1)``, default goal ``(grid_size - 2, grid_size - 2)``.
- Stepping onto a missing cell or off the grid is a fall: the episode ends with
  ``terminated=False, truncated=True`` (a fall is a failure, and ``World`` counts ``terminated`` as
  success). The fallen agent stays where it fell (possibly one cell outside the grid) and is drawn
  smaller; further steps change nothing.
- Reaching the goal cell is success: ``terminated=True``. Reward: ``+1`` on success, ``-1`` on a
  fall, ``0`` otherwise.

Observations (float32, integral values)
---------------------------------------
- ``proprio`` = agent cell ``(x, y)``, in ``[-1, grid_size]`` (outside the grid only after a fall).
- ``state`` = ``(agent x, agent y, goal x, goal y, floor mask)`` where the floor mask is the
  ``grid_size * grid_size`` row-major flattening of ``mask[y, x]`` (1 = intact, 0 = missing):
  length ``4 + grid_size**2``.
- ``goal_state`` is the state of the goal configuration (agent on the goal cell, floor as at
  reset), ``goal_proprio`` the goal cell, ``goal`` its image (drawn once per reset).
- ``eval_state(goal_state, cur_state)`` -> ``(agent cell == goal_state's agent cell, Manhattan
  distance between them)``.

Factors of variation (``variation_space``)
------------------------------------------
``prob_break``; ``floor.holes``, ``floor.color``, ``floor.broken_color``; ``void.color``;
``agent.start``, ``agent.color``, ``agent.radius`` (fraction of a cell); ``goal.position``,
``goal.color``. Start and goal are never sampled onto the same cell (a start *set* onto the goal
with ``variation_values`` gives an episode that succeeds at its first step).

Rendering draws directly at ``render_size`` (default 224x224), anti-aliased (tiles by their exact
pixel coverage, the agent with ``envs.utils``): the grid fills the frame with half a cell of void
around it; intact cells are ``floor.color`` tiles, missing ones small ``floor.broken_color``
squares on the void, the goal a ``goal.color`` tile, the agent a disk.
"""

from __future__ import annotations

from collections import deque
from functools import lru_cache
from typing import Any

import gymnasium as gym
import numpy as np

from ... import keys, spaces
from ...errors import ConfigError
from .. import utils
from ..base import DatasetResetMixin, apply_variation_options

LEFT, RIGHT, DOWN, UP = 0, 1, 2, 3
MOVES = np.array([[-1, 0], [1, 0], [0, 1], [0, -1]], np.int64)  # (dx, dy) of each action
_MAX_LAYOUT_TRIES = 100


def shortest_path_lengths(mask: np.ndarray, goal: tuple[int, int]) -> np.ndarray:
    """Steps from every intact cell to ``goal`` over intact cells (BFS); -1 where unreachable.

    ``mask`` is ``(N, N)`` indexed ``[y, x]``; ``goal`` is ``(x, y)``. Returns ``(N, N)`` int.
    """
    n = mask.shape[0]
    free = mask.reshape(-1).tolist()  # plain lists: far faster than numpy scalars for 64 cells
    dist = [-1] * (n * n)
    start = int(goal[1]) * n + int(goal[0])
    if free[start]:
        dist[start] = 0
        queue = deque([start])
        while queue:
            i = queue.popleft()
            y, x = divmod(i, n)
            for j, ok in ((i - 1, x > 0), (i + 1, x < n - 1), (i + n, y < n - 1), (i - n, y > 0)):
                if ok and free[j] and dist[j] < 0:
                    dist[j] = dist[i] + 1
                    queue.append(j)
    return np.array(dist, np.int64).reshape(n, n)


class VoidRunEnv(DatasetResetMixin, gym.Env):
    """Grid navigation over a breaking floor (see the module docstring for the rules)."""

    metadata = {"render_modes": ["rgb_array"], "render_fps": 5}

    def __init__(
        self,
        grid_size: int = 8,
        render_mode: str | None = "rgb_array",
        render_size: tuple[int, int] = (224, 224),
    ):
        if int(grid_size) < 4:
            raise ConfigError(f"VoidRunEnv requires grid_size >= 4, got {grid_size}")
        self.grid_size = n = int(grid_size)
        self.render_mode = render_mode
        self.render_size = (int(render_size[0]), int(render_size[1]))
        cell_low, cell_high = np.full(2, -1, np.float32), np.full(2, n, np.float32)
        state_low = np.concatenate([cell_low, np.zeros(2 + n * n, np.float32)])
        state_high = np.concatenate([cell_high, np.full(2, n - 1, np.float32), np.ones(n * n, np.float32)])
        self.observation_space = gym.spaces.Dict(
            {
                keys.PROPRIO: gym.spaces.Box(cell_low, cell_high, dtype=np.float32),
                keys.STATE: gym.spaces.Box(state_low, state_high, dtype=np.float32),
            }
        )
        self.action_space = gym.spaces.Discrete(4)
        self.variation_space = self._make_variation_space()
        self._agent = np.ones(2, np.int64)
        self._goal = np.array([n - 2, n - 2], np.int64)
        self._mask = np.ones((n, n), bool)
        self._start_mask = self._mask.copy()
        self._goal_img: np.ndarray | None = None

    def _make_variation_space(self) -> spaces.Dict:
        n = self.grid_size

        def differs_from(group: str, name: str):
            def check(cell) -> bool:
                space = getattr(self, "variation_space", None)  # None while it is being built
                return space is None or not np.array_equal(np.asarray(cell), space[group][name].value)

            return check

        def rgb(*c: int) -> spaces.RGBBox:
            return spaces.RGBBox(init_value=np.array(c, np.uint8))

        def unit(low: float, high: float, init: float) -> spaces.Box:
            return spaces.Box(low, high, shape=(), dtype=np.float32, init_value=np.float32(init))

        return spaces.Dict(
            {
                "prob_break": unit(0.0, 1.0, 0.5),
                "floor": spaces.Dict(
                    {
                        "holes": unit(0.0, 0.35, 0.2),
                        "color": rgb(205, 195, 175),
                        "broken_color": rgb(95, 70, 55),
                    }
                ),
                "void": spaces.Dict({"color": rgb(18, 16, 32)}),
                "agent": spaces.Dict(
                    {
                        "start": spaces.MultiDiscrete(
                            [n, n], init_value=np.array([1, 1], np.int64), constrain_fn=differs_from("goal", "position")
                        ),
                        "color": rgb(50, 110, 230),
                        "radius": unit(0.2, 0.45, 0.34),
                    }
                ),
                "goal": spaces.Dict(
                    {
                        "position": spaces.MultiDiscrete(
                            [n, n],
                            init_value=np.array([n - 2, n - 2], np.int64),
                            constrain_fn=differs_from("agent", "start"),
                        ),
                        "color": rgb(60, 200, 90),
                    }
                ),
            },
            sampling_order=["prob_break", "floor", "void", "agent", "goal"],
        )

    # -- protocol hooks -------------------------------------------------------------
    def set_render_size(self, size: tuple[int, int]) -> None:
        self.render_size = (int(size[0]), int(size[1]))
        self._goal_img = None

    def eval_state(self, goal_state: np.ndarray, cur_state: np.ndarray) -> tuple[bool, float]:
        goal = np.asarray(goal_state, np.float64)[:2]
        cur = np.asarray(cur_state, np.float64)[:2]
        dist = float(np.abs(goal - cur).sum())
        return dist < 0.5, dist

    # -- gym API ---------------------------------------------------------------------
    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None):
        super().reset(seed=seed)
        options = options or {}
        v = apply_variation_options(self.variation_space, options, self.np_random)
        self._agent = np.asarray(v["agent"]["start"], np.int64).copy()
        self._goal = np.asarray(v["goal"]["position"], np.int64).copy()
        self._mask = self._random_layout(float(v["floor"]["holes"]))
        if keys.STATE in options:
            self._set_state(np.asarray(options[keys.STATE]))
        if keys.GOAL_STATE in options:
            self._goal = self._cell(np.asarray(options[keys.GOAL_STATE])[:2], "goal_state")
            self._mask[self._goal[1], self._goal[0]] = True
        self._start_mask = self._mask.copy()
        self._goal_img = None
        return self._obs(), self._info()

    def step(self, action):
        action = int(np.asarray(action).reshape(-1)[0])
        if not 0 <= action < 4:
            raise ConfigError(f"VoidRunEnv requires an action in {{0, 1, 2, 3}}, got {action}")
        if self._fallen() or self._at_goal():  # the episode is over: nothing moves any more
            return self._obs(), 0.0, self._at_goal(), self._fallen(), self._info()
        old = self._agent.copy()
        self._agent = old + MOVES[action]
        p_break = float(self.variation_space["prob_break"].value)
        if not np.array_equal(old, self._goal) and self.np_random.random() < p_break:
            self._mask[old[1], old[0]] = False
        success, fallen = self._at_goal(), self._fallen()
        reward = 1.0 if success else (-1.0 if fallen else 0.0)
        return self._obs(), reward, success, fallen, self._info()

    def render(self) -> np.ndarray:
        return self._draw(self._agent, self._mask)

    # -- internals -----------------------------------------------------------------------
    def _cell(self, xy: np.ndarray, what: str, low: int = 0) -> np.ndarray:
        cell = np.rint(np.asarray(xy, np.float64)).astype(np.int64)
        if np.any(cell < low) or np.any(cell > self.grid_size - 1 - low):
            raise ConfigError(
                f"VoidRunEnv requires {what} cells inside the {self.grid_size}x{self.grid_size} grid, got {xy}"
            )
        return cell

    def _set_state(self, state: np.ndarray) -> None:
        n = self.grid_size
        if state.shape != (4 + n * n,):
            raise ConfigError(f"VoidRunEnv requires a state of shape {(4 + n * n,)}, got {state.shape}")
        self._agent = np.rint(state[:2]).astype(np.int64)
        if np.any(self._agent < -1) or np.any(self._agent > n):
            raise ConfigError(f"VoidRunEnv requires an agent cell in [-1, {n}], got {state[:2]}")
        self._goal = self._cell(state[2:4], "goal")
        self._mask = state[4:].reshape(n, n) > 0.5
        self._mask[self._goal[1], self._goal[0]] = True

    def _random_layout(self, holes: float) -> np.ndarray:
        """A floor with about ``holes`` of its cells missing and a path from start to goal."""
        n = self.grid_size
        keep = np.ones((n, n), bool)  # cells that may become holes
        for dx, dy in np.concatenate([MOVES, [[0, 0]]]):
            x, y = self._agent[0] + dx, self._agent[1] + dy
            if 0 <= x < n and 0 <= y < n:
                keep[y, x] = False
        keep[self._goal[1], self._goal[0]] = False
        for _ in range(_MAX_LAYOUT_TRIES):
            mask = (self.np_random.random((n, n)) >= holes) | ~keep
            if shortest_path_lengths(mask, self._goal)[self._agent[1], self._agent[0]] >= 0:
                return mask
        mask[self._agent[1], :] = True  # no luck: open an L-shaped corridor
        mask[:, self._goal[0]] = True
        return mask

    def _inside(self, cell: np.ndarray) -> bool:
        return bool(0 <= cell[0] < self.grid_size and 0 <= cell[1] < self.grid_size)

    def _fallen(self) -> bool:
        return not self._inside(self._agent) or not self._mask[self._agent[1], self._agent[0]]

    def _at_goal(self) -> bool:
        return bool(np.array_equal(self._agent, self._goal))

    def _state(self, agent: np.ndarray, mask: np.ndarray) -> np.ndarray:
        return np.concatenate([agent, self._goal, mask.reshape(-1)]).astype(np.float32)

    def _obs(self) -> dict[str, np.ndarray]:
        return {keys.PROPRIO: self._agent.astype(np.float32), keys.STATE: self._state(self._agent, self._mask)}

    def _info(self) -> dict[str, Any]:
        if self._goal_img is None:  # the goal image only changes on reset
            self._goal_img = self._draw(self._goal, self._start_mask)
        return {
            keys.GOAL: self._goal_img.copy(),  # infos must not share arrays (check_env)
            keys.GOAL_STATE: self._state(self._goal, self._start_mask),
            keys.GOAL_PROPRIO: self._goal.astype(np.float32),
        }

    def _draw(self, agent: np.ndarray, mask: np.ndarray) -> np.ndarray:
        v = self.variation_space.value
        n = self.grid_size
        h, w = self.render_size
        (fy, fx), (by, bx) = _band_coverage(n, h, w, _FLOOR_INSET), _band_coverage(n, h, w, _BROKEN_INSET)
        gy, gx = _band_coverage(n, h, w, _GOAL_INSET)
        m = mask.astype(np.float32)
        cover = np.empty((h, w, 3), np.float32)  # coverage of floor tiles, broken tiles, goal tile
        cover[..., 0] = fy.T @ m @ fx
        cover[..., 1] = by.T @ (1.0 - m) @ bx
        cover[..., 2] = np.outer(gy[self._goal[1]], gx[self._goal[0]])
        void, floor, broken, goal = (
            np.asarray(c, np.float32)
            for c in (v["void"]["color"], v["floor"]["color"], v["floor"]["broken_color"], v["goal"]["color"])
        )
        # floor and broken tiles lie side by side on the void; the goal tile lies inside a floor tile
        img = cover @ np.stack([floor - void, broken - void, goal - floor]) + (void + 0.5)
        img = img.astype(np.uint8)
        cw, ch = w / (n + 1), h / (n + 1)  # half a cell of void on every side
        inside = 0 <= agent[0] < n and 0 <= agent[1] < n
        fallen = not inside or not mask[agent[1], agent[0]]
        radius = float(v["agent"]["radius"]) * min(cw, ch) * (0.5 if fallen else 1.0)
        utils.fill_circle(img, ((agent[0] + 1.0) * cw, (agent[1] + 1.0) * ch), radius, v["agent"]["color"])
        return img


_FLOOR_INSET, _BROKEN_INSET, _GOAL_INSET = 0.04, 0.22, 0.1  # tile margins, in cells


@lru_cache(maxsize=32)
def _band_coverage(n: int, h: int, w: int, inset: float) -> tuple[np.ndarray, np.ndarray]:
    """Exact box-filter coverage of the tile rows/columns over pixel rows/columns.

    Cell ``k`` of an ``n``-cell grid drawn with half a cell of margin spans
    ``[(k + 0.5 + inset) * c, (k + 1.5 - inset) * c]`` pixels (``c`` = cell size). Returns
    ``(n, H)`` and ``(n, W)`` float32 arrays; the coverage of tile ``(x, y)`` at pixel ``(i, j)``
    is ``rows[y, i] * cols[x, j]``, so a whole mask of tiles is ``rows.T @ mask @ cols``.
    """

    def bands(size: int) -> np.ndarray:
        c = size / (n + 1)
        lo = (np.arange(n) + 0.5 + inset)[:, None] * c
        hi = (np.arange(n) + 1.5 - inset)[:, None] * c
        px = np.arange(size)[None, :]
        return np.clip(np.minimum(hi, px + 1) - np.maximum(lo, px), 0.0, 1.0).astype(np.float32)

    return bands(h), bands(w)

"""``swm/ImagePositioning-v1``: slide and turn a few small images into a target arrangement.

Rules
-----
- The canvas is the unit square ``[0, 1]^2`` (``y`` down, as in the image) over a plain
  background. It holds ``n_images`` (constructor argument, default 3) square images generated
  procedurally from the factor ``images.seed`` (see ``images.py``); each image ``i`` has a centre
  ``(x_i, y_i)`` in ``[0, 1]^2`` and an angle ``a_i`` in ``[-pi, pi)`` (radians, clockwise on
  screen). Images are drawn in index order (a later image covers an earlier one).
- Actions are ``Box([-1, 1]^(3 * n_images))`` laid out ``(dx_0, dy_0, da_0, dx_1, ...)``; a step
  clips the action to ``[-1, 1]``, moves image ``i`` by ``step.position * (dx_i, dy_i)`` (centres
  are clipped to ``[0, 1]``) and turns it by ``step.angle * da_i`` (angles wrapped to
  ``[-pi, pi)``).
- Success (``terminated``) when every image is within ``POSITION_TOLERANCE`` (0.03, canvas units,
  Euclidean) of its target centre and within ``ANGLE_TOLERANCE`` (pi / 18 = 10 degrees, wrapped)
  of its target angle. Reward = ``-distance`` (below). Episodes never truncate by themselves.

Observations (float32)
----------------------
- ``state`` = ``proprio`` = ``(x_0, y_0, a_0, x_1, y_1, a_1, ...)``: shape ``(3 * n_images,)``
  (the agent is the set of images).
- ``goal_state`` = ``goal_proprio`` = the target arrangement in the same layout; ``goal`` = its
  image (drawn once per reset).
- ``eval_state(goal_state, cur_state)`` -> ``(success, distance)`` with ``distance`` the L2 norm of
  all position errors and angle errors divided by pi.

Factors of variation (``variation_space``)
------------------------------------------
``background.color``; ``images.seed`` (which image set), ``images.size`` (tile side, canvas
units); ``start.positions`` ``(n_images, 2)``, ``start.angles`` ``(n_images,)``;
``target.positions``, ``target.angles``; ``step.position``, ``step.angle``. Defaults give every
image a fixed start and target that differ; resample ``["start", "target"]`` for new tasks.
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np

from ... import keys, spaces
from ...errors import ConfigError
from .. import utils
from ..base import DatasetResetMixin, apply_variation_options
from .images import draw_sprite, make_sprites

POSITION_TOLERANCE = 0.03
ANGLE_TOLERANCE = np.pi / 18


def wrap_angle(a: np.ndarray) -> np.ndarray:
    """Angles wrapped to ``[-pi, pi)``."""
    return (np.asarray(a, np.float64) + np.pi) % (2 * np.pi) - np.pi


def arrangement_errors(goal_state: np.ndarray, cur_state: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per-image position error (Euclidean) and absolute wrapped angle error; ``(..., N)`` each.

    Both states are laid out ``(..., 3 * N)`` as ``(x, y, angle)`` per image.
    """
    g = np.asarray(goal_state, np.float64).reshape(*np.shape(goal_state)[:-1], -1, 3)
    c = np.asarray(cur_state, np.float64).reshape(*np.shape(cur_state)[:-1], -1, 3)
    pos = np.linalg.norm(g[..., :2] - c[..., :2], axis=-1)
    ang = np.abs(wrap_angle(g[..., 2] - c[..., 2]))
    return pos, ang


def _default_layout(n: int, row: float, turn: float) -> tuple[np.ndarray, np.ndarray]:
    xs = (np.arange(n) + 0.5) / n
    ys = np.full(n, row) + 0.12 * np.sin(np.arange(n) * 2.0)
    angles = wrap_angle(turn * (np.arange(n) + 1))
    return np.stack([xs, ys], 1).astype(np.float32), angles.astype(np.float32)


class ImagePositioningEnv(DatasetResetMixin, gym.Env):
    """Arrange procedurally generated images (see the module docstring for the rules)."""

    metadata = {"render_modes": ["rgb_array"], "render_fps": 10}

    def __init__(
        self,
        n_images: int = 3,
        render_mode: str | None = "rgb_array",
        render_size: tuple[int, int] = (224, 224),
    ):
        if int(n_images) < 1:
            raise ConfigError(f"ImagePositioningEnv requires n_images >= 1, got {n_images}")
        self.n_images = n = int(n_images)
        self.render_mode = render_mode
        self.render_size = (int(render_size[0]), int(render_size[1]))
        low = np.tile(np.array([0.0, 0.0, -np.pi], np.float32), n)
        high = np.tile(np.array([1.0, 1.0, np.pi], np.float32), n)
        box = gym.spaces.Box(low, high, dtype=np.float32)
        self.observation_space = gym.spaces.Dict({keys.PROPRIO: box, keys.STATE: box})
        self.action_space = gym.spaces.Box(-1.0, 1.0, (3 * n,), np.float32)
        self.variation_space = self._make_variation_space()
        self._state = np.zeros(3 * n, np.float32)
        self._goal = np.zeros(3 * n, np.float32)
        self._goal_img: np.ndarray | None = None

    def _make_variation_space(self) -> spaces.Dict:
        n = self.n_images
        start_pos, start_ang = _default_layout(n, 0.3, 0.0)
        target_pos, target_ang = _default_layout(n, 0.7, 2 * np.pi / 5)
        target_pos = target_pos[::-1].copy()  # targets mirror the start row

        def layout(pos: np.ndarray, ang: np.ndarray) -> spaces.Dict:
            return spaces.Dict(
                {
                    "positions": spaces.Box(0.1, 0.9, shape=(n, 2), dtype=np.float32, init_value=pos),
                    "angles": spaces.Box(-np.pi, np.pi, shape=(n,), dtype=np.float32, init_value=ang),
                }
            )

        def scalar(low: float, high: float, init: float) -> spaces.Box:
            return spaces.Box(low, high, shape=(), dtype=np.float32, init_value=np.float32(init))

        return spaces.Dict(
            {
                "background": spaces.Dict({"color": spaces.RGBBox(init_value=np.array([235, 235, 228], np.uint8))}),
                "images": spaces.Dict(
                    {
                        "seed": spaces.Discrete(10_000, init_value=0),
                        "size": scalar(0.12, 0.24, 0.18),
                    }
                ),
                "start": layout(start_pos, start_ang),
                "target": layout(target_pos, target_ang),
                "step": spaces.Dict(
                    {
                        "position": scalar(0.02, 0.08, 0.05),
                        "angle": scalar(np.pi / 32, np.pi / 8, np.pi / 16),
                    }
                ),
            }
        )

    # -- protocol hooks -------------------------------------------------------------
    def set_render_size(self, size: tuple[int, int]) -> None:
        self.render_size = (int(size[0]), int(size[1]))
        self._goal_img = None

    def eval_state(self, goal_state: np.ndarray, cur_state: np.ndarray) -> tuple[bool, float]:
        pos, ang = arrangement_errors(goal_state, cur_state)
        success = bool(np.all(pos <= POSITION_TOLERANCE) and np.all(ang <= ANGLE_TOLERANCE))
        return success, float(np.sqrt(np.sum(pos**2) + np.sum((ang / np.pi) ** 2)))

    # -- gym API ---------------------------------------------------------------------
    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None):
        super().reset(seed=seed)
        options = options or {}
        v = apply_variation_options(self.variation_space, options, self.np_random)
        self._state = self._pack(v["start"]["positions"], v["start"]["angles"])
        self._goal = self._pack(v["target"]["positions"], v["target"]["angles"])
        if keys.STATE in options:
            self._state = self._checked(options[keys.STATE], "state")
        if keys.GOAL_STATE in options:
            self._goal = self._checked(options[keys.GOAL_STATE], "goal_state")
        self._goal_img = None
        return self._obs(), self._info()

    def step(self, action):
        n = self.n_images
        action = np.clip(np.asarray(action, np.float64).reshape(n, 3), -1.0, 1.0)
        step = self.variation_space["step"].value
        cur = self._state.astype(np.float64).reshape(n, 3)
        cur[:, :2] = np.clip(cur[:, :2] + float(step["position"]) * action[:, :2], 0.0, 1.0)
        cur[:, 2] = wrap_angle(cur[:, 2] + float(step["angle"]) * action[:, 2])
        self._state = cur.reshape(-1).astype(np.float32)
        success, dist = self.eval_state(self._goal, self._state)
        return self._obs(), -dist, success, False, self._info()

    def render(self) -> np.ndarray:
        return self._draw(self._state)

    # -- internals -----------------------------------------------------------------------
    def _pack(self, positions: np.ndarray, angles: np.ndarray) -> np.ndarray:
        pos = np.asarray(positions, np.float64).reshape(self.n_images, 2)
        ang = wrap_angle(np.asarray(angles, np.float64).reshape(self.n_images, 1))
        return np.concatenate([pos, ang], axis=1).reshape(-1).astype(np.float32)

    def _checked(self, state: Any, what: str) -> np.ndarray:
        arr = np.asarray(state, np.float64)
        if arr.shape != (3 * self.n_images,):
            raise ConfigError(f"ImagePositioningEnv requires a {what} of shape {(3 * self.n_images,)}, got {arr.shape}")
        arr = arr.reshape(self.n_images, 3)
        return self._pack(np.clip(arr[:, :2], 0.0, 1.0), arr[:, 2])

    def _obs(self) -> dict[str, np.ndarray]:
        return {keys.PROPRIO: self._state.copy(), keys.STATE: self._state.copy()}

    def _info(self) -> dict[str, Any]:
        if self._goal_img is None:  # the goal image only changes on reset
            self._goal_img = self._draw(self._goal)
        return {
            keys.GOAL: self._goal_img.copy(),  # infos must not share arrays (check_env)
            keys.GOAL_STATE: self._goal.copy(),
            keys.GOAL_PROPRIO: self._goal.copy(),
        }

    def _draw(self, state: np.ndarray) -> np.ndarray:
        v = self.variation_space.value
        img = utils.new_canvas(self.render_size, v["background"]["color"])
        sprites = make_sprites(int(v["images"]["seed"]), self.n_images)
        side = float(v["images"]["size"])
        for sprite, (x, y, a) in zip(sprites, np.asarray(state, np.float64).reshape(-1, 3), strict=False):
            draw_sprite(img, sprite, np.array([x, y]), float(a), side)
        return img

"""``swm/Toy-v0``: a disk moves on the unit square towards a goal disk.

- state = proprio = agent (x, y) in [0, 1]^2 (float32); goal_state = goal (x, y).
- action in [-1, 1]^2; the agent moves by ``speed * action`` and is clipped to the square.
- success (``terminated``) when the agent is within 0.05 of the goal; reward = -distance.
- Start and goal positions are drawn from the reset seed; the factors of variation are the
  looks (colors, radius) and the speed.
- Rendering is pure numpy with anti-aliased disks, drawn directly at ``render_size``.
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np

from ... import keys, spaces
from ...policy import ExpertPolicy
from ..base import DatasetResetMixin, apply_variation_options

SUCCESS_RADIUS = 0.05


def draw_disk(img: np.ndarray, center_xy: np.ndarray, radius: float, color: np.ndarray) -> None:
    """Blend an anti-aliased disk into ``img`` (H, W, 3) uint8; center and radius in [0, 1] units."""
    h, w = img.shape[:2]
    scale = float(min(h, w))
    cx, cy = float(center_xy[0]) * w, float(center_xy[1]) * h
    r = float(radius) * scale
    x0, x1 = max(int(cx - r - 1), 0), min(int(cx + r + 2), w)
    y0, y1 = max(int(cy - r - 1), 0), min(int(cy + r + 2), h)
    if x0 >= x1 or y0 >= y1:
        return
    yy, xx = np.mgrid[y0:y1, x0:x1]
    d = np.sqrt((xx + 0.5 - cx) ** 2 + (yy + 0.5 - cy) ** 2)
    alpha = np.clip(r - d + 0.5, 0.0, 1.0)[..., None]
    patch = img[y0:y1, x0:x1].astype(np.float32)
    img[y0:y1, x0:x1] = (patch * (1 - alpha) + np.asarray(color, np.float32) * alpha + 0.5).astype(np.uint8)


class ToyEnv(DatasetResetMixin, gym.Env):
    """Point reaching on the unit square (see the module docstring)."""

    metadata = {"render_modes": ["rgb_array"], "render_fps": 10}

    def __init__(self, render_mode: str | None = "rgb_array", render_size: tuple[int, int] = (64, 64)):
        self.render_mode = render_mode
        self.render_size = tuple(render_size)
        box = gym.spaces.Box(0.0, 1.0, (2,), np.float32)
        self.observation_space = gym.spaces.Dict({keys.PROPRIO: box, keys.STATE: box})
        self.action_space = gym.spaces.Box(-1.0, 1.0, (2,), np.float32)
        self.variation_space = spaces.Dict(
            {
                "agent": spaces.Dict(
                    {
                        "color": spaces.RGBBox(init_value=np.array([220, 40, 40], np.uint8)),
                        "radius": spaces.Box(0.03, 0.08, shape=(), dtype=np.float32, init_value=np.float32(0.05)),
                        "speed": spaces.Box(0.02, 0.1, shape=(), dtype=np.float32, init_value=np.float32(0.05)),
                    }
                ),
                "goal": spaces.Dict({"color": spaces.RGBBox(init_value=np.array([40, 180, 40], np.uint8))}),
                "background": spaces.Dict({"color": spaces.RGBBox(init_value=np.array([245, 245, 245], np.uint8))}),
            }
        )
        self._pos = np.zeros(2, np.float32)
        self._goal = np.zeros(2, np.float32)
        self._goal_img: np.ndarray | None = None

    # -- protocol hooks -------------------------------------------------------------
    def set_render_size(self, size: tuple[int, int]) -> None:
        self.render_size = (int(size[0]), int(size[1]))
        self._goal_img = None

    def eval_state(self, goal_state: np.ndarray, cur_state: np.ndarray) -> tuple[bool, float]:
        dist = float(np.linalg.norm(np.asarray(goal_state, np.float64)[:2] - np.asarray(cur_state, np.float64)[:2]))
        return dist < SUCCESS_RADIUS, dist

    # -- gym API ---------------------------------------------------------------------
    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None):
        super().reset(seed=seed)
        options = options or {}
        apply_variation_options(self.variation_space, options, self.np_random)
        self._pos = self.np_random.uniform(0.1, 0.9, 2).astype(np.float32)
        self._goal = self.np_random.uniform(0.1, 0.9, 2).astype(np.float32)
        if keys.STATE in options:
            self._pos = np.asarray(options[keys.STATE], np.float32)[:2].copy()
        if keys.GOAL_STATE in options:
            self._goal = np.asarray(options[keys.GOAL_STATE], np.float32)[:2].copy()
        self._goal_img = None
        return self._obs(), self._info()

    def step(self, action):
        action = np.clip(np.asarray(action, np.float32).reshape(2), -1.0, 1.0)
        speed = float(self.variation_space["agent"]["speed"].value)
        self._pos = np.clip(self._pos + speed * action, 0.0, 1.0).astype(np.float32)
        success, dist = self.eval_state(self._goal, self._pos)
        return self._obs(), -dist, success, False, self._info()

    def render(self) -> np.ndarray:
        return self._draw(self._pos, show_goal=True)

    # -- internals -----------------------------------------------------------------------
    def _obs(self) -> dict[str, np.ndarray]:
        return {keys.PROPRIO: self._pos.copy(), keys.STATE: self._pos.copy()}

    def _info(self) -> dict[str, Any]:
        if self._goal_img is None:  # the goal image only changes on reset
            self._goal_img = self._draw(self._goal, show_goal=True)  # what the agent sees at the goal
        return {
            keys.GOAL: self._goal_img.copy(),  # check_env rejects infos that share arrays
            keys.GOAL_STATE: self._goal.copy(),
            keys.GOAL_PROPRIO: self._goal.copy(),
        }

    def _draw(self, agent_pos: np.ndarray, show_goal: bool) -> np.ndarray:
        v = self.variation_space.value
        h, w = self.render_size
        img = np.empty((h, w, 3), np.uint8)
        img[:] = v["background"]["color"]
        if show_goal:
            draw_disk(img, self._goal, SUCCESS_RADIUS, v["goal"]["color"])
        draw_disk(img, agent_pos, float(v["agent"]["radius"]), v["agent"]["color"])
        return img


class ToyExpert(ExpertPolicy):
    """Moves straight to the goal; batched over ``(B, T, 2)`` infos from :class:`World`."""

    def __init__(self, env_id: str = "swm/Toy-v0", **kwargs: Any):
        super().__init__(env_id=env_id, **kwargs)

    def get_action(self, infos: dict[str, np.ndarray], **kwargs: Any) -> np.ndarray:
        pos = np.asarray(infos[keys.STATE])[:, -1, :2]
        goal = np.asarray(infos[keys.GOAL_STATE])[:, -1, :2]
        return np.clip((goal - pos) / 0.05, -1.0, 1.0).astype(np.float32)

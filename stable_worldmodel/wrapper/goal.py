"""ResizeGoalWrapper: goal images at the world's image size, resized once per goal."""

from __future__ import annotations

from collections.abc import Callable

import gymnasium as gym
import numpy as np

from .. import keys
from ._image import check_shape, resize


class ResizeGoalWrapper(gym.Wrapper):
    """Resizes ``info["goal"]`` to ``pixels_shape`` and applies ``torchvision_transform``.

    The goal rarely changes within an episode: when the env hands back the same goal array
    object (or an equal one), the previous result is reused instead of resizing again.
    """

    def __init__(
        self, env: gym.Env, pixels_shape: tuple[int, int] = (84, 84), torchvision_transform: Callable | None = None
    ):
        super().__init__(env)
        self.pixels_shape = check_shape("ResizeGoalWrapper pixels_shape", pixels_shape)
        self.torchvision_transform = torchvision_transform
        self._src: np.ndarray | None = None
        self._out = None
        self.resize_count = 0  # how many times a goal was actually processed

    def _process(self, info: dict) -> dict:
        goal = info.get(keys.GOAL)
        if goal is None:
            return info
        if self._src is None or not (goal is self._src or np.array_equal(goal, self._src)):
            out = resize(np.asarray(goal), self.pixels_shape)
            self._out = self.torchvision_transform(out) if self.torchvision_transform is not None else out
            self._src = goal
            self.resize_count += 1
        info[keys.GOAL] = self._out
        return info

    def reset(self, *, seed=None, options=None):
        obs, info = self.env.reset(seed=seed, options=options)
        self._src = None
        return obs, self._process(dict(info))

    def step(self, action):
        obs, reward, terminated, truncated, info = self.env.step(action)
        return obs, reward, terminated, truncated, self._process(dict(info))

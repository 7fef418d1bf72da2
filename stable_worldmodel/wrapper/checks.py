"""Wrappers that validate what the env puts in ``info``."""

from __future__ import annotations

import re
from collections.abc import Iterable

import gymnasium as gym
import numpy as np

from .. import keys
from ._image import check_shape


class _InfoCheck(gym.Wrapper):
    """Runs :meth:`_check` on the info of ``reset`` (if ``on_reset``) and ``step`` (if ``on_step``)."""

    on_reset = True
    on_step = True

    def _check(self, info: dict, where: str) -> None:
        raise NotImplementedError("_check(info, where) -> None, raising RuntimeError on failure")

    def reset(self, *, seed=None, options=None):
        obs, info = self.env.reset(seed=seed, options=options)
        if self.on_reset:
            self._check(info, "reset")
        return obs, info

    def step(self, action):
        out = self.env.step(action)
        if self.on_step:
            self._check(out[-1], "step")
        return out


class EnsureInfoKeysWrapper(_InfoCheck):
    """Each regex of ``required_keys`` must match (as a whole) at least one info key, else RuntimeError."""

    def __init__(self, env: gym.Env, required_keys: Iterable[str]):
        super().__init__(env)
        self.required_keys = list(required_keys)
        self._patterns = [re.compile(p) for p in self.required_keys]

    def _check(self, info: dict, where: str) -> None:
        for pattern in self._patterns:
            if not any(pattern.fullmatch(k) for k in info):
                raise RuntimeError(
                    f"EnsureInfoKeysWrapper requires an info key matching {pattern.pattern!r} after {where}() "
                    f"(required info keys missing), got keys {sorted(info)}"
                )


class EnsureGoalInfoWrapper(_InfoCheck):
    """Requires ``info["goal"]`` after reset (``check_reset``) and/or step (``check_step``)."""

    def __init__(self, env: gym.Env, check_reset: bool, check_step: bool = False):
        super().__init__(env)
        self.on_reset = bool(check_reset)
        self.on_step = bool(check_step)

    def _check(self, info: dict, where: str) -> None:
        if keys.GOAL not in info:
            raise RuntimeError(
                f"EnsureGoalInfoWrapper requires info[{keys.GOAL!r}] after {where}() (a goal-conditioned env: the "
                f"info dict returned by {where}() must contain the key {keys.GOAL!r}), got keys {sorted(info)}; "
                "pass goal_conditioned=False to World for envs without goals"
            )


class EnsureImageShape(_InfoCheck):
    """Requires ``info[image_key]`` to be ``image_shape`` = (H, W) in its first two dims."""

    def __init__(self, env: gym.Env, image_key: str, image_shape: tuple[int, int]):
        super().__init__(env)
        self.image_key = image_key
        self.image_shape = check_shape("EnsureImageShape image_shape", image_shape)

    def _check(self, info: dict, where: str) -> None:
        img = info.get(self.image_key)
        if img is None:
            raise RuntimeError(
                f"EnsureImageShape requires info[{self.image_key!r}] after {where}(), got keys {sorted(info)}"
            )
        shape = tuple(np.shape(img)[:2])
        if shape != self.image_shape:
            raise RuntimeError(
                f"EnsureImageShape requires info[{self.image_key!r}] of shape {self.image_shape} (H, W), "
                f"got {tuple(np.shape(img))} after {where}() (Image shape {np.shape(img)} should be {self.image_shape})"
            )

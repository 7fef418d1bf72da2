"""StackedWrapper: a history axis on info entries."""

from __future__ import annotations

from collections import deque
from collections.abc import Iterable

import gymnasium as gym
import numpy as np

from ..errors import ConfigError


class StackedWrapper(gym.Wrapper):
    """Replaces ``info[key]`` by its last ``history_size`` values spaced ``frameskip`` steps apart.

    The history axis is always added, even for ``history_size=1``: ``(...)`` becomes
    ``(T, ...)`` with the newest value last. After ``reset`` the history is filled with the
    reset value. ``key`` is one info key, a list of keys, or ``None`` for every key.
    """

    def __init__(self, env: gym.Env, key: str | Iterable[str] | None, history_size: int = 1, frameskip: int = 1):
        super().__init__(env)
        for name, value in (("history_size", history_size), ("frameskip", frameskip)):
            if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 1:
                raise ConfigError(f"StackedWrapper requires {name} to be an integer >= 1, got {value!r}")
        self.keys = None if key is None else ([key] if isinstance(key, str) else list(key))
        self.history_size = int(history_size)
        self.frameskip = int(frameskip)
        self._span = (self.history_size - 1) * self.frameskip + 1
        self._buffers: dict[str, deque] = {}

    def _selected(self, info: dict) -> Iterable[str]:
        return list(info) if self.keys is None else [k for k in self.keys if k in info]

    def _stack(self, info: dict, reset: bool) -> dict:
        for k in self._selected(info):
            value = np.asarray(info[k])
            if self._span == 1:
                info[k] = value[None]
                continue
            buf = self._buffers.get(k)
            if reset or buf is None:
                buf = self._buffers[k] = deque([value] * self._span, maxlen=self._span)
            else:
                buf.append(value)
            info[k] = np.stack([buf[i] for i in range(0, self._span, self.frameskip)])
        return info

    def reset(self, *, seed=None, options=None):
        obs, info = self.env.reset(seed=seed, options=options)
        return obs, self._stack(dict(info), reset=True)

    def step(self, action):
        obs, reward, terminated, truncated, info = self.env.step(action)
        return obs, reward, terminated, truncated, self._stack(dict(info), reset=False)

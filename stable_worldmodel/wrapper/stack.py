"""StackedWrapper: a history axis on info entries."""

from __future__ import annotations

import sys
from collections import deque
from collections.abc import Iterable
from typing import Any

import gymnasium as gym
import numpy as np

from ..errors import ConfigError


def _is_tensor(value: Any) -> bool:
    """A torch tensor, without importing torch (a value cannot be one unless torch is loaded)."""
    torch = sys.modules.get("torch")
    return torch is not None and torch.is_tensor(value)


def stack_history(values: list) -> Any:
    """Stack the history of one info entry, oldest first, keeping its kind.

    ======================================  ===========================================
    torch tensors                           ``torch.stack`` (a tensor, same device)
    numpy arrays, numbers, bools, ``np.*``  ``np.stack`` (an array ``(T, ...)``)
    anything else (lists, strings, dicts)   a list of the ``T`` values
    ======================================  ===========================================
    """
    first = values[0]
    if _is_tensor(first):
        return sys.modules["torch"].stack(values)
    if isinstance(first, (np.ndarray, np.generic, int, float, bool, complex)):
        return np.stack([np.asarray(v) for v in values])
    return list(values)


class StackedWrapper(gym.Wrapper):
    """Replaces ``info[key]`` by its last ``history_size`` values spaced ``frameskip`` steps apart.

    The history axis is always added, even for ``history_size=1``: ``(...)`` becomes
    ``(T, ...)`` with the newest value last (see :func:`stack_history` for tensors, lists
    and other values). After ``reset`` the history is filled with the reset value. ``key``
    is one info key, a list of keys, or ``None`` for every key. :meth:`get_buffer_data`
    returns the current history of a key.
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
        self.buffers: dict[str, deque] = {}

    def get_buffer_data(self, key: str) -> Any:
        """The stacked history ``(T, ...)`` of ``key``, as put in ``info``; ``[]`` before any value."""
        buf = self.buffers.get(key)
        if not buf:
            return []
        if self._span == 1:
            return self._stack_one(buf[0])
        return stack_history([buf[i] for i in range(0, self._span, self.frameskip)])

    @staticmethod
    def _stack_one(value: Any) -> Any:
        """``history_size=1`` (the common case): a leading axis without copying."""
        if isinstance(value, np.ndarray):
            return value[None]
        if isinstance(value, (np.generic, int, float, bool, complex)):
            return np.asarray(value)[None]  # what np.stack gives, without its checks
        return stack_history([value])

    def _selected(self, info: dict) -> Iterable[str]:
        return list(info) if self.keys is None else [k for k in self.keys if k in info]

    def _stack(self, info: dict, reset: bool) -> dict:
        one = self._span == 1  # the common case, once per step for every key: arrays get their axis inline
        for k in self._selected(info):
            value = info[k]
            buf = self.buffers.get(k)
            if reset or buf is None:
                self.buffers[k] = deque([value] * self._span, maxlen=self._span)
            else:
                buf.append(value)
            info[k] = value[None] if one and type(value) is np.ndarray else self.get_buffer_data(k)
        return info

    def reset(self, *, seed=None, options=None):
        obs, info = self.env.reset(seed=seed, options=options)
        return obs, self._stack(dict(info), reset=True)

    def step(self, action):
        obs, reward, terminated, truncated, info = self.env.step(action)
        return obs, reward, terminated, truncated, self._stack(dict(info), reset=False)

"""EverythingToInfoWrapper: one info dict holds the whole transition."""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np

from .. import keys
from ..utils import flatten_dict


def nan_action(space: gym.Space) -> np.ndarray:
    """A NaN-filled float array shaped like one sample of ``space`` (the 'no action yet' marker)."""
    sample = np.asarray(space.sample())
    return np.full(sample.shape, np.nan, dtype=np.float32 if sample.dtype != np.float64 else np.float64)


class EverythingToInfoWrapper(gym.Wrapper):
    """Moves observation, reward, flags, action and bookkeeping into ``info``.

    Keys added on ``reset`` and ``step`` (the same set on both):

    ======================  ======================================================
    ``<obs key>``           each key of a Dict observation (else ``observation``)
    ``reward``              NaN after reset
    ``terminated``          bool
    ``truncated``           bool
    ``action``              the action that led here; NaN-filled after reset
    ``step_idx``            steps since reset (0 after reset)
    ``id``                  episode counter of this env (starts at 0)
    ``variation.<factor>``  value of each factor named in ``reset(options={"variation": [...]})``
                            (``["all"]`` = every factor), fixed for the episode
    ======================  ======================================================
    """

    def __init__(self, env: gym.Env):
        super().__init__(env)
        self._step_idx = 0
        self._episode = -1
        self._variation: dict[str, Any] = {}
        self._nan_action = nan_action(env.action_space)

    def _variation_info(self, options: dict | None) -> dict[str, Any]:
        requested = (options or {}).get(keys.VARIATION)
        space = getattr(self.env.unwrapped, "variation_space", None)
        if not requested or space is None:
            return {}
        values = flatten_dict(space.value)
        names = list(values) if "all" in requested else [
            n for n in values if any(n == r or n.startswith(r + ".") for r in requested)
        ]
        return {f"{keys.VARIATION}.{n}": np.asarray(values[n]).copy() for n in names}

    def _fill(self, info: dict[str, Any], obs: Any, reward: float, terminated: bool, truncated: bool, action: Any):
        if isinstance(obs, dict):
            info.update(obs)
        else:
            info["observation"] = obs
        info[keys.REWARD] = reward
        info[keys.TERMINATED] = bool(terminated)
        info[keys.TRUNCATED] = bool(truncated)
        info[keys.ACTION] = action
        info[keys.STEP_IDX] = self._step_idx
        info[keys.EPISODE_ID] = self._episode
        info.update(self._variation)
        return info

    def reset(self, *, seed: int | None = None, options: dict | None = None):
        obs, info = self.env.reset(seed=seed, options=options)
        self._step_idx = 0
        self._episode += 1
        self._variation = self._variation_info(options)
        return obs, self._fill(dict(info), obs, np.nan, False, False, self._nan_action)

    def step(self, action):
        obs, reward, terminated, truncated, info = self.env.step(action)
        self._step_idx += 1
        act = np.asarray(action, dtype=self._nan_action.dtype).reshape(self._nan_action.shape)
        return obs, reward, terminated, truncated, self._fill(dict(info), obs, reward, terminated, truncated, act)

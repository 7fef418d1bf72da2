"""EverythingToInfoWrapper: one info dict holds the whole transition."""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np

from .. import keys
from ..errors import ConfigError, SpaceError
from ..utils import flatten_dict


class InfoKeyCollisionError(ConfigError, AssertionError):
    """The env's own info (or observation) already holds a key that EverythingToInfoWrapper adds.

    A ``ValueError``, and an ``AssertionError`` like the original release's check.
    """


class UnsupportedActionSpaceError(SpaceError, NotImplementedError):
    """An action space the wrapper cannot record (a ``Dict``); a ``ValueError`` and a ``NotImplementedError``."""


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
                            (``["all"]`` = every factor), fixed for the episode; a later reset
                            without the option reports the same factors (as release 0.0.3)
    ======================  ======================================================

    Keys are never overwritten: an env whose info (or Dict observation) already holds one of
    them raises :class:`InfoKeyCollisionError`, naming the key. ``Dict`` action spaces are
    refused when the wrapper is built (:class:`UnsupportedActionSpaceError`).
    """

    def __init__(self, env: gym.Env):
        if isinstance(env.action_space, gym.spaces.Dict):
            raise UnsupportedActionSpaceError(
                f"EverythingToInfoWrapper requires an action space that is not a Dict (it stores the action as one "
                f"array), got {env.action_space!r}; flatten it first, e.g. with gymnasium.wrappers.FlattenAction"
            )
        super().__init__(env)
        self._step_idx = 0
        self._episode = -1
        self._variation: dict[str, Any] = {}
        self._requested: Any = None
        self._nan_action = nan_action(env.action_space)

    def _variation_info(self, options: dict | None) -> dict[str, Any]:
        if options and keys.VARIATION in options:
            self._requested = options[keys.VARIATION]
        requested = self._requested  # a reset without the option reports the factors named last (0.0.3)
        space = getattr(self.env.unwrapped, "variation_space", None)
        if not requested or space is None:
            return {}
        values = flatten_dict(space.value)
        names = (
            list(values)
            if "all" in requested
            else [n for n in values if any(n == r or n.startswith(r + ".") for r in requested)]
        )
        return {f"{keys.VARIATION}.{n}": np.asarray(values[n]).copy() for n in names}

    def _fill(self, info: dict[str, Any], obs: Any, reward: float, terminated: bool, truncated: bool, action: Any):
        observed = dict(obs) if isinstance(obs, dict) else {"observation": obs}
        book = {
            keys.REWARD: reward,
            keys.TERMINATED: bool(terminated),
            keys.TRUNCATED: bool(truncated),
            keys.ACTION: action,
            keys.STEP_IDX: self._step_idx,
            keys.EPISODE_ID: self._episode,
            **self._variation,
        }
        clash = sorted((info.keys() & (observed.keys() | book.keys())) | (observed.keys() & book.keys()))
        if clash:
            raise InfoKeyCollisionError(
                f"EverythingToInfoWrapper requires env infos and observation keys other than the ones it adds, got "
                f"{clash} already in the info or observation of {type(self.env.unwrapped).__name__}; rename them in "
                "the env (or in a wrapper below this one)"
            )
        info.update(observed)
        info.update(book)
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

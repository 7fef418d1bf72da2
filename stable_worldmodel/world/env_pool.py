"""``EnvPool``: a pool of envs stepped together in this process, some of them selectively
(upstream 0.1.1's ``stable_worldmodel.world.env_pool.EnvPool``, public there).

Infos are stacked as ``(num_envs, 1, ...)`` (env, then a time axis of 1, the World's layout),
allocated on the first full reset and updated in place afterwards: the dict that ``reset`` and
``step`` return is the same object every time. Tensors stay tensors, arrays and numbers become
numpy arrays, anything else a per-env list ``[[value], ...]``.

The World itself runs its envs through :class:`~stable_worldmodel.world.vector.VecEnv` (worker
processes, shared memory); this pool is the simple in-process one research code builds on.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium.vector.utils import batch_space

from ..errors import ConfigError

__all__ = ["EnvPool"]


def _per_env(value: Any, n: int, what: str, increment: bool = False) -> list:
    """``value`` for each of ``n`` envs: None for all, a list / array given per env, an int seed
    ``s`` as ``s, s + 1, ...`` (``increment``), anything else shared."""
    if value is None:
        return [None] * n
    if isinstance(value, (list, tuple, np.ndarray)):
        values = list(value)
        if len(values) != n:
            raise ConfigError(f"EnvPool requires one {what} per env ({n}), got {len(values)}")
        return values
    if increment and isinstance(value, (int, np.integer)) and not isinstance(value, bool):
        return [int(value) + i for i in range(n)]
    return [value] * n


def _torch_tensor(value: Any) -> bool:
    return type(value).__module__.startswith("torch") and hasattr(value, "unsqueeze")


class EnvPool:
    """Envs made by ``env_fns`` (zero-argument factories, each called once), reset and stepped
    as a batch; ``mask`` restricts a ``reset`` or ``step`` to some envs.

    ``autoreset=True`` resets an env right after the step that ends its episode (the infos then
    hold the new episode's first info; ``terminated`` / ``truncated`` still report the end).
    """

    def __init__(self, env_fns: Sequence[Callable[[], gym.Env]], *, autoreset: bool = False):
        fns = list(env_fns)
        if not fns or not all(callable(f) for f in fns):
            raise ConfigError(f"EnvPool requires a non-empty list of env factories (callables), got {env_fns!r}")
        self.envs = [fn() for fn in fns]
        self.autoreset = bool(autoreset)
        self.seeds = np.zeros(len(self.envs), dtype=np.int64)
        first = self.envs[0]
        # built once: a fresh batch space per access would be a fresh (unseeded) RNG each time
        self._action_space = batch_space(first.action_space, len(self.envs))
        self._observation_space = batch_space(first.observation_space, len(self.envs))
        self._infos: dict[str, Any] | None = None
        self._options: list = [None] * len(self.envs)

    # -- spaces -------------------------------------------------------------------------------
    @property
    def num_envs(self) -> int:
        return len(self.envs)

    @property
    def action_space(self) -> gym.Space:
        """The batched action space."""
        return self._action_space

    @property
    def single_action_space(self) -> gym.Space:
        return self.envs[0].action_space

    @property
    def observation_space(self) -> gym.Space:
        """The batched observation space."""
        return self._observation_space

    @property
    def single_observation_space(self) -> gym.Space:
        return self.envs[0].observation_space

    @property
    def variation_space(self) -> Any:
        """The first env's ``variation_space`` (on the unwrapped env), or None."""
        return getattr(self.envs[0].unwrapped, "variation_space", None)

    @property
    def single_variation_space(self) -> Any:
        return self.variation_space

    # -- running ------------------------------------------------------------------------------
    def _mask(self, mask: Any) -> np.ndarray:
        if mask is None:
            return np.ones(self.num_envs, dtype=bool)
        arr = np.asarray(mask, dtype=bool).reshape(-1)
        if arr.shape != (self.num_envs,):
            raise ConfigError(f"EnvPool requires a mask of {self.num_envs} booleans, got shape {np.shape(mask)}")
        return arr

    def reset(self, seed: Any = None, options: Any = None, mask: Any = None) -> tuple[None, dict[str, Any]]:
        """Reset the envs (those of ``mask``) and return ``(None, infos)``.

        ``seed``: None, an int (env ``i`` gets ``seed + i``) or one per env; ``options``: a dict
        shared by all or one per env. The first reset must reset every env.
        """
        chosen = self._mask(mask)
        seeds = _per_env(seed, self.num_envs, "seed", increment=True)
        opts = _per_env(options, self.num_envs, "options dict")
        if self._infos is None and not chosen.all():
            raise ConfigError("EnvPool requires its first reset to reset every env (no mask), to lay out the infos")
        infos: list = [None] * self.num_envs
        for i in np.flatnonzero(chosen):
            _, infos[i] = self.envs[i].reset(seed=seeds[i], options=opts[i])
            self._options[i] = opts[i]
            if seeds[i] is not None:
                self.seeds[i] = seeds[i]
        if self._infos is None or mask is None:
            self._infos = self._stack(infos)
        else:
            for i in np.flatnonzero(chosen):
                self._write(i, infos[i])
        return None, self._infos

    def step(self, actions: Any, mask: Any = None) -> tuple[None, np.ndarray, np.ndarray, np.ndarray, dict]:
        """Step the envs (those of ``mask``) with ``actions[i]``; returns ``(None, rewards,
        terminated, truncated, infos)``. Envs left out get reward 0, not done, and their infos untouched."""
        if self._infos is None:
            raise ConfigError("EnvPool requires reset() before step()")
        chosen = self._mask(mask)
        if len(actions) != self.num_envs:
            raise ConfigError(f"EnvPool requires one action per env ({self.num_envs}), got {len(actions)}")
        rewards = np.zeros(self.num_envs, dtype=np.float32)
        terminated = np.zeros(self.num_envs, dtype=bool)
        truncated = np.zeros(self.num_envs, dtype=bool)
        for i in np.flatnonzero(chosen):
            _, rewards[i], terminated[i], truncated[i], info = self.envs[i].step(actions[i])
            if self.autoreset and (terminated[i] or truncated[i]):
                _, info = self.envs[i].reset(options=self._options[i])
            self._write(i, info)
        return None, rewards, terminated, truncated, self._infos

    def close(self) -> None:
        for env in self.envs:
            env.close()

    def __enter__(self) -> EnvPool:
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()

    # -- infos --------------------------------------------------------------------------------
    @staticmethod
    def _stack(infos: list[dict]) -> dict[str, Any]:
        stacked: dict[str, Any] = {}
        for key in infos[0]:
            values = [info[key] for info in infos]
            first = values[0]
            if _torch_tensor(first):
                import torch

                stacked[key] = torch.stack(values).unsqueeze(1)
            elif isinstance(first, np.ndarray):
                stacked[key] = np.stack(values)[:, None]
            elif isinstance(first, (bool, int, float, np.number)):
                stacked[key] = np.asarray(values)[:, None]
            else:
                stacked[key] = [[v] for v in values]
        return stacked

    def _write(self, i: int, info: dict) -> None:
        for key, value in info.items():
            buf = self._infos.get(key)
            if buf is None:
                continue  # a key the first reset did not have: the layout is fixed
            if isinstance(buf, list):
                buf[i][0] = value
            elif _torch_tensor(buf):
                import torch

                buf[i, 0] = torch.as_tensor(value, dtype=buf.dtype, device=buf.device)
            else:
                buf[i, 0] = value

"""Checks of what users hand to ``World``: seeds, env keyword arguments, reset options.

They run in the calling process, before any env (or worker process) sees the value, and raise
:class:`~stable_worldmodel.errors.ConfigError` / :class:`~stable_worldmodel.errors.UnknownNameError`
naming the bad value and what is accepted.
"""

from __future__ import annotations

import inspect
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from .. import keys
from ..errors import ConfigError, unknown_name

SEED_LIMIT = 2**32  # numpy and Gymnasium take seeds in [0, 2**32) (and larger ints, which we do not need)
RESET_OPTIONS = (keys.VARIATION, keys.VARIATION_VALUES, keys.STATE, keys.GOAL_STATE)


def check_seed(owner: str, seed: Any) -> int | None:
    """``seed`` as an int in ``[0, 2**32)``, or None; anything else is a ConfigError."""
    if seed is None:
        return None
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)):
        raise ConfigError(
            f"{owner} requires seed to be an int in [0, 2**32) or None, got {seed!r} ({type(seed).__name__})"
        )
    if not 0 <= int(seed) < SEED_LIMIT:
        raise ConfigError(f"{owner} requires seed to be an int in [0, 2**32) or None, got {seed!r}")
    return int(seed)


def check_seeds(owner: str, seed: Any, n: int) -> list[int] | int | None:
    """A reset seed: None, an int, or one int per env (``n``)."""
    if seed is None or isinstance(seed, (int, np.integer, bool, str, float)):
        return check_seed(owner, seed)
    if not isinstance(seed, (Sequence, np.ndarray)):
        raise ConfigError(f"{owner} requires seed to be an int, one int per env ({n}) or None, got {seed!r}")
    seeds = [check_seed(owner, s) for s in seed]
    if len(seeds) != n or None in seeds:
        raise ConfigError(f"{owner} requires one seed per env ({n}), got {len(seeds)} seeds: {list(seed)}")
    return seeds


def env_class(env_name: str) -> type | None:
    """The class behind a registered Gymnasium id (its module is imported), or None for a factory function."""
    import gymnasium as gym

    entry = gym.spec(env_name).entry_point
    if isinstance(entry, str):
        from gymnasium.envs.registration import load_env_creator

        entry = load_env_creator(entry)
    return entry if inspect.isclass(entry) else None


def check_env_kwargs(env_name: str, kwargs: Mapping[str, Any]) -> None:
    """Every key of ``kwargs`` is a parameter of the env's constructor (or the constructor takes ``**kwargs``)."""
    import gymnasium as gym

    cls = env_class(env_name)
    if cls is None or not kwargs:
        return
    try:
        params = inspect.signature(cls.__init__).parameters
    except (TypeError, ValueError):  # pragma: no cover - builtins without signatures
        return
    if any(p.kind is inspect.Parameter.VAR_KEYWORD for p in params.values()):
        return
    accepted = [name for name, p in params.items() if name != "self" and p.kind is not inspect.Parameter.VAR_POSITIONAL]
    accepted += list(gym.spec(env_name).kwargs)  # the registration's own defaults
    for name in kwargs:
        if name not in accepted and name != "render_mode":
            raise unknown_name(f"keyword argument of {env_name} ({cls.__name__})", name, accepted)


def _state_space(observation_space: Any) -> Any:
    import gymnasium as gym

    if isinstance(observation_space, gym.spaces.Dict) and keys.STATE in observation_space.spaces:
        return observation_space[keys.STATE]
    return None


def check_reset_options(options: Any, n: int, observation_space: Any = None) -> list[dict | None]:
    """``options`` (None, one dict, or one dict/None per env) as one entry per env, each checked.

    Keys are those every built-in env reads (:data:`RESET_OPTIONS`); ``variation`` is a list of
    factor names, ``variation_values`` a mapping, ``state`` / ``goal_state`` finite numbers that
    lie in the observation space's ``state`` box when it has one.
    """
    if options is None or isinstance(options, Mapping):
        per_env = [options] * n
    elif isinstance(options, Sequence) and not isinstance(options, (str, bytes)):
        per_env = list(options)
        if len(per_env) != n:
            raise ConfigError(
                f"World.reset requires one options dict per env ({n}) when given a list, got {len(per_env)}"
            )
    else:
        raise ConfigError(
            f"World.reset requires options to be a dict (or one dict per env), got {options!r}; "
            f'for example {{"variation": ["all"]}}'
        )
    space = _state_space(observation_space)
    for opts in per_env:
        if opts is None:
            continue
        if not isinstance(opts, Mapping):
            raise ConfigError(f"World.reset requires each env's options to be a dict or None, got {opts!r}")
        _check_options(opts, space)
    return [None if o is None else dict(o) for o in per_env]


def _check_options(opts: Mapping[str, Any], state_space: Any) -> None:
    for key in opts:
        if key not in RESET_OPTIONS:
            raise unknown_name("reset option", key, RESET_OPTIONS)
    variation = opts.get(keys.VARIATION)
    if variation is not None:
        if isinstance(variation, str):
            raise ConfigError(
                f"reset option 'variation' requires a list of factor names, got the string {variation!r}; "
                f"write [{variation!r}]"
            )
        if not isinstance(variation, (Sequence, np.ndarray, set, frozenset)) or not all(
            isinstance(v, str) for v in variation
        ):
            raise ConfigError(
                f"reset option 'variation' requires a list of factor names (or ['all']), got {variation!r}"
            )
    values = opts.get(keys.VARIATION_VALUES)
    if values is not None and not isinstance(values, Mapping):
        raise ConfigError(
            f"reset option 'variation_values' requires a dict of factor name -> value, got {values!r}; "
            f'for example {{"agent.color": [255, 0, 0]}}'
        )
    for key in (keys.STATE, keys.GOAL_STATE):
        if key in opts and opts[key] is not None:
            _check_state(key, opts[key], state_space)


def _check_state(key: str, value: Any, space: Any) -> None:
    try:
        arr = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise ConfigError(f"reset option {key!r} requires an array of numbers, got {value!r}") from None
    if not np.isfinite(arr).all():
        raise ConfigError(f"reset option {key!r} requires finite numbers, got {value!r}")
    if space is None:
        return
    if arr.shape != space.shape:
        raise ConfigError(f"reset option {key!r} requires shape {space.shape} (the state space), got {arr.shape}")
    low, high = np.asarray(space.low, np.float64), np.asarray(space.high, np.float64)
    tol = 1e-6 * np.maximum(1.0, np.abs(high - low))
    outside = np.flatnonzero((arr < low - tol) | (arr > high + tol))
    if len(outside):
        i = int(outside[0])
        raise ConfigError(
            f"reset option {key!r} requires values inside the state space, got {key}[{i}] = {arr[i]:g} "
            f"outside [{low[i]:g}, {high[i]:g}]"
        )

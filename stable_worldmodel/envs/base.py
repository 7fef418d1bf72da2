"""Protocols every ``swm`` environment may implement, and the helpers they share.

World and the wrappers check these with ``isinstance`` (they are
``runtime_checkable``), never with ``hasattr`` on private names.

Reset options understood by every built-in env::

    {"variation": ["agent.color", ...] | ["all"],      # factors to resample
     "variation_values": {"agent.color": [255, 0, 0]},  # factors to set (dotted or nested)
     "state": np.ndarray,                               # start from this full state
     "goal_state": np.ndarray}                          # use this goal state
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any, Protocol, runtime_checkable

import numpy as np

from .. import keys
from ..errors import ConfigError, unknown_name


@runtime_checkable
class SupportsRenderSize(Protocol):
    """An env that can draw directly at a requested size (no resize afterwards)."""

    def set_render_size(self, size: tuple[int, int]) -> None:
        """Make ``render()`` return frames of ``size`` = (H, W)."""


def check_render_size(owner: str, size: Any) -> tuple[int, int]:
    """``size`` as an ``(H, W)`` pair of positive ints for ``set_render_size``;
    ConfigError naming ``owner`` otherwise."""
    try:
        h, w = (int(s) for s in size)
    except (TypeError, ValueError) as exc:
        raise ConfigError(f"{owner} requires render_size (H, W) of positive ints, got {size!r}") from exc
    if h < 1 or w < 1:
        raise ConfigError(f"{owner} requires render_size (H, W) of positive ints, got {size!r}")
    return h, w


@runtime_checkable
class SupportsDatasetReset(Protocol):
    """An env that can start from a state (and goal) recorded in a dataset."""

    def reset_options_from_dataset(
        self, start_row: Mapping[str, np.ndarray], goal_row: Mapping[str, np.ndarray]
    ) -> dict[str, Any]:
        """Reset options that start at ``start_row``'s state with ``goal_row``'s state as goal."""


@runtime_checkable
class SupportsEvalState(Protocol):
    """An env that can judge a state against a goal state."""

    def eval_state(self, goal_state: np.ndarray, cur_state: np.ndarray) -> tuple[bool, float]:
        """Return ``(success, distance)``."""


class DatasetResetMixin:
    """Default :class:`SupportsDatasetReset`: restore ``state``, ``goal_state`` and recorded variations."""

    def reset_options_from_dataset(
        self, start_row: Mapping[str, np.ndarray], goal_row: Mapping[str, np.ndarray]
    ) -> dict[str, Any]:
        if keys.STATE not in start_row:
            raise ConfigError(
                f"{type(self).__name__} requires a {keys.STATE!r} column to start from a dataset row, "
                f"got columns {sorted(start_row)}"
            )
        options: dict[str, Any] = {
            keys.STATE: np.asarray(start_row[keys.STATE]),
            keys.GOAL_STATE: np.asarray(goal_row[keys.STATE]),
        }
        prefix = keys.VARIATION + "."
        values = {k[len(prefix) :]: np.asarray(v) for k, v in start_row.items() if k.startswith(prefix)}
        if values:
            options[keys.VARIATION_VALUES] = values
        return options


def point_option(owner: str, options: Mapping[str, Any], key: str) -> np.ndarray | None:
    """The first two numbers of reset option ``key`` as float32 ``(2,)`` (None when absent);
    ConfigError naming ``owner`` when it has fewer than two."""
    if options.get(key) is None:
        return None
    value = np.asarray(options[key], np.float32).reshape(-1)
    if value.shape[0] < 2:
        raise ConfigError(f"{owner} requires reset option {key!r} with at least 2 numbers, got {options[key]!r}")
    return value[:2].copy()


def reset_point_task(
    env: Any, owner: str, seed: int | None, options: Mapping[str, Any], defaults: Any
) -> tuple[np.ndarray, np.ndarray]:
    """The reset of a point-agent task (TwoRoom-v1, Piecewise): resample ``env.variation_space`` (from
    ``seed``, or, where upstream reseeds from fresh entropy, a seed drawn from ``env.np_random``) with
    ``options`` and ``defaults`` (the factors resampled when the options name none), then return the agent's
    and the target's positions, float32 ``(2,)``: reset options ``state`` and ``target_state`` /
    ``goal_state`` where given, else the ``agent`` / ``target`` position factors."""
    from .. import spaces

    if seed is None:
        seed = int(env.np_random.integers(0, 2**31 - 1))
    spaces.reset_variation_space(env.variation_space, seed, options, defaults)
    v = env.variation_space
    agent = point_option(owner, options, keys.STATE)
    target = point_option(owner, options, "target_state")
    if target is None:
        target = point_option(owner, options, keys.GOAL_STATE)
    agent = v["agent"]["position"].value.astype(np.float32) if agent is None else agent
    target = v["target"]["position"].value.astype(np.float32) if target is None else target
    return agent, target


def check_variation_option(options: Mapping[str, Any] | None, names: list[str] | None = None) -> list[str] | None:
    """The factor names of reset option ``"variation"`` as a list (None when absent or empty).

    A bare string is refused (``["agent.color"]`` was meant); with ``names`` (the space's
    factor names), unknown names get a "did you mean" error.
    """
    requested = (options or {}).get(keys.VARIATION)
    if not requested:
        return None
    if isinstance(requested, str):
        raise ConfigError(
            f"reset option 'variation' requires a list of factor names, got the string {requested!r}; "
            f"write [{requested!r}]"
        )
    requested = list(requested)
    for name in requested if names is not None else ():
        if name != "all" and name not in names and not any(n.startswith(name + ".") for n in names):
            raise unknown_name("variation factor", name, ["all", *names])
    return requested


def rgb_factor(color) -> Any:
    """An RGB colour factor (``spaces.RGBBox``) whose default is ``color``."""
    from .. import spaces

    return spaces.RGBBox(init_value=np.array(color, np.uint8))


def scalar_factor(low: float, high: float, init: float) -> Any:
    """A one-number float32 factor in ``[low, high]`` (a ``(1,)`` ``spaces.Box``) whose default is ``init``."""
    from .. import spaces

    return spaces.Box(
        np.array([low], np.float32),
        np.array([high], np.float32),
        shape=(1,),
        dtype=np.float32,
        init_value=np.array([init], np.float32),
    )


def checked_reset_options(owner: str, options: Any, names: list[str]) -> dict[str, Any]:
    """A copy of reset ``options`` (``{}`` for None) once checked: a dict, its ``"variation"`` names and
    its ``"variation_values"`` keys factors among ``names`` (``owner`` and "did you mean" in the errors)."""
    if options is None:
        return {}
    if not isinstance(options, Mapping):
        raise ConfigError(f"{owner}.reset requires options as a dict, got {options!r}")
    check_variation_option(options, names)
    values = options.get(keys.VARIATION_VALUES)
    if values is not None:
        if not isinstance(values, Mapping):
            raise ConfigError(f"{owner}.reset requires options[{keys.VARIATION_VALUES!r}] as a dict, got {values!r}")
        for name in flatten_values(values):
            if name not in names:
                raise unknown_name("variation factor", name, names)
    return dict(options)


def apply_variation_options(variation_space, options: Mapping[str, Any] | None, np_random: np.random.Generator):
    """Reset ``variation_space`` to its defaults, then resample / set what ``options`` names.

    The space is seeded from ``np_random`` so the same env seed gives the same factors.
    Returns the (nested) value dict.
    """
    variation_space.reset()
    if not options:
        return variation_space.value
    names = variation_space.names()
    requested = check_variation_option(options, names)
    if requested:
        variation_space.seed(int(np_random.integers(0, 2**31 - 1)))
        variation_space.update(set(requested))
    values = options.get(keys.VARIATION_VALUES)
    if values:
        flat = flatten_values(values)
        for name in flat:
            if name not in names:
                raise unknown_name("variation factor", name, names)
        variation_space.set_value(flat)
    return variation_space.value


def flatten_values(d: Mapping[str, Any], prefix: str = "") -> dict[str, Any]:
    """Flatten nested reset-option values to dotted names (``{"a": {"b": 1}}`` -> ``{"a.b": 1}``)."""
    out: dict[str, Any] = {}
    for k, v in d.items():
        path = f"{prefix}{k}"
        if isinstance(v, Mapping):
            out.update(flatten_values(v, path + "."))
        else:
            out[path] = v
    return out

"""``reset_variation_space``: the variation part of an env's ``reset(seed, options)``."""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from typing import Any

from .. import keys
from ..errors import SpaceError
from ._dict import Dict
from ._report import SpaceCheckError

__all__ = ["reset_variation_space"]


def reset_variation_space(
    variation_space: Dict,
    seed: int | None = None,
    options: Mapping[str, Any] | None = None,
    default_variations: Iterable[str] | None = None,
) -> None:
    """Seed and reset ``variation_space``, then resample and set what the reset ``options`` name.

    Steps: ``seed(seed)`` (None draws fresh entropy, as in Gymnasium), ``reset()`` to the init
    values, ``update(options["variation"])`` (or ``default_variations`` when the option is absent
    or None; an explicit empty list resamples nothing), ``set_value(options["variation_values"])``
    (nested or dotted), and a final :meth:`Dict.check`. Other option keys are ignored.

    ``"variation"`` takes dotted names, ``"all"``, or one name as a string. Raises SpaceError for
    a non-Dict space, a non-mapping ``options`` or unknown names, and :class:`SpaceCheckError`
    (also an ``AssertionError``) when the resulting values fail ``check()``. Example::

        reset_variation_space(env.variation_space, seed=0, options={"variation": ["agent.color"]})
    """
    if not isinstance(variation_space, Dict):
        raise SpaceError(
            f"reset_variation_space requires a stable_worldmodel.spaces.Dict, got {type(variation_space).__name__}"
        )
    if options is None:
        options = {}
    if not isinstance(options, Mapping):
        raise SpaceError(f"reset_variation_space requires options as a dict, got {options!r}")
    names = options.get(keys.VARIATION)
    if names is None:
        names = () if default_variations is None else default_variations
    if not isinstance(names, (str, Iterable)) or isinstance(names, Mapping):
        raise SpaceError(
            f"reset_variation_space requires options[{keys.VARIATION!r}] as a list of variation names, got {names!r}"
        )
    variation_space.seed(seed)
    variation_space.reset()
    variation_space._update(names, require_valid=False)  # the values set next may complete the space
    if keys.VARIATION_VALUES in options:
        variation_space.set_value(options[keys.VARIATION_VALUES])
    if not variation_space.check(debug=True):
        raise SpaceCheckError(
            f"reset_variation_space requires variation values inside the variation space, got "
            f"{list(variation_space._failures())}; give every factor an init_value, or name it in "
            f"options[{keys.VARIATION!r}] or options[{keys.VARIATION_VALUES!r}]"
        )

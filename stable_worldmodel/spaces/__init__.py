"""Gymnasium spaces that carry a current value: the factors of variation of an env.

Every space here extends its Gymnasium class with

- ``init_value`` / ``value``: the default and the current element. A space built without
  ``init_value`` has both None, ``check()`` is False until a value is sampled or set, and
  ``reset()`` brings None back. Reading ``value`` returns a copy of array values (change it
  with ``set_value``).
- ``constrain_fn``: an optional predicate beyond the bounds. ``sample()`` rejection-samples
  until it holds (``RuntimeError`` after ``max_tries``; one warning per call once sampling takes
  longer than ``warn_after_s``), ``contains(x)`` requires it, ``check()`` reports a current value
  that breaks it. It must return a ``bool`` (or a numpy bool scalar): an array or any other
  result raises :class:`~stable_worldmodel.errors.SpaceError` when the function is called.
- ``set_value(v)`` / ``set_init_value(v)``: validated setters. A value of another numeric dtype
  is cast (exactly, for integer spaces); a wrong shape, a lossy cast or a value outside the
  bounds raises :class:`~stable_worldmodel.errors.SpaceError` naming the value and the space.
  Setters do not evaluate ``constrain_fn`` (it may read state that is not built yet);
  ``check()`` does. The constructor's ``init_value`` is the exception, as in release 0.0.3: a
  value outside the bounds is kept, and ``check()`` reports it.
- ``check()`` returns False and logs one warning saying why (unset, out of bounds, or
  "does not satisfy constrain_fn").
- ``reset()`` restores ``init_value``; ``seed(s)`` makes sampling deterministic.
- Bad constructor arguments raise :class:`~stable_worldmodel.errors.SpaceError` before Gymnasium
  sees them: ``Box`` bounds with NaN or ``low > high``, ``Discrete(n)`` with ``n < 1``,
  ``MultiDiscrete`` with an ``nvec`` entry below 1.

:class:`Dict` composes them: ordered sampling (``sampling_order``, readable and settable),
dotted names (``"agent.color"``), partial ``update``/``set_value``, and a ``constrain_fn`` over
the whole value dict. :func:`reset_variation_space` applies an env's reset ``options`` to one.

Warnings go through ``stable_worldmodel.spaces.logging`` (a stdlib ``logging.Logger`` named
``"stable_worldmodel.spaces"``, read at call time), so they can be captured with
``caplog`` or by patching ``stable_worldmodel.spaces.logging.warning``.

Example::

    from stable_worldmodel import spaces
    space = spaces.Dict({"color": spaces.RGBBox(), "size": spaces.Box(0.1, 1.0, shape=(), init_value=0.5)})
    space.value                      # {"color": None, "size": array(0.5, float32)}
    space.check()                    # False: "color" has no value yet
    space.sample()                   # draws both
    space.update({"color"})          # resample only the color
"""

from __future__ import annotations

from ._dict import Dict
from ._leaf import Box, Discrete, MultiDiscrete, RGBBox, StatefulSpaceMixin, rejection_sample
from ._report import LOGGER as logging  # release 0.0.3 exposed its logger under this name
from ._report import SpaceCheckError
from ._reset import reset_variation_space

__all__ = [
    "Box",
    "Dict",
    "Discrete",
    "MultiDiscrete",
    "RGBBox",
    "SpaceCheckError",
    "StatefulSpaceMixin",
    "logging",
    "rejection_sample",
    "reset_variation_space",
]

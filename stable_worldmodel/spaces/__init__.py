"""Gymnasium spaces that carry a current value: the factors of variation of an env.

Every space here extends its Gymnasium class with

- ``init_value`` / ``value``: the default and the current element. ``value`` is always
  defined; reading it returns a copy of array values (change it with ``set_value``).
- ``constrain_fn``: an optional predicate beyond the bounds. ``sample()`` rejection-samples
  until it holds (``RuntimeError`` after ``max_tries``; one warning per call once sampling takes
  longer than ``warn_after_s``), ``contains(x)`` requires it, ``check()`` reports a current value
  that breaks it. It must return a ``bool`` (or a numpy bool scalar): an array or any other
  result raises :class:`~stable_worldmodel.errors.SpaceError` when the function is called.
- ``set_value(v)`` / ``set_init_value(v)``: validated setters. A value of another numeric dtype
  is cast (exactly, for integer spaces); a wrong shape, a lossy cast or a value outside the
  bounds raises :class:`~stable_worldmodel.errors.SpaceError` naming the value and the space.
  Setters do not evaluate ``constrain_fn`` (it may read state that is not built yet);
  ``check()`` does.
- ``reset()`` restores ``init_value``; ``seed(s)`` makes sampling deterministic.
- Bad constructor arguments raise :class:`~stable_worldmodel.errors.SpaceError` before Gymnasium
  sees them: ``Box`` bounds with NaN or ``low > high``, ``Discrete(n)`` with ``n < 1``,
  ``MultiDiscrete`` with an ``nvec`` entry below 1.

Defaults for ``init_value=None``: ``Box`` takes the midpoint of its bounds (floored for integer
dtypes; the finite bound, or 0, on an unbounded side), so ``RGBBox`` is mid-grey 127;
``Discrete`` and ``MultiDiscrete`` take their ``start``. A default is not checked against
``constrain_fn``: pass an explicit ``init_value`` when the constraint matters at reset.

:class:`Dict` composes them: ordered sampling, dotted names (``"agent.color"``), partial
``update``/``set_value``, and a ``constrain_fn`` over the whole value dict.

Example::

    from stable_worldmodel import spaces
    space = spaces.Dict({"color": spaces.RGBBox(), "size": spaces.Box(0.1, 1.0, shape=())})
    space.update({"color"})          # resample only the color
    space.value                      # {"color": array([..], uint8), "size": array(0.55, float32)}
"""

from __future__ import annotations

from ._dict import Dict
from ._leaf import Box, Discrete, MultiDiscrete, RGBBox, StatefulSpaceMixin, rejection_sample

__all__ = ["Box", "Dict", "Discrete", "MultiDiscrete", "RGBBox", "StatefulSpaceMixin", "rejection_sample"]

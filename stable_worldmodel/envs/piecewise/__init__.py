"""Upstream's Piecewise (``swm/Piecewise-v0``): a dot in an open room whose zones add a drift
(:mod:`.piecewise_env`, upstream's module name) and its expert (:mod:`.expert`).

Names resolve lazily: importing this package imports no env code.
"""

from __future__ import annotations

from ..._lazy import lazy_getattr

__all__ = ["PiecewiseEnv", "PiecewiseExpert"]

__getattr__ = lazy_getattr(
    __name__,
    {
        "PiecewiseEnv": ".piecewise_env",
        "PiecewiseExpert": ".expert",
    },
)

"""PyFlyt rocket landing (``swm/PFRocketLanding-v0``, extra ``pyflyt``): the env (:mod:`.pyflyt_rocketlanding`,
upstream's module name) and its scripted expert (:mod:`.expert`).

Names resolve lazily: importing this package imports neither PyFlyt nor pybullet; using
``RocketLandingEnv`` without them installed raises
:class:`~stable_worldmodel.errors.DependencyNotInstalled` naming the extra.
"""

from __future__ import annotations

from ..._lazy import lazy_getattr

__all__ = ["RocketLandingEnv", "RocketLandingExpert"]

__getattr__ = lazy_getattr(
    __name__,
    {"RocketLandingEnv": ".pyflyt_rocketlanding", "RocketLandingExpert": ".expert"},
)

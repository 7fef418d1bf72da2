"""Craftax and Craftax-Classic (``swm/Craftax*-v1``, extra ``craftax``): craftax's JAX games as
Gymnasium envs with factors of variation (:mod:`.craftax`, upstream's module name).

Names resolve lazily: importing this package imports neither jax nor craftax; using an env without
them installed raises :class:`~stable_worldmodel.errors.DependencyNotInstalled` naming the extra.
"""

from __future__ import annotations

from ..._lazy import lazy_getattr

__all__ = [
    "CraftaxClassicPixelsWrapper",
    "CraftaxClassicSymbolicWrapper",
    "CraftaxPixelsWrapper",
    "CraftaxSymbolicWrapper",
    "CraftaxWrapper",
]

__getattr__ = lazy_getattr(__name__, {name: ".craftax" for name in __all__})

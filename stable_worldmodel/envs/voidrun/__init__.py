"""VoidRun: reach the goal across a floor that breaks behind you (``swm/VoidRun-v0``).

The classes are resolved lazily so that importing this package draws in nothing heavy.
"""

from __future__ import annotations

from ..._lazy import lazy_getattr

__all__ = ["VoidRunEnv", "VoidRunExpert"]
_WHERE = {"VoidRunEnv": ".env", "VoidRunExpert": ".expert"}

__getattr__ = lazy_getattr(__name__, _WHERE)

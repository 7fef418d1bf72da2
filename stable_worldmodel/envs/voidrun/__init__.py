"""VoidRun: reach the goal across a floor that breaks behind you (``swm/VoidRun-v0``).

The classes are resolved lazily so that importing this package draws in nothing heavy.
"""

from __future__ import annotations

import importlib
from typing import Any

__all__ = ["VoidRunEnv", "VoidRunExpert"]
_WHERE = {"VoidRunEnv": ".env", "VoidRunExpert": ".expert"}


def __getattr__(name: str) -> Any:
    if name not in _WHERE:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    return getattr(importlib.import_module(_WHERE[name], __name__), name)

"""``swm/TwoRoom-v1``: point navigation through door(s) between two rooms (classes resolved lazily)."""

from __future__ import annotations

import importlib
from typing import Any

__all__ = ["TwoRoomEnv", "TwoRoomExpert"]
_WHERE = {"TwoRoomEnv": ".env", "TwoRoomExpert": ".expert"}


def __getattr__(name: str) -> Any:
    if name in _WHERE:
        return getattr(importlib.import_module(_WHERE[name], __name__), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")

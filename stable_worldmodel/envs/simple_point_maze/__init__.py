"""``swm/SimplePointMaze-v0``: a point mass in a grid maze (classes resolved lazily)."""

from __future__ import annotations

import importlib
from typing import Any

__all__ = ["SimplePointMazeEnv", "SimplePointMazeExpert"]
_WHERE = {"SimplePointMazeEnv": ".env", "SimplePointMazeExpert": ".expert"}


def __getattr__(name: str) -> Any:
    if name in _WHERE:
        return getattr(importlib.import_module(_WHERE[name], __name__), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")

"""``swm/SimplePointMaze-v0``: a point mass in a grid maze (classes resolved lazily)."""

from __future__ import annotations

from ..._lazy import lazy_getattr

__all__ = ["SimplePointMazeEnv", "SimplePointMazeExpert"]
_WHERE = {"SimplePointMazeEnv": ".env", "SimplePointMazeExpert": ".expert"}

__getattr__ = lazy_getattr(__name__, _WHERE)

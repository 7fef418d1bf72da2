"""SimplePointMaze (classes resolved lazily).

- ``swm/SimplePointMaze-v0``: release 0.1.1's disk among random rectangles (:mod:`.v0`).
- ``swm/SimplePointMaze-v1``: our point mass with friction in a grid maze (:mod:`.env`).
"""

from __future__ import annotations

from ..._lazy import lazy_getattr

__all__ = ["SimplePointMazeEnv", "SimplePointMazeExpert", "SimplePointMazeV0Env", "SimplePointMazeV0Expert"]
_WHERE = {
    "SimplePointMazeEnv": ".env",
    "SimplePointMazeExpert": ".expert",
    "SimplePointMazeV0Env": ".v0",
    "SimplePointMazeV0Expert": ".v0_expert",
}

__getattr__ = lazy_getattr(__name__, _WHERE)

"""``swm/TwoRoom-v1`` (ours) and ``swm/TwoRoom-v0`` (release 0.0.3's): navigation through door(s) between two rooms.

Classes resolve lazily, so importing this package imports neither pymunk nor OpenCV.
"""

from __future__ import annotations

from ..._lazy import lazy_getattr

__all__ = ["ExpertPolicy", "TwoRoomEnv", "TwoRoomExpert", "TwoRoomV0Env", "TwoRoomV0Expert"]
_WHERE = {
    "TwoRoomEnv": ".env",
    "TwoRoomExpert": ".expert",
    "ExpertPolicy": ".expert",  # 0.0.3 / 0.1.1 name
    "TwoRoomV0Env": ".legacy",
    "TwoRoomV0Expert": ".legacy_expert",
}

__getattr__ = lazy_getattr(__name__, _WHERE)

"""``swm/TwoRoom-v1``: point navigation through door(s) between two rooms (classes resolved lazily)."""

from __future__ import annotations

from ..._lazy import lazy_getattr

__all__ = ["TwoRoomEnv", "TwoRoomExpert"]
_WHERE = {"TwoRoomEnv": ".env", "TwoRoomExpert": ".expert"}

__getattr__ = lazy_getattr(__name__, _WHERE)

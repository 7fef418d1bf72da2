"""``swm/TwoRoom-v1``: point navigation through door(s) between two rooms (classes resolved lazily)."""

from __future__ import annotations

from ..._lazy import lazy_getattr

__all__ = ["ExpertPolicy", "TwoRoomEnv", "TwoRoomExpert"]
_WHERE = {"TwoRoomEnv": ".env", "TwoRoomExpert": ".expert", "ExpertPolicy": ".expert"}  # ExpertPolicy: 0.0.3 / 0.1.1 name

__getattr__ = lazy_getattr(__name__, _WHERE)

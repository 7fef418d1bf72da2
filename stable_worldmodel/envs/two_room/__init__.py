"""TwoRoom: navigation through door(s) between two rooms. ``swm/TwoRoom-v1`` (upstream 0.1.1's,
:mod:`.v1`), ``swm/TwoRoom-v2`` (ours, :mod:`.env`) and ``swm/TwoRoom-v0`` (release 0.0.3's, :mod:`.v0`).

Classes resolve lazily, so importing this package imports neither pymunk nor OpenCV.
"""

from __future__ import annotations

from ..._lazy import lazy_getattr

__all__ = [
    "ExpertPolicy",
    "TwoRoomEnv",
    "TwoRoomExpert",
    "TwoRoomV0Env",
    "TwoRoomV0Expert",
    "TwoRoomV1Env",
    "TwoRoomV1Expert",
]
_WHERE = {
    "TwoRoomEnv": ".env",
    "TwoRoomExpert": ".expert",
    "ExpertPolicy": ".expert",  # 0.0.3 / 0.1.1 name: drives whichever TwoRoom it is set on
    "TwoRoomV0Env": ".v0",
    "TwoRoomV0Expert": ".v0_expert",
    "TwoRoomV1Env": ".v1",
    "TwoRoomV1Expert": ".v1_expert",
}

__getattr__ = lazy_getattr(__name__, _WHERE)

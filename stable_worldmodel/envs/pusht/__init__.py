"""The PushT family: ``swm/PushT-v1``, ``swm/PushT-Discrete-v1`` and their experts.

Names resolve lazily, so importing this package imports neither pymunk nor OpenCV.
"""

from __future__ import annotations

import importlib
from typing import Any

__all__ = ["PushT", "PushTDiscrete", "PushTDiscreteExpert", "PushTExpert"]

_LAZY = {
    "PushT": ".env",
    "PushTDiscrete": ".env",
    "PushTExpert": ".expert",
    "PushTDiscreteExpert": ".expert",
}


def __getattr__(name: str) -> Any:
    if name in _LAZY:
        value = getattr(importlib.import_module(_LAZY[name], __name__), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")

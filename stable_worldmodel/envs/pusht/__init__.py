"""The PushT family: ``swm/PushT-v1``, ``swm/PushT-Discrete-v1`` and their experts.

Names resolve lazily, so importing this package imports neither pymunk nor OpenCV.
"""

from __future__ import annotations

from ..._lazy import lazy_getattr

__all__ = ["PushT", "PushTDiscrete", "PushTDiscreteExpert", "PushTExpert", "WeakPolicy"]

_LAZY = {
    "PushT": ".env",
    "PushTDiscrete": ".env",
    "PushTExpert": ".expert",
    "PushTDiscreteExpert": ".expert",
    "WeakPolicy": ".weak",  # the name data recipes of 0.0.3 / 0.1.1 use
}

__getattr__ = lazy_getattr(__name__, _LAZY)

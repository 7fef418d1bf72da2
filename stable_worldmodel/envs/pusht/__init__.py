"""The PushT family: ``swm/PushT-v1`` / ``swm/PushT-Discrete-v1`` (upstream 0.1.1, :mod:`.v1`),
``swm/PushT-v2`` / ``swm/PushT-Discrete-v2`` (our design, :mod:`.env`) and the experts.

Names resolve lazily, so importing this package imports neither pymunk nor OpenCV.
"""

from __future__ import annotations

from ..._lazy import lazy_getattr

__all__ = ["PushT", "PushTDiscrete", "PushTDiscreteExpert", "PushTDiscreteV1", "PushTExpert", "PushTV1", "WeakPolicy"]

_LAZY = {
    "PushT": ".env",
    "PushTDiscrete": ".env",
    "PushTV1": ".v1",
    "PushTDiscreteV1": ".v1",
    "PushTExpert": ".expert",
    "PushTDiscreteExpert": ".expert",
    "WeakPolicy": ".weak",  # the name data recipes of 0.0.3 / 0.1.1 use
}

__getattr__ = lazy_getattr(__name__, _LAZY)

"""ImagePositioning: arrange procedurally generated images (``swm/ImagePositioning-v1``).

The classes are resolved lazily so that importing this package draws in nothing heavy.
"""

from __future__ import annotations

from ..._lazy import lazy_getattr

__all__ = ["ImagePositioningEnv", "ImagePositioningExpert"]
_WHERE = {"ImagePositioningEnv": ".env", "ImagePositioningExpert": ".expert"}

__getattr__ = lazy_getattr(__name__, _WHERE)

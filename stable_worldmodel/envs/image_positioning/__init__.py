"""ImagePositioning: arrange procedurally generated images (``swm/ImagePositioning-v1``).

The classes are resolved lazily so that importing this package draws in nothing heavy.
"""

from __future__ import annotations

import importlib
from typing import Any

__all__ = ["ImagePositioningEnv", "ImagePositioningExpert"]
_WHERE = {"ImagePositioningEnv": ".env", "ImagePositioningExpert": ".expert"}


def __getattr__(name: str) -> Any:
    if name not in _WHERE:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    return getattr(importlib.import_module(_WHERE[name], __name__), name)

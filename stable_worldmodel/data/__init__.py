"""Datasets: recording, loading and managing them.

Importing this package is cheap: h5py and torch are imported only when a dataset
class or a function that needs them is first used (PEP 562 lazy attributes).
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

from .utils import get_cache_dir

_ATTRS: dict[str, str] = {
    # name -> submodule that defines it
}

__all__ = ["get_cache_dir", *_ATTRS]


def __getattr__(name: str) -> Any:
    if name not in _ATTRS:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(importlib.import_module(f"{__name__}.{_ATTRS[name]}"), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))


if TYPE_CHECKING:  # pragma: no cover
    pass

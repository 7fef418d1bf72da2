"""stable_worldmodel: collect, train and evaluate world models through one interface.

Importing the package is cheap: it registers the ``swm/...`` environments with
Gymnasium (string entry points only) and resolves every other public name lazily
(PEP 562), so torch, h5py and cv2 are imported only when first used.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

#: above upstream 0.1.1 (same distribution name): `pip install -U` never swaps this package for an older one
__version__ = "0.2.0"

_SUBMODULES = (
    "data",
    "envs",
    "errors",
    "keys",
    "planning",
    "policy",
    "protocols",
    "solver",
    "spaces",
    "utils",
    "wm",
    "world",
    "wrapper",
    "wrappers",
    "cli",
)
_ATTRS = {
    "World": ("world", "World"),
    "PlanConfig": ("policy", "PlanConfig"),
}

__all__ = ["__version__", *_ATTRS, *[m for m in _SUBMODULES if m != "cli"]]


def __getattr__(name: str) -> Any:
    if name in _ATTRS:
        module, attr = _ATTRS[name]
        value = getattr(importlib.import_module(f"{__name__}.{module}"), attr)
    elif name in _SUBMODULES:
        value = importlib.import_module(f"{__name__}.{name}")
    else:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))


if TYPE_CHECKING:  # pragma: no cover
    from . import data, envs, policy, solver, spaces, utils, wm, wrapper, wrappers  # noqa: F401
    from .policy import PlanConfig  # noqa: F401
    from .world import World  # noqa: F401

from .envs import _registry  # noqa: E402  (registers swm/... ids; imports gymnasium only)

_registry.register_all()

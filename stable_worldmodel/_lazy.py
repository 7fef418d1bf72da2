"""PEP 562 lazy attributes: the one implementation every package ``__init__`` uses."""

from __future__ import annotations

import importlib
import importlib.util
import sys
from collections.abc import Callable
from typing import Any


def lazy_getattr(package: str, where: dict[str, str]) -> Callable[[str], Any]:
    """A module ``__getattr__`` that imports ``name`` from ``where[name]`` on first use.

    ``where`` maps a public name to the module defining it, relative to ``package``
    (``".env"``) or absolute (``"stable_worldmodel.planning"``). A name not in ``where`` that is
    a submodule of ``package`` is imported as the attribute (``swm.wm.utils.load_pretrained``
    works without ``import stable_worldmodel.wm.utils``, as in the original releases). The
    resolved value is cached in the package namespace, so later lookups cost nothing.
    """

    def __getattr__(name: str) -> Any:
        if name not in where:
            if not name.startswith("_") and importlib.util.find_spec(f"{package}.{name}") is not None:
                return importlib.import_module(f"{package}.{name}")  # the import binds it on the package
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        value = getattr(importlib.import_module(where[name], package), name)
        setattr(sys.modules[package], name, value)
        return value

    return __getattr__

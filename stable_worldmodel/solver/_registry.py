"""The solver registry: name -> solver class, resolved lazily.

Built-in solvers are known by ``"module:Class"`` strings so that listing them imports
nothing heavy; :func:`register_solver` adds user classes (and marks the built-ins).
"""

from __future__ import annotations

import importlib
from collections.abc import Callable
from typing import Any

from ..errors import ConfigError, unknown_name

__all__ = ["BUILTIN", "get_solver_class", "list_solvers", "make_solver", "register_solver"]

_P = "stable_worldmodel.solver"
#: the built-in solvers, ``name: "module:Class"`` (a new solver: its file and one line here)
BUILTIN: dict[str, str] = {
    "cem": f"{_P}.cem:CEMSolver",
    "icem": f"{_P}.icem:ICEMSolver",
    "mppi": f"{_P}.mppi:MPPISolver",
    "gd": f"{_P}.gd:GradientSolver",
    "pgd": f"{_P}.discrete_solvers:PGDSolver",
    "random": f"{_P}.random:RandomSolver",
    "nevergrad": f"{_P}.nevergrad:NevergradSolver",
    "predictive_sampling": f"{_P}.predictive_sampling:PredictiveSamplingSolver",
    "lagrangian": f"{_P}.lagrangian:LagrangianSolver",
    "categorical_cem": f"{_P}.categorical_cem:CategoricalCEMSolver",
}
_ENTRIES: dict[str, Any] = dict(BUILTIN)


def register_solver(name: str) -> Callable[[type], type]:
    """Class decorator: make ``cls`` available as ``make_solver(name, ...)``."""
    if not isinstance(name, str) or not name:
        raise ConfigError(f"register_solver requires a non-empty name, got {name!r}")

    def decorator(cls: type) -> type:
        current = _ENTRIES.get(name)
        if isinstance(current, type) and current is not cls and current.__qualname__ != cls.__qualname__:
            raise ConfigError(f"register_solver requires a free name, got {name!r} (taken by {current.__qualname__})")
        _ENTRIES[name] = cls
        cls.name = name
        return cls

    return decorator


def list_solvers() -> list[str]:
    """Registered solver names."""
    return sorted(_ENTRIES)


def get_solver_class(name: str) -> type:
    """The class registered as ``name`` (imports its module on first use)."""
    if name not in _ENTRIES:
        raise unknown_name("solver", name, _ENTRIES)
    entry = _ENTRIES[name]
    if isinstance(entry, str):
        module, _, attr = entry.partition(":")
        entry = getattr(importlib.import_module(module), attr)
        _ENTRIES[name] = entry
    return entry


def make_solver(name: str, *args: Any, **kwargs: Any) -> Any:
    """Build the solver registered as ``name``: ``make_solver("cem", model, num_samples=64)``."""
    return get_solver_class(name)(*args, **kwargs)

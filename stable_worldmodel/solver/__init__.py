"""Planning solvers: optimize action sequences against a cost model.

Importing this package is cheap; each solver class (and torch) is imported on first use.
``make_solver("cem", model, ...)`` builds a solver by its registered name.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from .._lazy import lazy_getattr
from ._registry import BUILTIN, get_solver_class, list_solvers, make_solver, register_solver

_ATTRS = {
    "Solver": "solver",
    "BaseSolver": "base",
    "PlanKnobs": "base",
    "Costable": "solver",
    "AUTO_BATCH": "base",
    "GDSolver": "gd",  # the seed's alias of GradientSolver
    # every built-in solver class, from the registry's table (one line there adds a solver)
    **{entry.partition(":")[2]: entry.partition(":")[0].rpartition(".")[2] for entry in BUILTIN.values()},
}

__all__ = ["get_solver_class", "list_solvers", "make_solver", "register_solver", *_ATTRS]


__getattr__ = lazy_getattr(__name__, {name: f".{module}" for name, module in _ATTRS.items()})


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))


if TYPE_CHECKING:  # pragma: no cover
    from .base import AUTO_BATCH, BaseSolver  # noqa: F401
    from .categorical_cem import CategoricalCEMSolver  # noqa: F401
    from .cem import CEMSolver  # noqa: F401
    from .discrete_solvers import PGDSolver  # noqa: F401
    from .gd import GDSolver, GradientSolver  # noqa: F401
    from .icem import ICEMSolver  # noqa: F401
    from .lagrangian import LagrangianSolver  # noqa: F401
    from .mppi import MPPISolver  # noqa: F401
    from .nevergrad import NevergradSolver  # noqa: F401
    from .predictive_sampling import PredictiveSamplingSolver  # noqa: F401
    from .random import RandomSolver  # noqa: F401
    from .solver import Costable, Solver  # noqa: F401

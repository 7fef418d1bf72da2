"""``stable_worldmodel.solver.pgd``: upstream 0.1.1's module of :class:`PGDSolver` (defined in
:mod:`.discrete_solvers`, with the simplex projection)."""

from __future__ import annotations

from .discrete_solvers import PGDSolver, project_simplex

__all__ = ["PGDSolver", "project_simplex"]

"""Planning-side solvers of upstream 0.1.1's layout: they plan against a ``cost`` (not a ``model``).

``stable_worldmodel.planning.CEMSolver`` and ``stable_worldmodel.planning.solver.cem.CEMSolver``
are the same class; the model-side solvers live in :mod:`stable_worldmodel.solver`.
"""

from __future__ import annotations

from .cem import CEMSolver

__all__ = ["CEMSolver"]

"""Per-iteration hooks of the solvers (upstream 0.1.1's ``stable_worldmodel.solver.callbacks``).

Pass ``callbacks=[...]`` to :class:`~stable_worldmodel.solver.CEMSolver`, ``ICEMSolver``,
``GradientSolver``, ``PGDSolver``, ``LagrangianSolver`` or ``CategoricalCEMSolver``. After every
iteration the solver calls each callback with keyword arguments describing the state (the
keys each solver passes are listed in :mod:`.common`); a callback's ``compute(**state)`` returns a
value (per env, reduced by its ``reduction``) that is appended to its ``history``, one list per
batch of envs. ``solve()`` returns the histories under ``outputs["callbacks"][cb.output_key]``.

Ours also stops early: a callback that sets ``self.stop = True`` ends the iterations of the
current batch of envs (:class:`EarlyStopping` does it when the best cost stops improving).
"""

from __future__ import annotations

from .cem import EliteCostRecorder, EliteSpreadRecorder, MeanShiftRecorder, VarNormRecorder
from .common import BestCostRecorder, Callback, EarlyStopping, MeanCostRecorder
from .gd import ActionNormRecorder, GradNormRecorder

__all__ = [
    "ActionNormRecorder",
    "BestCostRecorder",
    "Callback",
    "EarlyStopping",
    "EliteCostRecorder",
    "EliteSpreadRecorder",
    "GradNormRecorder",
    "MeanCostRecorder",
    "MeanShiftRecorder",
    "VarNormRecorder",
]

"""Planning with world models: WorldModelPolicy, checkpoint loading, upstream's planning-side
``CEMSolver(cost=...)``, the cost layer of upstream's main (``ShootingCostEvaluator`` and the
objectives) and the other solvers re-exported (needs torch).

``stable_worldmodel.policy`` re-exports these names lazily.
"""

from __future__ import annotations

from ..solver import (
    CategoricalCEMSolver,
    GradientSolver,
    ICEMSolver,
    LagrangianSolver,
    MPPISolver,
    PGDSolver,
    PredictiveSamplingSolver,
)
from .auto import AutoActionableModel, AutoCostModel, MissingAttributeError, list_model_checkpoints
from .evaluator import ShootingCostEvaluator, default_goal_encode
from .io import prepare_info, to_env_actions
from .objective import ControlPenalty, GoalMSE, WeightedSum
from .solver import CEMSolver
from .world_model_policy import WorldModelPolicy

__all__ = [
    "AutoActionableModel",
    "AutoCostModel",
    "CEMSolver",
    "CategoricalCEMSolver",
    "ControlPenalty",
    "GoalMSE",
    "GradientSolver",
    "ICEMSolver",
    "LagrangianSolver",
    "MPPISolver",
    "MissingAttributeError",
    "PGDSolver",
    "PredictiveSamplingSolver",
    "ShootingCostEvaluator",
    "WeightedSum",
    "WorldModelPolicy",
    "default_goal_encode",
    "list_model_checkpoints",
    "prepare_info",
    "to_env_actions",
]

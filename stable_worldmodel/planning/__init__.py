"""Planning with world models: WorldModelPolicy, checkpoint loading and upstream's
planning-side ``CEMSolver(cost=...)`` (needs torch).

``stable_worldmodel.policy`` re-exports these names lazily.
"""

from __future__ import annotations

from .auto import AutoActionableModel, AutoCostModel, MissingAttributeError, list_model_checkpoints
from .io import prepare_info, to_env_actions
from .solver import CEMSolver
from .world_model_policy import WorldModelPolicy

__all__ = [
    "AutoActionableModel",
    "AutoCostModel",
    "CEMSolver",
    "MissingAttributeError",
    "WorldModelPolicy",
    "list_model_checkpoints",
    "prepare_info",
    "to_env_actions",
]

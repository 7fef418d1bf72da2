"""Planning with world models: WorldModelPolicy and checkpoint loading (needs torch).

``stable_worldmodel.policy`` re-exports these names lazily.
"""

from __future__ import annotations

from .auto import AutoActionableModel, AutoCostModel, list_model_checkpoints
from .io import prepare_info, to_env_actions
from .world_model_policy import WorldModelPolicy

__all__ = [
    "AutoActionableModel",
    "AutoCostModel",
    "WorldModelPolicy",
    "list_model_checkpoints",
    "prepare_info",
    "to_env_actions",
]

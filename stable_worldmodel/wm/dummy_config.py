"""The dummy model's light config (two linear layers; for tests and examples)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, ClassVar

from .base import WorldModelConfig

__all__ = ["DummyConfig"]


@dataclass
class DummyConfig(WorldModelConfig):
    """Only ``image_size``, the data protocol and the training recipe matter (one preset, ``tiny``)."""

    model_name: ClassVar[str] = "dummy"
    target: ClassVar[str] = "stable_worldmodel.wm.dummy.DummyWorldModel"
    presets: ClassVar[dict[str, dict[str, Any]]] = {"tiny": {"image_size": 16, "history_size": 1}}

    def target_tree(self, action_dim: int) -> dict[str, Any]:
        return {
            "_target_": self.target,
            "image_shape": [3, self.image_size, self.image_size],
            "action_dim": self.frameskip * int(action_dim),
        }

"""DINO-WM under the seed's module name: ``DINOWM`` is :class:`~stable_worldmodel.wm.prejepa.PreJEPA`."""

from __future__ import annotations

from .backbones import create_backbone
from .prejepa.config import PreJEPAConfig
from .prejepa.module import CausalPredictor, Embedder
from .prejepa.prejepa import PreJEPA

DINOWM = PreJEPA
DINOWMConfig = PreJEPAConfig

__all__ = ["DINOWM", "DINOWMConfig", "PreJEPA", "PreJEPAConfig", "CausalPredictor", "Embedder", "create_backbone"]

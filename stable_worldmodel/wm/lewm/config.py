"""LeWM's light config and presets (no torch import)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, ClassVar

from ..config import IMAGENET_MEAN, IMAGENET_STD, JEPAConfig

__all__ = ["LeWMConfig"]


@dataclass
class LeWMConfig(JEPAConfig):
    """:class:`~stable_worldmodel.wm.config.JEPAConfig` plus ``sigreg_weight`` (0.09) and
    ``sigreg_num_proj`` (random directions of SIGReg).

    Presets: ``tiny`` (64x64, CNN, D=64, 2 predictor layers: trains on a laptop CPU in
    minutes; SIGReg weight 0.01 and 256 directions: on TwoRoom, 0.09 made the latent distance
    to a far goal say little about the true one and CEM reached 30% of goals, 0.01 reached
    53-67%, 0.003 20%), ``cpu`` (the tiny sizes with a CNN of width 16, a history of 3
    frames, D=128, SIGReg at 0.09, 17500 steps: the Push-T recipe for a 2-core CPU, ~52 minutes
    on both cores; with ``encoder=state`` it is the state-input recipe), ``small`` (64x64, a 6-layer ViT with patch
    8, D=192: a GPU in an hour) and
    ``paper`` (upstream's recipe: ViT-tiny patch 14 at 224x224, predictor depth 6 with 16
    heads, projectors of width 2048, batch 128, lr 5e-5).
    """

    model_name: ClassVar[str] = "lewm"
    target: ClassVar[str] = "stable_worldmodel.wm.lewm.LeWM"
    presets: ClassVar[dict[str, dict[str, Any]]] = {
        "tiny": {"sigreg_num_proj": 256, "sigreg_weight": 0.01},
        "cpu": {"sigreg_num_proj": 256, "history_size": 3, "embed_dim": 128, "cnn_width": 16, "steps": 17500},
        "small": {
            "encoder": "vit",
            "vit_size": "tiny",
            "patch_size": 8,
            "vit_overrides": {"num_hidden_layers": 6},
            "embed_dim": 192,
            "depth": 4,
            "heads": 8,
            "dim_head": 32,
            "mlp_dim": 768,
            "projector_hidden": 1024,
            "image_mean": IMAGENET_MEAN,
            "image_std": IMAGENET_STD,
            "batch_size": 128,
            "lr": 3e-4,
            "steps": 20000,
        },
        "paper": {
            "encoder": "vit",
            "vit_size": "tiny",
            "patch_size": 14,
            "image_size": 224,
            "embed_dim": 192,
            "depth": 6,
            "heads": 16,
            "dim_head": 64,
            "mlp_dim": 2048,
            "dropout": 0.1,
            "projector_hidden": 2048,
            "image_mean": IMAGENET_MEAN,
            "image_std": IMAGENET_STD,
            "batch_size": 128,
            "lr": 5e-5,
            "warmup_steps": 1000,
            "steps": 100000,
        },
    }

    FIELD_HELP: ClassVar[dict[str, str]] = {
        "sigreg_weight": "Weight of SIGReg, the loss pulling the embeddings towards an isotropic Gaussian.",
        "sigreg_num_proj": "Random directions SIGReg tests the embeddings' distribution along, per step.",
    }

    sigreg_weight: float = 0.09
    sigreg_num_proj: int = 1024

    def model_kwargs(self, action_dim: int) -> dict[str, Any]:
        return {
            **super().model_kwargs(action_dim),
            "sigreg_weight": self.sigreg_weight,
            "sigreg_num_proj": self.sigreg_num_proj,
        }

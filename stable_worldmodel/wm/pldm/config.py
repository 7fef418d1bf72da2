"""PLDM's light config and presets (no torch import)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, ClassVar

from ..config import IMAGENET_MEAN, IMAGENET_STD, JEPAConfig

__all__ = ["PLDMConfig", "UPSTREAM_LOSS_WEIGHTS"]

#: the term weights of upstream's recipe (``scripts/train/config/pldm.yaml``): every enabled term is added with
#: its weight, zero included; temporal straightening is disabled there (the ``paper`` preset's weights)
UPSTREAM_LOSS_WEIGHTS = {
    "std_loss": 18.0,
    "std_t_loss": 0.7,
    "cov_loss": 12.0,
    "cov_t_loss": 0.0,
    "temp_align_loss": 0.2,
    "idm_loss": 0.0,
    "temp_straight_loss": 0.0,
}


@dataclass
class PLDMConfig(JEPAConfig):
    """:class:`~stable_worldmodel.wm.config.JEPAConfig` plus ``idm_hidden`` (width of the
    inverse dynamics MLP, 0 for none) and ``loss_weights`` (see
    :data:`stable_worldmodel.wm.pldm.pldm.DEFAULT_LOSS_WEIGHTS`). Presets as LeWM's; ``cpu`` is the tiny
    sizes with a history of 3 frames and D=128 for 10000 steps (the Push-T recipe measured on a 2-core CPU:
    ~37 minutes on one thread)."""

    model_name: ClassVar[str] = "pldm"
    target: ClassVar[str] = "stable_worldmodel.wm.pldm.PLDM"
    presets: ClassVar[dict[str, dict[str, Any]]] = {
        "tiny": {},
        "cpu": {"history_size": 3, "embed_dim": 128, "steps": 10000},
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
            "idm_hidden": 512,
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
            "idm_hidden": 512,
            "loss_weights": dict(UPSTREAM_LOSS_WEIGHTS),
        },
    }

    FIELD_HELP: ClassVar[dict[str, str]] = {
        "idm_hidden": "Hidden width of the inverse-dynamics MLP predicting the action block (0: no such term).",
        "loss_weights": "Weights of the loss terms by name, over pldm.DEFAULT_LOSS_WEIGHTS (e.g. std_loss, idm_loss).",
    }

    idm_hidden: int = 128
    loss_weights: dict[str, float] = field(default_factory=dict)

    def target_tree(self, action_dim: int) -> dict[str, Any]:
        tree = super().target_tree(action_dim)
        if self.idm_hidden:
            tree["idm"] = self._mlp(
                2 * self.embed_dim, self.frameskip * int(action_dim), self.idm_hidden, batchnorm=False
            )
        return tree

    def model_kwargs(self, action_dim: int) -> dict[str, Any]:
        return {**super().model_kwargs(action_dim), "loss_weights": dict(self.loss_weights)}

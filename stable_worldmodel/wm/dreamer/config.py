"""Dreamer's light config and presets (no torch import)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, ClassVar

from ...errors import ConfigError
from ..base import check_positive_int
from ..config import IMAGENET_MEAN, IMAGENET_STD, ImageEncoderConfig

__all__ = ["DreamerConfig"]

_P = "stable_worldmodel.wm"


@dataclass
class DreamerConfig(ImageEncoderConfig):
    """:class:`~stable_worldmodel.wm.config.ImageEncoderConfig` for a Dreamer-style RSSM.

    Model: the inherited image ``encoder`` (``embed_dim`` wide for the CNN), a GRU deterministic
    state of ``deter_dim``, a diagonal Gaussian stochastic state of ``stoch_dim`` (prior and
    posterior MLPs of ``hidden`` units) and a transposed-conv image decoder of ``cnn_width``
    reading the features ``[h, z]`` (``deter_dim + stoch_dim`` numbers), and an ``embed_head``
    predicting a frame's encoder embedding from the prior's features (planning compares it with
    the goal frame's). Loss: squared error of the decoded frames summed over each frame (a
    unit-variance Gaussian; the decoder adds the training frames' mean, fitted before training)
    + ``kl_dyn * max(free_bits, KL(sg(post) || prior)) + kl_rep * max(free_bits,
    KL(post || sg(prior)))`` (DreamerV3's balancing, 0.5 / 0.1 and 1 nat) + ``embed_coef`` times
    the embedding head's MSE (to detached embeddings); with ``reward_head``
    a reward MLP is trained with MSE (``reward_coef``) and the dataset must have a ``reward``
    column (``needs_reward``). Every sample has ``history_size + num_preds`` frames, all filtered
    by the posterior.

    Presets: ``tiny`` (64x64, ConvEncoder of width 8, deter 64, stoch 16, 5 frames per sample,
    2000 steps: about 4 minutes on a 2-core CPU; on TwoRoom its latent starts encoding the agent
    after ~400 steps, and 1000 steps gave 42% or 70% depending on the run, 2000 gave 70% twice),
    ``small`` (64x64, width 32, deter 256, stoch 32: one GPU) and ``paper`` (64x64, width 64,
    deter 512, stoch 32, 16 frames per sample, batch 16, lr 1e-4).
    """

    model_name: ClassVar[str] = "dreamer"
    target: ClassVar[str] = "stable_worldmodel.wm.dreamer.Dreamer"
    #: read by :class:`~stable_worldmodel.train.data.TrainData`; set per instance from ``reward_head``
    needs_reward: ClassVar[bool] = False
    #: planning may aim at waypoints (the embedding head predicts a frame's embedding)
    subgoal_graph: ClassVar[bool] = True
    presets: ClassVar[dict[str, dict[str, Any]]] = {
        "tiny": {
            "image_size": 64,
            "cnn_width": 8,
            "embed_dim": 64,
            "deter_dim": 64,
            "stoch_dim": 16,
            "hidden": 64,
            "history_size": 4,
            "num_preds": 1,
            "batch_size": 16,
            "lr": 1e-3,
            "warmup_steps": 50,
            "steps": 2000,
        },
        "small": {
            "image_size": 64,
            "cnn_width": 32,
            "embed_dim": 256,
            "deter_dim": 256,
            "stoch_dim": 32,
            "hidden": 256,
            "history_size": 8,
            "num_preds": 1,
            "batch_size": 32,
            "lr": 3e-4,
            "steps": 20000,
        },
        "paper": {
            "image_size": 64,
            "cnn_width": 64,
            "embed_dim": 512,
            "deter_dim": 512,
            "stoch_dim": 32,
            "hidden": 512,
            "history_size": 15,
            "num_preds": 1,
            "image_mean": IMAGENET_MEAN,
            "image_std": IMAGENET_STD,
            "batch_size": 16,
            "lr": 1e-4,
            "weight_decay": 0.0,
            "warmup_steps": 0,
            "grad_clip": 1000.0,
            "steps": 100000,
        },
    }

    FIELD_HELP: ClassVar[dict[str, str]] = {
        "deter_dim": "Width of the GRU's deterministic state h.",
        "stoch_dim": "Width of the diagonal-Gaussian stochastic state z.",
        "hidden": "Hidden units of the prior and posterior MLPs.",
        "min_std": "Smallest standard deviation of the stochastic state.",
        "kl_dyn": "Weight of the dynamics KL term, KL(sg(posterior) || prior).",
        "kl_rep": "Weight of the representation KL term, KL(posterior || sg(prior)).",
        "free_bits": "Nats of KL below which the KL terms are not penalised.",
        "recon_coef": "Weight of the frame-reconstruction loss.",
        "reward_head": "Train a reward head too (the dataset must have a reward column).",
        "reward_coef": "Weight of the reward loss (with reward_head).",
        "embed_coef": "Weight of the embedding head's loss (it predicts a frame's embedding, for planning).",
    }

    deter_dim: int = 64
    stoch_dim: int = 16
    hidden: int = 64
    min_std: float = 0.1
    kl_dyn: float = 0.5
    kl_rep: float = 0.1
    free_bits: float = 1.0
    recon_coef: float = 1.0
    reward_head: bool = False
    reward_coef: float = 1.0
    embed_coef: float = 1.0
    history_size: int = 4

    def __post_init__(self) -> None:
        super().__post_init__()
        name = type(self).__name__
        for key in ("deter_dim", "stoch_dim", "hidden"):
            check_positive_int(name, key, getattr(self, key))
        for key in ("kl_dyn", "kl_rep", "free_bits", "recon_coef", "reward_coef", "embed_coef"):
            value = getattr(self, key)
            if isinstance(value, bool) or not isinstance(value, (int, float)) or value < 0:
                raise ConfigError(f"{name} requires {key} to be a number >= 0, got {value!r}")
        if isinstance(self.min_std, bool) or not isinstance(self.min_std, (int, float)) or self.min_std <= 0:
            raise ConfigError(f"{name} requires min_std to be a number > 0, got {self.min_std!r}")
        if not isinstance(self.reward_head, bool):
            raise ConfigError(f"{name} requires reward_head to be a bool, got {self.reward_head!r}")
        if self.num_steps < 2:
            raise ConfigError(
                f"{name} requires at least 2 frames per sample (history_size + num_preds), got {self.num_steps}"
            )
        self.needs_reward = self.reward_head

    def target_tree(self, action_dim: int) -> dict[str, Any]:
        """The ``_target_`` tree of the model for env actions of ``action_dim`` numbers."""
        feat = self.deter_dim + self.stoch_dim
        return {
            "_target_": self.target,
            "encoder": self.encoder_tree(),
            "decoder": {
                "_target_": f"{_P}.frame.module.FrameDecoder",
                "embed_dim": feat,
                "image_size": self.image_size,
                "width": self.cnn_width,
            },
            "rssm": {
                "_target_": f"{_P}.dreamer.module.RSSM",
                "embed_dim": self.encoder_dim,
                "action_dim": self.frameskip * int(action_dim),
                "deter_dim": self.deter_dim,
                "stoch_dim": self.stoch_dim,
                "hidden": self.hidden,
                "min_std": float(self.min_std),
            },
            "action_dim": self.frameskip * int(action_dim),
            "history_size": self.history_size,
            "kl_dyn": float(self.kl_dyn),
            "kl_rep": float(self.kl_rep),
            "free_bits": float(self.free_bits),
            "recon_coef": float(self.recon_coef),
            "reward_head": self.reward_head,
            "reward_coef": float(self.reward_coef),
            "embed_coef": float(self.embed_coef),
        }

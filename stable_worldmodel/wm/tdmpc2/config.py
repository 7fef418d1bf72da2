"""TD-MPC2's light config and presets (no torch import)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, ClassVar

from ... import keys
from ...errors import ConfigError, did_you_mean
from ..base import WorldModelConfig, check_positive_int

__all__ = ["TDMPC2Config"]

_PIXEL_ENCODERS = ("conv", "tdmpc2")


@dataclass
class TDMPC2Config(WorldModelConfig):
    """:class:`~stable_worldmodel.wm.base.WorldModelConfig` for TD-MPC2, which learns from a ``reward``
    column (``needs_reward``: training on a dataset without one is refused, saying how to record it).

    Model: ``pixel_encoder`` (``"conv"``: our :class:`~stable_worldmodel.wm.encoders.ConvEncoder` of
    ``cnn_width``; ``"tdmpc2"``: upstream's 4-layer CNN of ``num_channels``, image_size >= 35),
    ``embed_dim`` (the latent ``L``, a multiple of ``simnorm_dim``), ``mlp_dim`` (dynamics, reward,
    policy and Q heads), ``num_q`` Q heads with ``q_dropout``, ``num_bins`` two-hot bins over
    ``[vmin, vmax]`` in symlog space, ``proprio_dim`` (numbers of the dataset's ``proprio``
    column; 0: pixels only) encoded to ``proprio_emb_dim`` through a hidden ``enc_dim``, and
    ``goal_proprio_dim`` (numbers of the ``goal_proprio`` column, the episode's goal; 0: none)
    encoded the same way. TD-MPC2 plans on the reward it learned, so it reaches goals that change
    per episode only when its latent holds the goal: with ``goal_proprio_dim`` it does (the
    World gives ``goal_proprio`` to the planner as it gives ``proprio``).
    Loss: ``rho`` (step weight ``rho**t``), ``discount``, ``tau`` (EMA of the target Q heads and of
    the Q scale), ``entropy_coef``, ``consistency_coef``, ``reward_coef``, ``value_coef``, ``bc_coef``
    (0: upstream's loss; > 0: the prior also imitates the dataset's actions, as in TD3+BC: with
    offline data, a prior that maximises Q alone picks actions the data never shows, where Q is
    extrapolated).
    Planning: ``uncertainty_penalty`` (of the terminal Q), ``num_pi_trajs`` (prior samples averaged
    by ``get_action``). Data: one frame of context (``history_size`` must be 1) and ``num_preds``
    transitions per sample (upstream's ``horizon``); ``reward[:, t]`` is the sum of the
    ``frameskip`` env rewards earned by the action block ``t`` (see :mod:`stable_worldmodel.train.data`).
    ``encoder_lr_scale`` is not used (the encoder's parameters are named ``cnn`` / ``pixel_encoder``,
    as upstream's).

    Presets: ``tiny`` (64x64, ConvEncoder of width 16, latent 64, MLPs of 128, batch 32, 3000 steps
    of ~0.12 s on 2 CPU cores, so about 6 minutes, discount 0.9: with TwoRoom's episodes of ~20
    action blocks, 1000 steps at 0.99 left the Q heads anti-correlated with the distance to the
    goal, and their terminal value ranked the expert's actions below random ones; TD-MPC2's own
    rule, ``(L - 1) / L`` for ``L`` blocks per episode, gives 0.95), ``small`` (upstream's CNN
    at 64x64, latent 256, MLPs of 256: one GPU) and
    ``paper`` (upstream's / the paper's defaults: latent 512, MLPs of 512, 5 Q heads, 101 bins in
    [-10, 10], horizon 3, rho 0.5, lr 3e-4, batch 256, gradient clip 20, pixels scaled to
    ``x / 255 - 0.5``).
    """

    model_name: ClassVar[str] = "tdmpc2"
    target: ClassVar[str] = "stable_worldmodel.wm.tdmpc2.TDMPC2"
    #: :class:`~stable_worldmodel.train.data.TrainData` serves ``reward (B, T)`` and refuses a dataset without one
    needs_reward: ClassVar[bool] = True
    presets: ClassVar[dict[str, dict[str, Any]]] = {
        "tiny": {
            "pixel_encoder": "conv",
            "image_size": 64,
            "cnn_width": 16,
            "embed_dim": 64,
            "mlp_dim": 128,
            "enc_dim": 64,
            "batch_size": 32,
            "lr": 1e-3,
            "warmup_steps": 50,
            "steps": 3000,
            "discount": 0.9,
        },
        "small": {
            "pixel_encoder": "tdmpc2",
            "image_size": 64,
            "embed_dim": 256,
            "mlp_dim": 256,
            "enc_dim": 128,
            "batch_size": 128,
            "lr": 3e-4,
            "steps": 20000,
        },
        "paper": {
            "pixel_encoder": "tdmpc2",
            "image_size": 64,
            "embed_dim": 512,
            "mlp_dim": 512,
            "enc_dim": 256,
            "image_std": (1.0, 1.0, 1.0),
            "batch_size": 256,
            "lr": 3e-4,
            "weight_decay": 0.0,
            "warmup_steps": 0,
            "grad_clip": 20.0,
            "steps": 100000,
        },
    }

    FIELD_HELP: ClassVar[dict[str, str]] = {
        "pixel_encoder": "Pixel encoder: conv (a CNN of cnn_width) or tdmpc2 (upstream's; image_size >= 35).",
        "cnn_width": "Channels of the conv pixel encoder's first stage.",
        "num_channels": "Channels of upstream's CNN (pixel_encoder=tdmpc2).",
        "embed_dim": "Width L of the pixel latent (the latent is a multiple of simnorm_dim).",
        "mlp_dim": "Hidden width of the dynamics, reward, policy and Q MLPs.",
        "enc_dim": "Hidden width of the encoders of proprio and goal_proprio.",
        "num_q": "Q heads of the ensemble (>= 2).",
        "q_dropout": "Dropout of the Q heads.",
        "num_bins": "Two-hot bins of the reward and Q heads, over [vmin, vmax] in symlog space.",
        "vmin": "Lowest bin of the reward and Q heads (symlog space).",
        "vmax": "Highest bin of the reward and Q heads (symlog space).",
        "simnorm_dim": "Group size of the latent's simplicial normalisation (SimNorm).",
        "proprio_dim": "Numbers of the dataset's proprio column the model reads (0: pixels only).",
        "proprio_emb_dim": "Width of the encoding of proprio and of goal_proprio.",
        "goal_proprio_dim": "Numbers of the goal_proprio column, the episode's goal (0: none).",
        "rho": "Weight rho**t of the loss terms at step t of the horizon.",
        "discount": "Discount of the TD targets.",
        "tau": "EMA rate of the target Q heads and of the Q scale.",
        "entropy_coef": "Entropy bonus of the policy prior.",
        "consistency_coef": "Weight of the latent-dynamics consistency loss.",
        "reward_coef": "Weight of the reward loss.",
        "value_coef": "Weight of the Q loss.",
        "bc_coef": "Weight of imitating the dataset's actions in the prior's loss (0: upstream's loss).",
        "uncertainty_penalty": "Penalty on the Q heads' disagreement in the terminal value when planning.",
        "num_pi_trajs": "Prior samples averaged by get_action (acting without planning).",
        "num_preds": "Transitions per training sample (upstream's horizon).",
    }

    pixel_encoder: str = "conv"
    cnn_width: int = 8
    num_channels: int = 32
    embed_dim: int = 64
    mlp_dim: int = 128
    enc_dim: int = 64
    num_q: int = 5
    q_dropout: float = 0.01
    num_bins: int = 101
    vmin: float = -10.0
    vmax: float = 10.0
    simnorm_dim: int = 8
    proprio_dim: int = 0
    proprio_emb_dim: int = 32
    goal_proprio_dim: int = 0
    rho: float = 0.5
    discount: float = 0.99
    tau: float = 0.01
    entropy_coef: float = 1e-4
    consistency_coef: float = 20.0
    reward_coef: float = 0.1
    value_coef: float = 0.1
    bc_coef: float = 0.0
    uncertainty_penalty: float = 0.5
    num_pi_trajs: int = 1
    num_preds: int = 3
    grad_clip: float = 20.0

    def __post_init__(self) -> None:
        super().__post_init__()
        name = type(self).__name__
        if self.pixel_encoder not in _PIXEL_ENCODERS:
            raise ConfigError(
                f"{name} requires pixel_encoder in {_PIXEL_ENCODERS}, got {self.pixel_encoder!r}."
                f"{did_you_mean(str(self.pixel_encoder), _PIXEL_ENCODERS)}"
            )
        if self.history_size != 1:
            raise ConfigError(f"{name} requires history_size 1 (TD-MPC2 encodes one frame), got {self.history_size}")
        for key in (
            "cnn_width",
            "embed_dim",
            "mlp_dim",
            "num_channels",
            "enc_dim",
            "num_q",
            "num_bins",
            "simnorm_dim",
            "proprio_emb_dim",
            "num_pi_trajs",
        ):
            check_positive_int(name, key, getattr(self, key))
        for key in ("proprio_dim", "goal_proprio_dim"):
            check_positive_int(name, key, getattr(self, key), minimum=0)
        if self.num_q < 2 or self.num_bins < 2 or not self.vmin < self.vmax:
            raise ConfigError(
                f"{name} requires num_q >= 2, num_bins >= 2 and vmin < vmax, "
                f"got {self.num_q}, {self.num_bins}, {self.vmin}, {self.vmax}"
            )
        latent = self.embed_dim + self.proprio_emb_dim * len(self.extra_columns)
        if latent % self.simnorm_dim:
            raise ConfigError(
                f"{name} requires the latent width {latent} (embed_dim + proprio_emb_dim per extra input) to be "
                f"a multiple of simnorm_dim={self.simnorm_dim}"
            )
        if isinstance(self.bc_coef, bool) or not isinstance(self.bc_coef, (int, float)) or self.bc_coef < 0:
            raise ConfigError(f"{name} requires bc_coef >= 0 (0: upstream's loss), got {self.bc_coef!r}")
        for key in ("rho", "discount", "tau"):
            value = getattr(self, key)
            if not 0.0 < value <= 1.0:
                raise ConfigError(f"{name} requires {key} in (0, 1], got {value!r}")
        if self.pixel_encoder == "tdmpc2" and self.image_size < 35:
            raise ConfigError(
                f"{name} requires image_size >= 35 with pixel_encoder 'tdmpc2' (upstream's CNN), "
                f"got {self.image_size}; use 'conv'"
            )

    @property
    def extra_columns(self) -> dict[str, int]:
        """The dataset columns the model encodes besides pixels, with their widths."""
        widths = {keys.PROPRIO: self.proprio_dim, keys.goal_key(keys.PROPRIO): self.goal_proprio_dim}
        return {key: width for key, width in widths.items() if width}

    def target_tree(self, action_dim: int) -> dict[str, Any]:
        """The ``_target_`` tree of the model for env actions of ``action_dim`` numbers: upstream's
        ``TDMPC2(cfg)`` with ``cfg`` as a plain mapping."""
        encoding = {keys.PIXELS: self.embed_dim}
        extra_dims = self.extra_columns
        encoding.update({key: self.proprio_emb_dim for key in extra_dims})
        wm = {
            "encoding": encoding,
            "encoder": self.pixel_encoder,
            "num_channels": self.num_channels,
            "cnn_width": self.cnn_width,
            "enc_dim": self.enc_dim,
            "mlp_dim": self.mlp_dim,
            "num_bins": self.num_bins,
            "vmin": self.vmin,
            "vmax": self.vmax,
            "num_q": self.num_q,
            "simnorm_dim": self.simnorm_dim,
            "q_dropout": self.q_dropout,
            "tau": self.tau,
            "rho": self.rho,
            "discount": self.discount,
            "entropy_coef": self.entropy_coef,
            "consistency_coef": self.consistency_coef,
            "reward_coef": self.reward_coef,
            "value_coef": self.value_coef,
            "bc_coef": self.bc_coef,
            "horizon": self.num_preds,
            "uncertainty_penalty": self.uncertainty_penalty,
        }
        cfg = {
            "image_size": self.image_size,
            "action_dim": self.frameskip * int(action_dim),
            "extra_dims": extra_dims,
            "num_pi_trajs": self.num_pi_trajs,
            "wm": wm,
        }
        return {"_target_": self.target, "cfg": cfg}

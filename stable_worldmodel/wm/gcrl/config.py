"""Light configs of the goal-conditioned baselines (no torch import): ``gcbc``, ``gcivl`` and
``gciql`` in the model registry, each a :class:`~stable_worldmodel.wm.gcrl.GCRL` with presets.

A config also says how training samples hindsight goals (read by
:class:`~stable_worldmodel.train.data.TrainData`): ``goal_probabilities`` maps a way of
drawing a goal for a window to its probability (:data:`GOAL_SAMPLING`)::

    random     any frame of an episode of the same split
    geometric  k >= 1 frames after the window's last history frame, k ~ Geometric(1 - goal_gamma)
               (clipped to the episode's end)
    uniform    k uniform in 1 .. frames left in the episode
    current    the window's last history frame itself (the goal is reached: reward 0)

``actor_goal_probabilities`` (empty: the same goals) draws a second goal for the actor term
of ``gcivl`` / ``gciql``, as upstream's actor phase does.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any, ClassVar

from ... import keys
from ...errors import ConfigError, did_you_mean, unknown_name
from ..base import check_positive_int
from ..config import IMAGENET_MEAN, IMAGENET_STD, ImageEncoderConfig, PredictorConfig

__all__ = ["GOAL_SAMPLING", "GCBCConfig", "GCIQLConfig", "GCIVLConfig", "GCRLConfig", "check_goal_probabilities"]

GOAL_SAMPLING = ("random", "geometric", "uniform", "current")
POOL_TYPES = ("attention", "mean")
VALUE_HEADS = ("transformer", "metric")
_P = "stable_worldmodel.wm.gcrl"


def check_goal_probabilities(
    probabilities: Mapping[str, float], owner: str, allow_empty: bool = False
) -> dict[str, float]:
    """``probabilities`` as a dict over :data:`GOAL_SAMPLING` (unknown names raise
    :class:`~stable_worldmodel.errors.UnknownNameError` with "did you mean"); values must be
    >= 0 and sum to 1."""
    if not isinstance(probabilities, Mapping):
        raise ConfigError(
            f"{owner} requires goal probabilities as a mapping {{name: p}} over {GOAL_SAMPLING}, got {probabilities!r}"
        )
    probs = dict(probabilities)
    if not probs and allow_empty:
        return probs
    for name, p in probs.items():
        if name not in GOAL_SAMPLING:
            raise unknown_name(f"goal sampling of {owner}", name, GOAL_SAMPLING)
        if isinstance(p, bool) or not isinstance(p, (int, float)) or not p >= 0:
            raise ConfigError(f"{owner} requires goal probability {name!r} >= 0, got {p!r}")
    if not math.isclose(sum(probs.values()), 1.0, abs_tol=1e-6):
        raise ConfigError(
            f"{owner} requires goal probabilities summing to 1, got {probs} (sum {sum(probs.values()):g})"
        )
    return {k: float(v) for k, v in probs.items()}


def _presets(paper_lr: float, paper_dropout: float, **common: Any) -> dict[str, dict[str, Any]]:
    """``tiny`` (CPU, minutes), ``small`` (a GPU) and ``paper`` (upstream's recipe)."""
    return {
        "tiny": {
            "image_size": 64,
            "embed_dim": 32,
            "cnn_width": 8,
            "depth": 3,
            "heads": 2,
            "dim_head": 16,
            "mlp_dim": 64,
            "history_size": 1,
            "frameskip": 1,
            "batch_size": 64,
            "lr": 1e-3,
            "warmup_steps": 100,
            "steps": 2000,
            "q_hidden": 64,
            "metric_dim": 32,
            **common,
        },
        "small": {
            "encoder": "vit",
            "vit_size": "tiny",
            "patch_size": 8,
            "vit_overrides": {"num_hidden_layers": 6},
            "depth": 4,
            "heads": 8,
            "dim_head": 32,
            "mlp_dim": 768,
            "history_size": 3,
            "frameskip": 1,
            "image_mean": IMAGENET_MEAN,
            "image_std": IMAGENET_STD,
            "batch_size": 128,
            "lr": 3e-4,
            "steps": 20000,
            **common,
        },
        "paper": {
            "encoder": "vit",
            "vit_size": "tiny",
            "patch_size": 14,
            "image_size": 224,
            "depth": 6,
            "heads": 16,
            "dim_head": 64,
            "mlp_dim": 2048,
            "dropout": paper_dropout,
            "history_size": 3,
            "frameskip": 1,
            "image_mean": IMAGENET_MEAN,
            "image_std": IMAGENET_STD,
            "batch_size": 32,
            "lr": paper_lr,
            "warmup_steps": 1000,
            "steps": 100000,
            **common,
        },
    }


@dataclass
class GCRLConfig(ImageEncoderConfig, PredictorConfig):
    """An image encoder (:class:`~stable_worldmodel.wm.config.ImageEncoderConfig`) and transformer heads
    (:class:`~stable_worldmodel.wm.config.PredictorConfig`) over the data protocol and recipe
    for a :class:`~stable_worldmodel.wm.gcrl.GCRL` policy whose ``algorithm`` the subclass fixes.

    The heads are transformers of ``depth`` layers over the ``history_size`` frames' tokens
    (1 per frame with the CNN encoder, the patches with a ViT), ``embed_dim`` wide with the CNN.
    ``pool_type``: how the action head pools a frame (``attention`` or ``mean``); ``value_head``:
    ``transformer`` (a mean-pooled Predictor) or ``metric`` (:class:`MetricValuePredictor`,
    ``metric_dim`` wide); ``q_hidden``: the critic's MLP width. RL: ``discount``,
    ``expectile``, ``awr_alpha``, ``value_ema`` (EMA coefficient of the target heads),
    ``actor_encoder_grad`` (the actor term trains the encoder too: True, as our encoders start
    from scratch; upstream froze it, see :mod:`stable_worldmodel.wm.gcrl.algorithms`). Goals:
    see the module docstring. Proprioception (upstream's default, ``use_proprio_encoder``):
    ``proprio_dim > 0`` reads the dataset's ``proprio`` column (that many numbers), embedded to
    ``proprio_emb_dim`` by an :class:`~stable_worldmodel.wm.gcrl.module.Embedder` and joined to
    every image token, for the observed frames and the goal frame alike; the policy then acts
    from ``proprio`` / ``goal_proprio`` infos too. ``num_preds`` is not used.
    """

    target: ClassVar[str] = f"{_P}.GCRL"
    algorithm: ClassVar[str] = "gcbc"
    #: ``swm eval --policy gc:RUN`` acts with these checkpoints
    eval_prefix: ClassVar[str] = "gc"

    FIELD_HELP: ClassVar[dict[str, str]] = {
        "pool_type": "How the action head pools a frame's tokens: attention or mean.",
        "value_head": "Value head (gcivl, gciql): transformer (mean-pooled) or metric (a distance of embeddings).",
        "metric_dim": "Width of the metric value head's embeddings (value_head=metric).",
        "q_hidden": "Hidden width of the critic's MLP (gciql).",
        "discount": "Discount of the TD targets (gcivl, gciql).",
        "expectile": "Expectile of the value regression (gcivl, gciql).",
        "awr_alpha": "Inverse temperature of the advantage-weighted actor (gcivl, gciql).",
        "actor_encoder_grad": "Whether the actor term trains the image encoder too (gcivl, gciql).",
        "value_ema": "EMA coefficient of the target value and critic heads.",
        "log_std_min": "Lower clip of the policy's log standard deviation.",
        "log_std_max": "Upper clip of the policy's log standard deviation.",
        "goal_probabilities": "How hindsight goals are drawn: {random, geometric, uniform, current: p}, summing to 1.",
        "actor_goal_probabilities": "Goal mixture of the actor term, as goal_probabilities (empty: the same goals).",
        "goal_gamma": "Geometric goal sampling: the goal is k ~ Geometric(1 - goal_gamma) frames ahead.",
        "proprio_dim": "Numbers of the dataset's proprio column the policy reads, of its frames and goal (0: none).",
        "proprio_emb_dim": "Width of the proprio embedding joined to every image token (proprio_dim > 0).",
    }

    pool_type: str = "attention"
    value_head: str = "transformer"
    metric_dim: int = 64
    q_hidden: int = 256
    discount: float = 0.99
    expectile: float = 0.7
    awr_alpha: float = 10.0
    actor_encoder_grad: bool = True
    value_ema: float = 0.995
    log_std_min: float = -5.0
    log_std_max: float = 2.0
    goal_probabilities: dict[str, float] = field(default_factory=lambda: {"uniform": 1.0})
    actor_goal_probabilities: dict[str, float] = field(default_factory=dict)
    goal_gamma: float = 0.99
    proprio_dim: int = 0
    proprio_emb_dim: int = 10

    def __post_init__(self) -> None:
        super().__post_init__()
        name = type(self).__name__
        check_positive_int(name, "proprio_dim", self.proprio_dim, minimum=0)
        check_positive_int(name, "proprio_emb_dim", self.proprio_emb_dim)
        for key, allowed in (("pool_type", POOL_TYPES), ("value_head", VALUE_HEADS)):
            value = getattr(self, key)
            if value not in allowed:
                raise ConfigError(
                    f"{name} requires {key} in {allowed}, got {value!r}.{did_you_mean(str(value), allowed)}"
                )
        least = 3 if self.pool_type == "attention" else 2
        if self.depth < least:
            raise ConfigError(
                f"{name} requires depth >= {least} with pool_type={self.pool_type!r}, got {self.depth}: "
                "a shallower stack never attends to the goal"
            )
        for key in ("metric_dim", "q_hidden"):
            value = getattr(self, key)
            if isinstance(value, bool) or not isinstance(value, int) or value < 1:
                raise ConfigError(f"{name} requires {key} to be a positive int, got {value!r}")
        if not (
            0.0 <= self.discount <= 1.0
            and 0.0 < self.expectile < 1.0
            and 0.0 <= self.value_ema < 1.0
            and 0.0 < self.goal_gamma < 1.0
        ):
            raise ConfigError(
                f"{name} requires discount in [0, 1], expectile in (0, 1), value_ema in [0, 1) "
                "and goal_gamma in (0, 1), "
                f"got {self.discount}, {self.expectile}, {self.value_ema}, {self.goal_gamma}"
            )
        if self.awr_alpha < 0 or self.log_std_min > self.log_std_max:
            raise ConfigError(
                f"{name} requires awr_alpha >= 0 and log_std_min <= log_std_max, "
                f"got {self.awr_alpha}, {self.log_std_min}, {self.log_std_max}"
            )
        if self.encoder == "vit" and self.image_size % self.patch_size:
            raise ConfigError(
                f"{name} requires image_size divisible by patch_size, got {self.image_size} and {self.patch_size}"
            )
        self.goal_probabilities = check_goal_probabilities(self.goal_probabilities, name)
        self.actor_goal_probabilities = check_goal_probabilities(
            self.actor_goal_probabilities, f"{name} (actor)", allow_empty=True
        )

    @property
    def num_steps(self) -> int:
        """Frames per training sample: ``history_size``, plus the next frame for the TD targets of gcivl / gciql."""
        return self.history_size + (0 if self.algorithm == "gcbc" else 1)

    @property
    def extra_columns(self) -> dict[str, int]:
        """``proprio`` (its width) when ``proprio_dim > 0``."""
        return {keys.PROPRIO: self.proprio_dim} if self.proprio_dim else {}

    @property
    def token_dim(self) -> int:
        """Width of the heads' tokens: the encoder's, plus the proprio embedding when there is one."""
        return self.encoder_dim + (self.proprio_emb_dim if self.proprio_dim else 0)

    @property
    def num_patches(self) -> int:
        """Tokens per frame: 1 with the CNN encoder, ``(image_size / patch_size)^2`` with a ViT."""
        return (self.image_size // self.patch_size) ** 2 if self.encoder == "vit" else 1

    def encoder_tree(self) -> dict[str, Any]:
        if self.encoder == "vit":
            return super().encoder_tree()
        return {
            "_target_": f"{_P}.module.ConvLogitsEncoder",
            "image_size": self.image_size,
            "width": self.cnn_width,
            "hidden_size": self.embed_dim,
        }

    def _head(self, target: str, **extra: Any) -> dict[str, Any]:
        return {
            "_target_": f"{_P}.module.{target}",
            "num_patches": self.num_patches,
            "num_frames": self.history_size,
            "dim": self.token_dim,
            "depth": self.depth,
            "heads": self.heads,
            "mlp_dim": self.mlp_dim,
            "dim_head": self.dim_head,
            "dropout": self.dropout,
            "emb_dropout": 0.0,
            **extra,
        }

    def _ema(self, student: dict[str, Any]) -> dict[str, Any]:
        return {
            "_target_": f"{_P}.module.TeacherStudentWrapper",
            "student": student,
            "warm_init": True,
            "base_ema_coefficient": self.value_ema,
            "final_ema_coefficient": self.value_ema,
        }

    def target_tree(self, action_dim: int) -> dict[str, Any]:
        """The ``GCRL`` tree for env actions of ``action_dim`` numbers
        (heads act on blocks of ``frameskip`` actions)."""
        block = self.frameskip * int(action_dim)
        tree: dict[str, Any] = {
            "_target_": self.target,
            "encoder": self.encoder_tree(),
            "action_predictor": self._head("Predictor", out_dim=block, pool_type=self.pool_type),
        }
        if self.algorithm != "gcbc":
            value = (
                self._head("MetricValuePredictor", embed_dim=self.metric_dim)
                if self.value_head == "metric"
                else self._head("Predictor", out_dim=1, pool_type="mean")
            )
            tree["value_predictor"] = self._ema(value)
        if self.proprio_dim:
            tree["extra_encoders"] = {
                keys.PROPRIO: {
                    "_target_": f"{_P}.module.Embedder",
                    "in_chans": self.proprio_dim,
                    "emb_dim": self.proprio_emb_dim,
                }
            }
        if self.algorithm == "gciql":
            tree["critic_predictor"] = self._ema(
                self._head("QPredictor", action_dim=block, q_hidden_dim=self.q_hidden, pool_type="mean")
            )
        tree.update(history_size=self.history_size, log_std_min=self.log_std_min, log_std_max=self.log_std_max)
        tree.update(self.model_kwargs(action_dim))
        return tree

    def model_kwargs(self, action_dim: int) -> dict[str, Any]:
        kwargs: dict[str, Any] = {"algorithm": self.algorithm}
        if self.algorithm != "gcbc":
            kwargs.update(
                discount=self.discount,
                expectile=self.expectile,
                awr_alpha=self.awr_alpha,
                actor_encoder_grad=self.actor_encoder_grad,
            )
        return kwargs


#: upstream's goal mixtures of the value phase and of the actor phase (``scripts/train/config/gci*l.yaml``)
_VALUE_GOALS = {"random": 0.3, "geometric": 0.5, "current": 0.2}
_ACTOR_GOALS = {"random": 0.5, "uniform": 0.5}


@dataclass
class GCBCConfig(GCRLConfig):
    """Goal-conditioned behaviour cloning: the mean action of the policy regresses the data's
    action block (MSE). Goals: future frames of the same episode (``uniform``: upstream's)."""

    model_name: ClassVar[str] = "gcbc"
    algorithm: ClassVar[str] = "gcbc"
    presets: ClassVar[dict[str, dict[str, Any]]] = _presets(1e-4, 0.1)


@dataclass
class GCIVLConfig(GCRLConfig):
    """Goal-conditioned implicit V-learning: an expectile (0.7) TD value with an EMA target, and
    an advantage-weighted actor. Goals: upstream's value and actor mixtures."""

    model_name: ClassVar[str] = "gcivl"
    algorithm: ClassVar[str] = "gcivl"
    presets: ClassVar[dict[str, dict[str, Any]]] = _presets(3e-4, 0.0)

    goal_probabilities: dict[str, float] = field(default_factory=lambda: dict(_VALUE_GOALS))
    actor_goal_probabilities: dict[str, float] = field(default_factory=lambda: dict(_ACTOR_GOALS))


@dataclass
class GCIQLConfig(GCIVLConfig):
    """Goal-conditioned implicit Q-learning: a TD critic, an expectile (0.9) value towards it,
    EMA targets, and an advantage-weighted actor (``A = Q - V``)."""

    model_name: ClassVar[str] = "gciql"
    algorithm: ClassVar[str] = "gciql"
    presets: ClassVar[dict[str, dict[str, Any]]] = _presets(3e-4, 0.0)

    expectile: float = 0.9

"""Light configuration of the world models (no torch import), built on
:class:`~stable_worldmodel.wm.base.WorldModelConfig` (what every model shares): the parts a model
may have (:class:`ImageEncoderConfig`, :class:`PredictorConfig`) and the JEPA family's config
(:class:`JEPAConfig`: LeWM, PLDM). A config renders the ``_target_`` tree that builds the model
(:meth:`JEPAConfig.target_tree`), which is also what ``config.json`` of a checkpoint holds.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, ClassVar

from .. import keys
from ..errors import ConfigError, did_you_mean
from .base import WorldModelConfig, check_positive_int

__all__ = [
    "GOAL_COSTS",
    "IMAGENET_MEAN",
    "IMAGENET_STD",
    "VIT_SIZES",
    "ImageEncoderConfig",
    "JEPAConfig",
    "PredictorConfig",
    "WorldModelConfig",
    "parse_override",
]

IMAGENET_MEAN = (0.485, 0.456, 0.406)
IMAGENET_STD = (0.229, 0.224, 0.225)

#: how a model scores a rollout against the goal (``goal_cost``): ``final`` (upstream's: the last
#: predicted embedding) or ``min`` (the closest predicted embedding: reaching the goal at any step)
GOAL_COSTS = ("final", "min")

_BATCHNORM = {"_target_": "torch.nn.BatchNorm1d", "_partial_": True}
_P = "stable_worldmodel.wm"


#: ViT sizes of ``vit_hf`` (the MLP width is 4x the hidden size)
VIT_SIZES = {
    "tiny": {"hidden_size": 192, "num_hidden_layers": 12, "num_attention_heads": 3},
    "small": {"hidden_size": 384, "num_hidden_layers": 12, "num_attention_heads": 6},
    "base": {"hidden_size": 768, "num_hidden_layers": 12, "num_attention_heads": 12},
    "large": {"hidden_size": 1024, "num_hidden_layers": 24, "num_attention_heads": 16},
    "huge": {"hidden_size": 1280, "num_hidden_layers": 32, "num_attention_heads": 16},
}


def parse_override(text: str) -> tuple[str, Any]:
    """``"KEY=VALUE"`` -> ``(KEY, VALUE)``, a config override as ``swm train --set`` takes it: the
    value read as JSON when it parses (``2``, ``true``, ``[1, 2]``), else kept as a string."""
    import json

    key, sep, raw = text.partition("=")
    if not sep or not key.strip():
        raise ConfigError(
            f"A config override requires KEY=VALUE (a config field of the model, e.g. proprio_dim=2), got {text!r}"
        )
    try:
        return key.strip(), json.loads(raw)
    except json.JSONDecodeError:
        return key.strip(), raw


@dataclass
class PredictorConfig(WorldModelConfig):
    """A config with a transformer predictor (or transformer heads): ``depth`` layers of ``heads``
    heads of ``dim_head``, MLP ``mlp_dim``, ``dropout``."""

    FIELD_HELP: ClassVar[dict[str, str]] = {
        "depth": "Transformer layers of the predictor (or of the heads).",
        "heads": "Attention heads per transformer layer.",
        "dim_head": "Width of each attention head.",
        "mlp_dim": "Hidden width of the transformer's MLP blocks.",
        "dropout": "Dropout probability in the transformer (0 <= p < 1).",
    }

    depth: int = 2
    heads: int = 4
    dim_head: int = 16
    mlp_dim: int = 256
    dropout: float = 0.0

    def __post_init__(self) -> None:
        super().__post_init__()
        name = type(self).__name__
        for key in ("depth", "heads", "dim_head", "mlp_dim"):
            check_positive_int(name, key, getattr(self, key))
        if not 0.0 <= self.dropout < 1.0:
            raise ConfigError(f"{name} requires 0 <= dropout < 1, got {self.dropout!r}")

    def transformer_sizes(self) -> dict[str, Any]:
        """The predictor transformer's size arguments (``depth``, ``heads``, ``mlp_dim``, ``dim_head``, dropouts)."""
        return {
            "depth": self.depth,
            "heads": self.heads,
            "mlp_dim": self.mlp_dim,
            "dim_head": self.dim_head,
            "dropout": self.dropout,
            "emb_dropout": 0.0,
        }


@dataclass
class ImageEncoderConfig(WorldModelConfig):
    """A config with a trained image encoder: ``encoder`` ("cnn" or "vit"), ``embed_dim`` (D; the
    CNN's output width), CNN ``cnn_width``, ViT ``vit_size`` / ``patch_size`` / ``vit_overrides``
    (ViTConfig fields)."""

    FIELD_HELP: ClassVar[dict[str, str]] = {
        "encoder": "Image encoder trained with the model: cnn (a strided CNN) or vit (a ViT from scratch).",
        "embed_dim": "Width D of the embeddings (also the CNN encoder's output width).",
        "cnn_width": "Channels of the CNN encoder's first stage (doubled per stage, up to 8x).",
        "vit_size": "ViT size with encoder=vit: tiny, small, base, large or huge.",
        "patch_size": "Side of the ViT's square patches, in pixels.",
        "vit_overrides": "ViTConfig fields replacing the size's (e.g. num_hidden_layers), with encoder=vit.",
    }

    #: the encoders this config can build
    ENCODERS: ClassVar[tuple[str, ...]] = ("cnn", "vit")

    encoder: str = "cnn"
    embed_dim: int = 64
    cnn_width: int = 8
    vit_size: str = "tiny"
    patch_size: int = 8
    vit_overrides: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        super().__post_init__()
        name = type(self).__name__
        if self.encoder not in self.ENCODERS:
            raise ConfigError(
                f"{name} requires encoder in {self.ENCODERS}, got "
                f"{self.encoder!r}.{did_you_mean(self.encoder, self.ENCODERS)}"
            )
        for key in ("embed_dim", "cnn_width", "patch_size"):
            check_positive_int(name, key, getattr(self, key))
        if self.encoder == "vit" and self.vit_size not in VIT_SIZES:
            raise ConfigError(
                f"{name} requires vit_size in {sorted(VIT_SIZES)}, got "
                f"{self.vit_size!r}.{did_you_mean(self.vit_size, VIT_SIZES)}"
            )

    def encoder_tree(self) -> dict[str, Any]:
        if self.encoder == "vit":
            return {
                "_target_": "stable_pretraining.backbone.utils.vit_hf",
                "size": self.vit_size,
                "patch_size": self.patch_size,
                "image_size": self.image_size,
                "pretrained": False,
                "use_mask_token": False,
                **self.vit_overrides,
            }
        return {
            "_target_": f"{_P}.encoders.ConvEncoder",
            "image_size": self.image_size,
            "width": self.cnn_width,
            "hidden_size": self.encoder_dim,
        }

    @property
    def encoder_dim(self) -> int:
        """Width of the encoder's output token."""
        if self.encoder == "vit":
            return int(self.vit_overrides.get("hidden_size", VIT_SIZES[self.vit_size]["hidden_size"]))
        return self.embed_dim


@dataclass
class JEPAConfig(ImageEncoderConfig, PredictorConfig):
    """Sizes and recipe of a JEPA world model (LeWM, PLDM): an image encoder
    (:class:`ImageEncoderConfig`), a transformer predictor (:class:`PredictorConfig`) and
    ``projector_hidden`` (the projector heads' width; 0: none), over the data protocol and
    training recipe every model shares (:class:`~stable_worldmodel.wm.base.WorldModelConfig`).
    """

    #: planning may aim at waypoints of the training data (the embedding of a frame is a goal)
    subgoal_graph: ClassVar[bool] = True

    ENCODERS: ClassVar[tuple[str, ...]] = ("cnn", "vit", "state")
    FIELD_HELP: ClassVar[dict[str, str]] = {
        "projector_hidden": "Hidden width of the projector heads (0: no projectors; the encoder width must be D).",
        "encoder": "Encoder trained with the model: cnn (a strided CNN), vit (a ViT from scratch) or state (an MLP "
        "over the dataset column state_key instead of the pixels).",
        "rollout_steps": "K > 0 adds to the loss the error of K open-loop predictions from one frame, each fed back "
        "as context as planning does (samples get at least 1 + K frames; 0: upstream's teacher-forced objective).",
        "state_key": "encoder=state: the column (and info key) the model observes, e.g. state or proprio.",
        "state_dim": "encoder=state: numbers in that column (its width).",
        "state_width": "encoder=state: hidden width of the state encoder's MLP.",
        "state_dims": "encoder=state: the entries of that column the model reads, e.g. [0,1,2,3,4] (Push-T's poses "
        "without the agent's velocity; default: all).",
    }

    projector_hidden: int = 256
    rollout_steps: int = 0
    state_key: str = keys.STATE
    state_dim: int = 0
    state_width: int = 256
    state_dims: list[int] = field(default_factory=list)

    def __post_init__(self) -> None:
        super().__post_init__()
        name = type(self).__name__
        check_positive_int(name, "projector_hidden", self.projector_hidden, minimum=0)
        check_positive_int(name, "rollout_steps", self.rollout_steps, minimum=0)
        check_positive_int(name, "state_width", self.state_width)
        check_positive_int(name, "state_dim", self.state_dim, minimum=0)
        if self.encoder == "state" and (not self.state_dim or self.state_key in (keys.PIXELS, keys.ACTION)):
            raise ConfigError(
                f"{name} with encoder='state' requires state_dim > 0 (the width of the dataset column it reads) and "
                f"state_key a numeric column other than pixels and action, got state_dim={self.state_dim}, "
                f"state_key={self.state_key!r}; e.g. --set encoder=state --set state_dim=7 (swm/PushT-v1's state)"
            )
        dims = self.state_dims
        if (
            not isinstance(dims, (list, tuple))
            or any(isinstance(d, bool) or not isinstance(d, int) or not 0 <= d < max(self.state_dim, 1) for d in dims)
            or len(set(dims)) != len(dims)
        ):
            raise ConfigError(
                f"{name} requires state_dims to be distinct entries of the state_dim={self.state_dim} column "
                f"(0..{self.state_dim - 1}), got {dims!r}; e.g. --set state_dims=[0,1,2,3,4]"
            )

    @property
    def num_steps(self) -> int:
        """Frames per training sample: ``history_size + num_preds``, or ``1 + rollout_steps`` when more."""
        return max(self.history_size + self.num_preds, 1 + self.rollout_steps)

    @property
    def extra_columns(self) -> dict[str, int]:
        """``state_key`` (its width) with the state encoder."""
        return {self.state_key: self.state_dim} if self.encoder == "state" else {}

    @property
    def reads_pixels(self) -> bool:
        return self.encoder != "state"

    @classmethod
    def subgoal_graph_unavailable(cls, config: Any) -> str | None:
        if (config or {}).get("encoder") == "state":
            return "a state-input model plans on states, and the waypoint graph is built from the frames"
        return super().subgoal_graph_unavailable(config)

    def encoder_tree(self) -> dict[str, Any]:
        if self.encoder == "state":
            return {
                "_target_": f"{_P}.encoders.StateEncoder",
                "input_dim": self.state_dim,
                "hidden_size": self.encoder_dim,
                "width": self.state_width,
                **({"dims": list(self.state_dims)} if self.state_dims else {}),
            }
        return super().encoder_tree()

    # -- the model as a _target_ tree -----------------------------------------------------------
    def _mlp(self, d_in: int, d_out: int, hidden: int, batchnorm: bool = True) -> dict[str, Any]:
        tree = {"_target_": f"{_P}.lewm.module.MLP", "input_dim": d_in, "output_dim": d_out, "hidden_dim": hidden}
        if batchnorm:
            tree["norm_fn"] = dict(_BATCHNORM)
        return tree

    def target_tree(self, action_dim: int) -> dict[str, Any]:
        """The ``_target_`` tree of the model for env actions of ``action_dim`` numbers."""
        d, enc = self.embed_dim, self.encoder_dim
        tree: dict[str, Any] = {
            "_target_": self.target,
            "encoder": self.encoder_tree(),
            "predictor": {
                "_target_": f"{_P}.lewm.module.Predictor",
                "num_frames": self.history_size,
                "input_dim": d,
                "hidden_dim": d,
                "output_dim": d,
                **self.transformer_sizes(),
            },
            "action_encoder": {
                "_target_": f"{_P}.lewm.module.Embedder",
                "input_dim": self.frameskip * int(action_dim),
                "emb_dim": d,
            },
        }
        if self.projector_hidden:
            tree["projector"] = self._mlp(enc, d, self.projector_hidden)
            tree["pred_proj"] = self._mlp(d, d, self.projector_hidden)
        elif enc != d:
            raise ConfigError(
                f"{type(self).__name__} requires projector_hidden > 0 when the encoder width {enc} != embed_dim {d}"
            )
        tree.update(self.model_kwargs(action_dim))
        return tree

    def model_kwargs(self, action_dim: int) -> dict[str, Any]:
        """Extra keyword arguments of the model class (training knobs; the observed key of a state-input model)."""
        kwargs: dict[str, Any] = {"num_preds": self.num_preds, "history_size": self.history_size}
        if self.rollout_steps:  # absent by default: the config a checkpoint keeps stays upstream's
            kwargs["rollout_steps"] = self.rollout_steps
        if self.encoder == "state":
            kwargs["obs_key"] = self.state_key
        return kwargs

"""Light configuration of the JEPA world models (no torch import): sizes, data protocol and
training recipe, with named presets. A config renders the ``_target_`` tree that builds the
model (:meth:`JEPAConfig.target_tree`), which is also what ``config.json`` of a checkpoint holds.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from typing import Any, ClassVar

from ..errors import ConfigError, did_you_mean

__all__ = ["JEPAConfig", "IMAGENET_MEAN", "IMAGENET_STD", "VIT_SIZES", "GOAL_COSTS", "parse_override"]

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
        raise ConfigError(f"A config override requires KEY=VALUE (a config field of the model, e.g. proprio_dim=2), got {text!r}")
    try:
        return key.strip(), json.loads(raw)
    except json.JSONDecodeError:
        return key.strip(), raw

@dataclass
class JEPAConfig:
    """Sizes and recipe of a JEPA world model (LeWM, PLDM).

    Model: ``encoder`` ("cnn" or "vit"), ``image_size``, ``embed_dim`` (D), CNN ``cnn_width``,
    ViT ``vit_size`` / ``patch_size`` / ``vit_overrides`` (ViTConfig fields), predictor
    ``depth`` / ``heads`` / ``dim_head`` / ``mlp_dim`` / ``dropout``, ``projector_hidden``
    (0: no projector heads). Data protocol: ``history_size`` context frames and
    ``num_preds`` predicted frames per sample (``num_steps = history_size + num_preds``),
    ``frameskip`` env steps per frame (the action block), ``image_mean`` / ``image_std``.
    Training: ``batch_size``, ``lr``, ``weight_decay``, ``warmup_steps``, ``steps``,
    ``grad_clip``, ``val_fraction``, ``encoder_lr_scale``.
    """

    model_name: ClassVar[str] = ""
    target: ClassVar[str] = ""
    presets: ClassVar[dict[str, dict[str, Any]]] = {}
    #: how ``swm eval --policy <prefix>:RUN`` uses a checkpoint: ``wm`` plans with it, ``gc`` acts with it
    eval_prefix: ClassVar[str] = "wm"

    encoder: str = "cnn"
    image_size: int = 64
    embed_dim: int = 64
    cnn_width: int = 8
    vit_size: str = "tiny"
    patch_size: int = 8
    vit_overrides: dict[str, Any] = field(default_factory=dict)
    depth: int = 2
    heads: int = 4
    dim_head: int = 16
    mlp_dim: int = 256
    dropout: float = 0.0
    projector_hidden: int = 256
    history_size: int = 1
    num_preds: int = 1
    frameskip: int = 5
    image_mean: tuple[float, ...] = (0.5, 0.5, 0.5)
    image_std: tuple[float, ...] = (0.5, 0.5, 0.5)
    batch_size: int = 64
    lr: float = 1e-3
    weight_decay: float = 1e-3
    warmup_steps: int = 100
    steps: int = 2000
    grad_clip: float = 1.0
    val_fraction: float = 0.1
    encoder_lr_scale: float = 1.0

    def __post_init__(self) -> None:
        name = type(self).__name__
        if self.encoder not in ("cnn", "vit"):
            raise ConfigError(f"{name} requires encoder 'cnn' or 'vit', got {self.encoder!r}.{did_you_mean(self.encoder, ['cnn', 'vit'])}")
        for key in ("image_size", "embed_dim", "cnn_width", "patch_size", "depth", "heads", "dim_head", "mlp_dim",
                    "history_size", "num_preds", "frameskip", "batch_size", "steps"):
            value = getattr(self, key)
            if isinstance(value, bool) or not isinstance(value, int) or value < 1:
                raise ConfigError(f"{name} requires {key} to be a positive int, got {value!r}")
        for key in ("projector_hidden", "warmup_steps"):
            value = getattr(self, key)
            if isinstance(value, bool) or not isinstance(value, int) or value < 0:
                raise ConfigError(f"{name} requires {key} to be an int >= 0, got {value!r}")
        if not 0.0 < self.lr < 1.0 or self.weight_decay < 0 or self.grad_clip < 0:
            raise ConfigError(f"{name} requires 0 < lr < 1, weight_decay >= 0 and grad_clip >= 0, got {self.lr}, {self.weight_decay}, {self.grad_clip}")
        if not 0.0 <= self.val_fraction < 1.0:
            raise ConfigError(f"{name} requires 0 <= val_fraction < 1, got {self.val_fraction!r}")
        if not 0.0 <= self.dropout < 1.0:
            raise ConfigError(f"{name} requires 0 <= dropout < 1, got {self.dropout!r}")
        if self.encoder == "vit" and self.vit_size not in VIT_SIZES:
            raise ConfigError(f"{name} requires vit_size in {sorted(VIT_SIZES)}, got {self.vit_size!r}.{did_you_mean(self.vit_size, VIT_SIZES)}")
        self.image_mean, self.image_std = tuple(self.image_mean), tuple(self.image_std)

    @property
    def num_steps(self) -> int:
        """Frames per training sample: ``history_size + num_preds``."""
        return self.history_size + self.num_preds

    @classmethod
    def from_preset(cls, preset: str = "tiny", **overrides: Any) -> JEPAConfig:
        """The config of ``preset`` with ``overrides`` (unknown fields get a "did you mean" error)."""
        if preset not in cls.presets:
            raise ConfigError(f"{cls.model_name} requires preset in {sorted(cls.presets)}, got {preset!r}.{did_you_mean(preset, cls.presets)}")
        names = {f.name for f in dataclasses.fields(cls)}
        for key in overrides:
            if key not in names:
                raise ConfigError(f"{cls.__name__} has no field {key!r}.{did_you_mean(key, names)} Fields: {', '.join(sorted(names))}")
        return cls(**{**cls.presets[preset], **overrides})

    def to_dict(self) -> dict[str, Any]:
        return dataclasses.asdict(self)

    # -- the model as a _target_ tree -----------------------------------------------------------
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
        return {"_target_": f"{_P}.encoders.ConvEncoder", "image_size": self.image_size, "width": self.cnn_width, "hidden_size": self.encoder_dim}

    @property
    def encoder_dim(self) -> int:
        """Width of the encoder's output token."""
        if self.encoder == "vit":
            return int(self.vit_overrides.get("hidden_size", VIT_SIZES[self.vit_size]["hidden_size"]))
        return self.embed_dim

    def transformer_sizes(self) -> dict[str, Any]:
        """The predictor transformer's size arguments (``depth``, ``heads``, ``mlp_dim``, ``dim_head``, dropouts)."""
        return {"depth": self.depth, "heads": self.heads, "mlp_dim": self.mlp_dim, "dim_head": self.dim_head,
                "dropout": self.dropout, "emb_dropout": 0.0}

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
            "action_encoder": {"_target_": f"{_P}.lewm.module.Embedder", "input_dim": self.frameskip * int(action_dim), "emb_dim": d},
        }
        if self.projector_hidden:
            tree["projector"] = self._mlp(enc, d, self.projector_hidden)
            tree["pred_proj"] = self._mlp(d, d, self.projector_hidden)
        elif enc != d:
            raise ConfigError(f"{type(self).__name__} requires projector_hidden > 0 when the encoder width {enc} != embed_dim {d}")
        tree.update(self.model_kwargs(action_dim))
        return tree

    def model_kwargs(self, action_dim: int) -> dict[str, Any]:
        """Extra keyword arguments of the model class (training knobs)."""
        return {"num_preds": self.num_preds, "history_size": self.history_size}

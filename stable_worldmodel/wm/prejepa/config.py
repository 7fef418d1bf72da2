"""PreJEPA's (DINO-WM's) light config and presets (no torch import)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, ClassVar

from ... import keys
from ...errors import ConfigError
from ..backbones import BACKBONES, LOCAL_FAMILIES, backbone_spec
from ..base import check_positive_int
from ..config import IMAGENET_MEAN, IMAGENET_STD, PredictorConfig

__all__ = ["PreJEPAConfig"]

_P = "stable_worldmodel.wm"
_EMBEDDER = f"{_P}.prejepa.module.Embedder"


@dataclass
class PreJEPAConfig(PredictorConfig):
    """:class:`~stable_worldmodel.wm.config.PredictorConfig` for DINO-WM.

    Encoder (frozen): ``backbone`` (a name of :func:`~stable_worldmodel.wm.backbones.list_backbones`),
    ``pretrained`` (load its weights from ``backbone_path`` or ``$STABLEWM_HOME/backbones/``;
    never downloaded), ``backbone_overrides`` (transformers config fields of a randomly
    initialised backbone). With ``backbone="cnn"`` or ``"cnn_aa"`` (the random anti-aliased CNN,
    :class:`~stable_worldmodel.wm.prejepa.module.AntialiasedPatchCNN`): ``embed_dim`` is the token
    width, ``cnn_width`` the first conv's channels and ``cnn_grid`` the side of the patch grid. With
    ``backbone="blur"`` (:class:`~stable_worldmodel.wm.prejepa.module.BlurPatchEncoder`): the
    image blurred by ``blur_sigma`` pixels (0: ``image_size / 8``), pooled by ``blur_pool``, in
    ``cnn_grid`` x ``cnn_grid`` tokens (``embed_dim`` unused: the width follows).
    Extra inputs: ``action_emb_dim`` (width of the action embedding), ``proprio_dim``
    (numbers of the dataset's ``proprio`` column; 0: pixels only) and ``proprio_emb_dim``.
    Predictor: ``depth``, ``heads``, ``dim_head``, ``mlp_dim``, ``dropout`` over
    ``history_size`` frames.

    Presets: ``tiny`` (64x64, the randomly initialised anti-aliased CNN ``cnn_aa`` with 2 x 2
    tokens of 64 values, one context frame, a 2-layer predictor: a CPU trains it in under a
    minute from cached features and plans in ~5 s per CEM plan of 10 envs; 16 tokens and
    3 frames plan 9x slower; a plain strided random CNN or ViT there scores the agent's steps
    towards the goal no better than chance, see ``AntialiasedPatchCNN``), ``small`` (pretrained DINOv2 ViT-S/14 at
    112x112, 64 patches, a 4-layer predictor: one GPU) and ``paper`` (upstream's DINO-WM
    recipe: pretrained DINOv2 ViT-S/14 at 224x224, 256 patches, predictor depth 6 with 16
    heads of 64 and MLP 2048, action and proprio embeddings of 10, frameskip 5, history 3).
    """

    model_name: ClassVar[str] = "prejepa"
    target: ClassVar[str] = f"{_P}.prejepa.PreJEPA"
    presets: ClassVar[dict[str, dict[str, Any]]] = {
        "tiny": {
            "backbone": "cnn_aa",
            "pretrained": False,
            "image_size": 64,
            "cnn_width": 16,
            "embed_dim": 64,
            "cnn_grid": 2,
            "depth": 2,
            "heads": 4,
            "dim_head": 16,
            "mlp_dim": 128,
            "batch_size": 32,
            "lr": 1e-3,
            "warmup_steps": 50,
            "steps": 1000,
            "history_size": 1,
        },
        "small": {
            "backbone": "dinov2_small",
            "pretrained": True,
            "image_size": 112,
            "depth": 4,
            "heads": 8,
            "dim_head": 32,
            "mlp_dim": 1024,
            "image_mean": IMAGENET_MEAN,
            "image_std": IMAGENET_STD,
            "batch_size": 64,
            "lr": 5e-4,
            "steps": 20000,
        },
        "paper": {
            "backbone": "dinov2_small",
            "pretrained": True,
            "image_size": 224,
            "depth": 6,
            "heads": 16,
            "dim_head": 64,
            "mlp_dim": 2048,
            "dropout": 0.1,
            "image_mean": IMAGENET_MEAN,
            "image_std": IMAGENET_STD,
            "batch_size": 32,
            "lr": 5e-4,
            "warmup_steps": 1000,
            "steps": 100000,
        },
    }

    #: planning may aim at waypoints (without proprio: see :meth:`subgoal_graph_unavailable`)
    subgoal_graph: ClassVar[bool] = True

    FIELD_HELP: ClassVar[dict[str, str]] = {
        "backbone": "Frozen image encoder: a name of wm.backbones.list_backbones() (cnn_aa, blur, dinov2_small...).",
        "embed_dim": "Token width of the cnn and cnn_aa backbones.",
        "cnn_width": "Channels of the cnn / cnn_aa backbone's first conv.",
        "backbone_path": "File or folder of the backbone's weights (default: $STABLEWM_HOME/backbones/).",
        "pretrained": "Load the backbone's pretrained weights from disk (never downloaded); else random.",
        "backbone_overrides": "transformers config fields of a randomly initialised backbone.",
        "cnn_grid": "Side of the token grid of the cnn, cnn_aa and blur backbones (cnn_grid**2 tokens).",
        "blur_sigma": "Blur of the blur backbone, in pixels (0: image_size / 8).",
        "blur_pool": "Pooling factor of the blur backbone.",
        "action_emb_dim": "Width of the action embedding appended to each token.",
        "proprio_dim": "Numbers of the dataset's proprio column the model reads (0: pixels only).",
        "proprio_emb_dim": "Width of the proprio embedding appended to each token.",
        "interpolate_pos_encoding": "Interpolate a ViT backbone's position embeddings to image_size.",
    }

    backbone: str = "cnn"
    embed_dim: int = 64
    cnn_width: int = 8
    backbone_path: str | None = None
    pretrained: bool = False
    backbone_overrides: dict[str, Any] = field(default_factory=dict)
    cnn_grid: int = 4
    blur_sigma: float = 0.0
    blur_pool: int = 8
    action_emb_dim: int = 10
    proprio_dim: int = 0
    proprio_emb_dim: int = 10
    interpolate_pos_encoding: bool = True
    history_size: int = 3

    def __post_init__(self) -> None:
        super().__post_init__()
        name = type(self).__name__
        backbone_spec(self.backbone)  # an unknown name gets the "did you mean" error
        for key in ("embed_dim", "cnn_width", "cnn_grid", "blur_pool", "action_emb_dim", "proprio_emb_dim"):
            check_positive_int(name, key, getattr(self, key))
        if isinstance(self.blur_sigma, bool) or not isinstance(self.blur_sigma, (int, float)) or self.blur_sigma < 0:
            raise ConfigError(f"{name} requires blur_sigma >= 0 (pixels; 0: image_size / 8), got {self.blur_sigma!r}")
        check_positive_int(name, "proprio_dim", self.proprio_dim, minimum=0)
        if not isinstance(self.pretrained, bool):
            raise ConfigError(f"{name} requires pretrained to be a bool, got {self.pretrained!r}")
        local = backbone_spec(self.backbone).family in LOCAL_FAMILIES
        if local and self.pretrained:
            raise ConfigError(
                f"{name} requires pretrained=False with backbone {self.backbone!r} "
                "(it has no pretrained weights), got True"
            )
        if self.backbone == "blur" and self.image_size % (self.blur_pool * self.cnn_grid):
            raise ConfigError(
                f"{name} requires image_size divisible by blur_pool * cnn_grid with backbone 'blur', got "
                f"image_size={self.image_size}, blur_pool={self.blur_pool}, cnn_grid={self.cnn_grid}"
            )
        if not local and self.image_size < self.backbone_patch:
            raise ConfigError(
                f"{name} requires image_size >= the backbone's patch size {self.backbone_patch}, got {self.image_size}"
            )

    @property
    def extra_columns(self) -> dict[str, int]:
        """``proprio`` (its width) when ``proprio_dim > 0``."""
        return {keys.PROPRIO: self.proprio_dim} if self.proprio_dim else {}

    @classmethod
    def subgoal_graph_unavailable(cls, config: Any) -> str | None:
        if (config or {}).get("proprio_dim"):
            return "a PreJEPA with proprio scores more than its patch features"
        return None

    # -- sizes --------------------------------------------------------------------------------
    @property
    def backbone_patch(self) -> int:
        return int(self.backbone_overrides.get("patch_size", BACKBONES[self.backbone].patch_size))

    @property
    def encoder_dim(self) -> int:
        """Width ``Dv`` of the backbone's tokens."""
        spec = backbone_spec(self.backbone)
        if spec.family in ("cnn", "cnn_aa"):
            return self.embed_dim
        if spec.family == "blur":
            return 3 * (self.image_size // (self.blur_pool * self.cnn_grid)) ** 2
        if spec.family == "resnet" and "hidden_sizes" in self.backbone_overrides:
            return int(self.backbone_overrides["hidden_sizes"][-1])
        return int(self.backbone_overrides.get("hidden_size", spec.width))

    @property
    def num_patches(self) -> int:
        """Tokens per frame ``P``: the CNN's grid, one for a ResNet, (image_size // patch)**2 for a ViT."""
        spec = backbone_spec(self.backbone)
        if spec.family in LOCAL_FAMILIES:
            return self.cnn_grid**2
        if spec.family == "resnet":
            return 1
        return (self.image_size // self.backbone_patch) ** 2

    # -- the model as a _target_ tree -----------------------------------------------------------
    def encoder_tree(self) -> dict[str, Any]:
        if self.backbone in ("cnn", "cnn_aa"):
            backbone = {
                "name": self.backbone,
                "image_size": self.image_size,
                "width": self.cnn_width,
                "hidden_size": self.embed_dim,
                "grid": self.cnn_grid,
            }
        elif self.backbone == "blur":
            backbone = {
                "name": "blur",
                "image_size": self.image_size,
                "sigma": float(self.blur_sigma),
                "pool": self.blur_pool,
                "grid": self.cnn_grid,
            }
        else:
            backbone = {
                "name": self.backbone,
                "path": self.backbone_path,
                "pretrained": self.pretrained,
                **self.backbone_overrides,
            }
        frozen = {"_target_": f"{_P}.backbones.create_backbone", **backbone}
        return {"_target_": f"{_P}.gcrl.module.EvalOnly", "backbone": frozen}

    def target_tree(self, action_dim: int) -> dict[str, Any]:
        """The ``_target_`` tree of the model for env actions of ``action_dim`` numbers."""
        extras: dict[str, Any] = {}
        if self.proprio_dim:
            extras["proprio"] = {"_target_": _EMBEDDER, "in_chans": self.proprio_dim, "emb_dim": self.proprio_emb_dim}
        extras["action"] = {
            "_target_": _EMBEDDER,
            "in_chans": self.frameskip * int(action_dim),
            "emb_dim": self.action_emb_dim,
        }
        dim = self.encoder_dim + sum(e["emb_dim"] for e in extras.values())
        return {
            "_target_": self.target,
            "encoder": self.encoder_tree(),
            "predictor": {
                "_target_": f"{_P}.prejepa.module.CausalPredictor",
                "num_patches": self.num_patches,
                "num_frames": self.history_size,
                "dim": dim,
                **self.transformer_sizes(),
            },
            "extra_encoders": extras,
            "history_size": self.history_size,
            "num_pred": self.num_preds,
            "interpolate_pos_encoding": self.interpolate_pos_encoding
            and backbone_spec(self.backbone).family != "resnet",
        }

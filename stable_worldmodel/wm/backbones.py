"""Frozen image backbones by name: ``create_backbone(name, path=None, pretrained=True)``.

The names are upstream 0.1.1's aliases (``dinov2_small`` -> ``facebook/dinov2-small`` ...)
plus ``cnn``, our small patch CNN, ``cnn_aa``, a random anti-aliased patch CNN (the ``tiny``
preset's frozen encoder), and ``blur``, the blurred picture as patch tokens (no weights). Every backbone is called as
``backbone(pixels (N, C, h, w), [interpolate_pos_encoding=True])`` and returns
``last_hidden_state (N, 1 + P, D)`` (token 0 a CLS-like summary, then ``P`` patch tokens),
except the ResNet family, which returns ``logits (N, D)`` (upstream's classifier head with
its last layer replaced by a ``LayerNorm``).

Nothing is downloaded. Pretrained weights come from ``path`` (a folder written by
``save_pretrained`` / ``huggingface-cli download --local-dir``, or a weights file with a
``config.json`` beside it), else from ``$STABLEWM_HOME/backbones/<org>--<model>/``; when
neither exists, :class:`~stable_worldmodel.errors.ConfigError` says where to put the files.
``pretrained=False`` builds a randomly initialised model of the same architecture
(``config_overrides`` change its config, e.g. ``hidden_size=8`` for a test model).
``torch`` and ``transformers`` are imported on call, so this module is cheap to import.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ..errors import ConfigError, unknown_name
from .trust import checkpoint_factory

__all__ = ["BACKBONES", "BACKBONE_ALIASES", "BackboneSpec", "backbone_dir", "create_backbone", "list_backbones"]


@dataclass(frozen=True)
class BackboneSpec:
    """What a config needs to know about a backbone without building it: the hub id, the
    family (which transformers classes build it), the token width and the patch size (0: one
    token per image)."""

    hub_id: str | None
    family: str
    width: int
    patch_size: int


# fmt: off
BACKBONES: dict[str, BackboneSpec] = {
    "cnn":               BackboneSpec(None, "cnn", 0, 0),
    "cnn_aa":            BackboneSpec(None, "cnn_aa", 0, 0),
    "blur":              BackboneSpec(None, "blur", 0, 0),
    "dinov2_small":      BackboneSpec("facebook/dinov2-small", "dinov2", 384, 14),
    "dinov2_base":       BackboneSpec("facebook/dinov2-base", "dinov2", 768, 14),
    "dinov2_large":      BackboneSpec("facebook/dinov2-large", "dinov2", 1024, 14),
    "dinov2_giant":      BackboneSpec("facebook/dinov2-giant", "dinov2", 1536, 14),
    "dinov3_small":      BackboneSpec("facebook/dinov3-vits16-pretrain-lvd1689m", "dinov3", 384, 16),
    "dino_vits16":       BackboneSpec("facebook/dino-vits16", "dino", 384, 16),
    "dino_vits8":        BackboneSpec("facebook/dino-vits8", "dino", 384, 8),
    "dino_vitb16":       BackboneSpec("facebook/dino-vitb16", "dino", 768, 16),
    "dino_vitb8":        BackboneSpec("facebook/dino-vitb8", "dino", 768, 8),
    "mae_base":          BackboneSpec("facebook/vit-mae-base", "mae", 768, 16),
    "mae_large":         BackboneSpec("facebook/vit-mae-large", "mae", 1024, 16),
    "mae_huge":          BackboneSpec("facebook/vit-mae-huge", "mae", 1280, 14),
    "ijepa_huge":        BackboneSpec("facebook/ijepa-huge-patch14-224", "ijepa", 1280, 14),
    "webssl_large":      BackboneSpec("facebook/webssl-vith14-5b", "webssl", 1280, 14),
    "vit_base_patch16":  BackboneSpec("google/vit-base-patch16-224", "vit", 768, 16),
    "vit_large_patch16": BackboneSpec("google/vit-large-patch16-224", "vit", 1024, 16),
    "siglip2_base_224":  BackboneSpec("google/siglip2-base-patch16-224", "siglip2", 768, 16),
    "siglip2_large_256": BackboneSpec("google/siglip2-large-patch16-256", "siglip2", 1024, 16),
    "resnet_50":         BackboneSpec("microsoft/resnet-50", "resnet", 2048, 0),
    "resnet_101":        BackboneSpec("microsoft/resnet-101", "resnet", 2048, 0),
}
# fmt: on

#: families built here without transformers or weights files (``config_overrides`` are constructor arguments)
LOCAL_FAMILIES = ("cnn", "cnn_aa", "blur")

#: upstream's alias -> hub id table
BACKBONE_ALIASES = {name: spec.hub_id for name, spec in BACKBONES.items() if spec.hub_id}

#: random-init architectures of the families whose config class has no size presets:
#: transformers config fields per alias (the defaults of the config class otherwise)
_SIZES = {
    "dinov2_small": {"hidden_size": 384, "num_hidden_layers": 12, "num_attention_heads": 6},
    "dinov2_large": {"hidden_size": 1024, "num_hidden_layers": 24, "num_attention_heads": 16},
    "dinov2_giant": {"hidden_size": 1536, "num_hidden_layers": 40, "num_attention_heads": 24, "use_swiglu_ffn": True},
    "dino_vits16": {"hidden_size": 384, "num_attention_heads": 6, "intermediate_size": 1536},
    "dino_vits8": {"hidden_size": 384, "num_attention_heads": 6, "intermediate_size": 1536, "patch_size": 8},
    "dino_vitb8": {"patch_size": 8},
    "vit_large_patch16": {
        "hidden_size": 1024,
        "num_hidden_layers": 24,
        "num_attention_heads": 16,
        "intermediate_size": 4096,
    },
    "resnet_101": {"depths": [3, 4, 23, 3]},
}
#: family -> (transformers config class, model class) for random initialisation
_RANDOM_INIT = {
    "dinov2": ("Dinov2Config", "Dinov2Model"),
    "dino": ("ViTConfig", "ViTModel"),
    "vit": ("ViTConfig", "ViTModel"),
    "resnet": ("ResNetConfig", "ResNetForImageClassification"),
}


def list_backbones() -> list[str]:
    """Backbone names accepted by :func:`create_backbone`."""
    return sorted(BACKBONES)


def _resolve(name: str) -> str:
    """The alias of ``name`` (an alias or a hub id of the table)."""
    if not isinstance(name, str):
        raise ConfigError(f"create_backbone requires a backbone name, got {name!r}")
    if name in BACKBONES:
        return name
    for alias, hub_id in BACKBONE_ALIASES.items():
        if hub_id == name:
            return alias
    raise unknown_name("backbone", name, [*BACKBONES, *BACKBONE_ALIASES.values()])


def backbone_spec(name: str) -> BackboneSpec:
    """The :class:`BackboneSpec` of ``name`` (an alias or its hub id)."""
    return BACKBONES[_resolve(name)]


def backbone_dir(name: str, cache_dir: str | os.PathLike | None = None) -> Path:
    """Where the pretrained files of ``name`` are looked for when no path is given:
    ``<cache>/backbones/<org>--<model>/`` (not created)."""
    from ..data import get_cache_dir

    spec = backbone_spec(name)
    root = Path(cache_dir).expanduser() if cache_dir is not None else get_cache_dir()
    return root / "backbones" / (spec.hub_id or name).replace("/", "--")


def _missing_weights(name: str, where: Path, spec: BackboneSpec) -> ConfigError:
    return ConfigError(
        f"create_backbone({name!r}, pretrained=True) requires local weights, got none at {where}. "
        f"Put the files of {spec.hub_id} (config.json and model.safetensors) in {where}/, e.g. "
        f"`huggingface-cli download {spec.hub_id} --local-dir {where}`, or pass path=<folder or weights file>; "
        "stable-worldmodel never downloads. Use pretrained=False for a randomly initialised backbone."
    )


def _post_init(model: Any, family: str) -> Any:
    """Upstream's adjustments: the vision tower of CLIP-like models, a LayerNorm head on ResNets."""
    from torch import nn

    if hasattr(model, "vision_model"):
        model = model.vision_model
    if family == "resnet":
        model.classifier[1] = nn.LayerNorm(model.config.hidden_sizes[-1])
    return model


def _model_class(transformers: Any, family: str) -> Any:
    return transformers.AutoModelForImageClassification if family == "resnet" else transformers.AutoModel


#: weight files that transformers' ``from_pretrained`` reads from their folder (renaming old layouts)
_HF_WEIGHTS = ("model.safetensors", "pytorch_model.bin")


def _from_file(transformers: Any, file: Path, family: str, overrides: dict[str, Any]) -> Any:
    """A model from a weights file with ``config.json`` beside it: a Hugging Face file
    (``model.safetensors``, ``pytorch_model.bin``) or a ``.pt`` state dict of the model."""
    import torch

    if not (file.parent / "config.json").is_file():
        raise ConfigError(
            f"create_backbone requires a config.json beside the weights file {file}, got none in {file.parent}"
        )
    model_class = _model_class(transformers, family)
    if file.name in _HF_WEIGHTS:
        return model_class.from_pretrained(str(file.parent), local_files_only=True, **overrides)
    if file.suffix != ".pt":
        raise ConfigError(
            f"create_backbone requires a weights file named {' or '.join(_HF_WEIGHTS)} or a .pt state dict, "
            f"got {file.name!r}"
        )
    model = model_class.from_config(transformers.AutoConfig.from_pretrained(str(file.parent), **overrides))
    state = torch.load(file, map_location="cpu", weights_only=True)
    missing, unexpected = model.load_state_dict(state, strict=False)
    if missing or unexpected:
        raise ConfigError(
            f"create_backbone: the weights {file} do not fit {model.config.model_type}: "
            f"missing {missing[:8]}, unexpected {unexpected[:8]}"
        )
    return model


def _random(transformers: Any, alias: str, spec: BackboneSpec, overrides: dict[str, Any]) -> Any:
    if spec.family not in _RANDOM_INIT:
        raise ConfigError(
            f"create_backbone({alias!r}, pretrained=False) requires a family among {sorted(_RANDOM_INIT)} "
            f"(or a path to a folder with its config.json), got family {spec.family!r}"
        )
    config_cls, _ = _RANDOM_INIT[spec.family]
    params = {**_SIZES.get(alias, {}), **overrides}
    if spec.family == "resnet":
        config = getattr(transformers, config_cls)(**params)
        return transformers.AutoModelForImageClassification.from_config(config)
    config = getattr(transformers, config_cls)(**params)
    return transformers.AutoModel.from_config(config)


@checkpoint_factory
def create_backbone(
    name: str,
    path: str | os.PathLike | None = None,
    pretrained: bool = True,
    *,
    cache_dir: str | os.PathLike | None = None,
    **config_overrides: Any,
) -> Any:
    """Build backbone ``name`` (see :func:`list_backbones`; hub ids of the table work too).

    ``pretrained=True`` loads weights from ``path`` (a folder or a weights file) or from
    :func:`backbone_dir`; a missing folder is a :class:`ConfigError` naming where to put
    the files. ``pretrained=False`` (or ``path`` with only a ``config.json``) gives random
    weights. ``config_overrides`` go into the model's config (the CNN's constructor for
    ``cnn``). The model is returned with upstream's adjustments (vision tower of CLIP-like
    models, LayerNorm head on ResNets); freezing it is the caller's job.
    """
    if "trust_remote_code" in config_overrides:  # it would run Python files of the weights folder
        raise ConfigError(
            "create_backbone refuses trust_remote_code: backbones are built from transformers' own classes, "
            f"got trust_remote_code={config_overrides['trust_remote_code']!r}"
        )
    alias = _resolve(name)
    spec = BACKBONES[alias]
    if spec.family in LOCAL_FAMILIES:
        from .prejepa import module

        local = {"cnn": module.PatchConvEncoder, "cnn_aa": module.AntialiasedPatchCNN, "blur": module.BlurPatchEncoder}
        return local[spec.family](**config_overrides)
    from .._optional import require

    transformers = require("transformers", extra="vit", purpose=f"the {alias} backbone")
    if path is not None:
        where = Path(path).expanduser()
        if not where.exists():
            raise ConfigError(
                f"create_backbone({alias!r}) requires an existing folder or weights file, got path={str(path)!r}"
            )
    else:
        where = backbone_dir(alias, cache_dir)
    if not pretrained:
        if path is not None and (where / "config.json").is_file():
            config = transformers.AutoConfig.from_pretrained(str(where), **config_overrides)
            return _post_init(_model_class(transformers, spec.family).from_config(config), spec.family)
        return _post_init(_random(transformers, alias, spec, config_overrides), spec.family)
    if where.is_file():
        return _post_init(_from_file(transformers, where, spec.family, config_overrides), spec.family)
    if not (where / "config.json").is_file():
        raise _missing_weights(alias, where, spec)
    model = _model_class(transformers, spec.family).from_pretrained(
        str(where), local_files_only=True, **config_overrides
    )
    return _post_init(model, spec.family)

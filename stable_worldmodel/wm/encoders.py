"""Image encoders with the interface the JEPA models call:
``encoder(pixels (N, C, h, w), interpolate_pos_encoding=...) -> out.last_hidden_state (N, L, D)``.

- :func:`vit_hf`: the Hugging Face ``transformers.ViTModel`` (no pooler) that upstream's
  configs build through ``stable_pretraining.backbone.utils.vit_hf``; same sizes, same
  parameter names, so upstream checkpoints load. ``transformers`` is imported on call.
- :class:`ConvEncoder`: a small strided CNN for CPU presets (one token, ``L = 1``).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from types import SimpleNamespace
from typing import Any

import torch
from torch import nn

from .._optional import require
from ..errors import ConfigError, SpaceError, did_you_mean
from .config import VIT_SIZES
from .trust import checkpoint_factory

__all__ = ["VIT_SIZES", "ConvEncoder", "EncoderOutput", "vit_hf"]


@checkpoint_factory
def vit_hf(
    size: str = "tiny",
    patch_size: int = 16,
    image_size: int = 224,
    pretrained: bool = False,
    use_mask_token: bool = True,
    **vit_config_overrides: Any,
) -> nn.Module:
    """A ``transformers.ViTModel(ViTConfig(...), add_pooling_layer=False)`` of ``size``.

    ``vit_config_overrides`` go into the ``ViTConfig`` (e.g. ``num_hidden_layers=2`` for a
    tiny test model); ``interpolate_pos_encoding`` is enabled so other image sizes work.
    ``pretrained=True`` is refused: nothing is downloaded; build with ``pretrained=False``
    and load weights with :func:`stable_worldmodel.wm.utils.load_pretrained`.
    """
    if size not in VIT_SIZES:
        raise ConfigError(f"vit_hf requires size in {sorted(VIT_SIZES)}, got {size!r}.{did_you_mean(size, VIT_SIZES)}")
    if pretrained:
        raise ConfigError(
            "vit_hf(pretrained=True) would download ImageNet weights, which stable-worldmodel never does; "
            "use pretrained=False and load a checkpoint (weights.pt + config.json) from $STABLEWM_HOME/checkpoints"
        )
    transformers = require("transformers", extra="vit", purpose="ViT encoders")
    params: dict[str, Any] = dict(VIT_SIZES[size])
    params["intermediate_size"] = 4 * params["hidden_size"]
    params.update(image_size=int(image_size), patch_size=int(patch_size))
    params.update(vit_config_overrides)
    model = transformers.ViTModel(
        transformers.ViTConfig(**params), add_pooling_layer=False, use_mask_token=use_mask_token
    )
    model.config.interpolate_pos_encoding = True
    return model


@dataclass
class EncoderOutput:
    """What :class:`ConvEncoder` returns: ``last_hidden_state (N, 1, D)`` like a ViT's."""

    last_hidden_state: torch.Tensor

    def __getitem__(self, key: str) -> torch.Tensor:
        return getattr(self, key)


class ConvEncoder(nn.Module):
    """Strided CNN: ``(N, in_channels, image_size, image_size) -> last_hidden_state (N, 1, hidden_size)``.

    Each stage is a 4x4 stride-2 conv + GroupNorm + GELU (channels ``width * 2**i``, capped
    at ``8 * width``) until the map is at most 4x4, then flatten and a linear layer.
    ``config.hidden_size`` / ``config.image_size`` mirror a ViT's config.
    """

    def __init__(self, image_size: int = 64, in_channels: int = 3, width: int = 16, hidden_size: int = 64):
        super().__init__()
        for name, value in (
            ("image_size", image_size),
            ("in_channels", in_channels),
            ("width", width),
            ("hidden_size", hidden_size),
        ):
            if isinstance(value, bool) or not isinstance(value, int) or value < 1:
                raise ConfigError(f"ConvEncoder requires {name} to be a positive int, got {value!r}")
        if image_size < 8:
            raise ConfigError(f"ConvEncoder requires image_size >= 8, got {image_size}")
        self.config = SimpleNamespace(
            image_size=image_size, hidden_size=hidden_size, num_channels=in_channels, width=width
        )
        layers: list[nn.Module] = []
        channels, side, i = in_channels, image_size, 0
        while side > 4:
            out = width * min(2**i, 8)
            layers += [nn.Conv2d(channels, out, 4, stride=2, padding=1), nn.GroupNorm(max(1, out // 8), out), nn.GELU()]
            channels, side, i = out, side // 2, i + 1
        self.convs = nn.Sequential(*layers)
        self.head = nn.Linear(channels * side * side, hidden_size)

    def forward(self, pixels: torch.Tensor, interpolate_pos_encoding: bool = False, **kwargs: Any) -> EncoderOutput:
        size = self.config.image_size
        if pixels.ndim != 4 or pixels.shape[1] != self.config.num_channels or tuple(pixels.shape[-2:]) != (size, size):
            raise SpaceError(
                f"ConvEncoder requires images of shape (N, {self.config.num_channels}, {size}, {size}), "
                f"got {tuple(pixels.shape)}; resize them to {size}x{size} (the model's image_size)"
            )
        x = pixels.to(self.head.weight.dtype)
        if x.device.type == "cpu":
            # oneDNN's convolutions and GroupNorm run faster on channels-last maps: the LeWM `cpu` preset's training
            # step 1.18x on 2 threads, 1.08x on one (same loss; gradients within 4e-7). The weights stay as they are.
            x = x.contiguous(memory_format=torch.channels_last)
        return EncoderOutput(self.head(self.convs(x).flatten(1)).unsqueeze(1))


class StateEncoder(nn.Module):
    """MLP over a state vector: ``(N, input_dim) -> last_hidden_state (N, 1, hidden_size)``, the
    encoder of a JEPA that reads a dataset column (``state``, ``proprio``) instead of pixels.
    Linear, LayerNorm, GELU, Linear; ``config.hidden_size`` as a ViT's config.

    ``dims``: the entries of the vector it reads (default: all ``input_dim``), e.g. the poses of
    Push-T's state without the agent's velocity; the others do not reach the embedding, so the
    planner's latent distance ignores them."""

    def __init__(self, input_dim: int, hidden_size: int = 64, width: int = 256, dims: Sequence[int] | None = None):
        super().__init__()
        for name, value in (("input_dim", input_dim), ("hidden_size", hidden_size), ("width", width)):
            if isinstance(value, bool) or not isinstance(value, int) or value < 1:
                raise ConfigError(f"StateEncoder requires {name} to be a positive int, got {value!r}")
        dims = list(range(input_dim)) if dims is None or len(dims) == 0 else list(dims)
        bad = [d for d in dims if isinstance(d, bool) or not isinstance(d, int) or not 0 <= d < input_dim]
        if bad or len(set(dims)) != len(dims):
            raise ConfigError(
                f"StateEncoder requires dims to be distinct entries of its {input_dim}-number input "
                f"(0..{input_dim - 1}), got {dims!r}"
            )
        self.config = SimpleNamespace(input_dim=input_dim, hidden_size=hidden_size, width=width, dims=dims)
        self._all = dims == list(range(input_dim))
        self.register_buffer("_dims", torch.tensor(dims, dtype=torch.long), persistent=False)
        self.net = nn.Sequential(
            nn.Linear(len(dims), width), nn.LayerNorm(width), nn.GELU(), nn.Linear(width, hidden_size)
        )

    def forward(self, state: torch.Tensor, **kwargs: Any) -> EncoderOutput:
        if state.ndim != 2 or state.shape[1] != self.config.input_dim:
            raise SpaceError(
                f"StateEncoder requires states of shape (N, {self.config.input_dim}), got {tuple(state.shape)}"
            )
        picked = state if getattr(self, "_all", True) else state.index_select(1, self._dims)  # pickled before dims: all
        return EncoderOutput(self.net(picked).unsqueeze(1))

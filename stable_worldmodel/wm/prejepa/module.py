"""Building blocks of PreJEPA (DINO-WM), with upstream 0.1.1's constructor arguments and
``state_dict`` names, so its checkpoints load here.

- :class:`CausalPredictor`: a ViT over the ``T * P`` patch tokens of ``T`` frames whose
  attention is causal across frames (a token sees every patch of its own and earlier frames).
- :class:`Embedder`: a per-frame linear map (a 1-D conv) of actions or proprioception,
  ``(B, T, in_chans) -> (B, T, emb_dim)``.
- :class:`PatchConvEncoder`: a small CNN (``create_backbone("cnn")``),
  :class:`AntialiasedPatchCNN`: a random anti-aliased CNN (``create_backbone("cnn_aa")``, the ``tiny``
  preset's), and :class:`BlurPatchEncoder`: the blurred picture as patch tokens, without weights
  (``create_backbone("blur")``), all returning a ViT-like ``last_hidden_state (N, 1 + P, D)``.

Shapes: ``B`` batch, ``T`` frames, ``P`` patches per frame, ``D`` token width.
"""

from __future__ import annotations

from types import SimpleNamespace
from typing import Any

import torch
import torch.nn.functional as F
from torch import nn

from ...errors import ConfigError, SpaceError, check_int
from ..backbones import create_backbone  # noqa: F401  (upstream's configs name it here)
from ..encoders import EncoderOutput
from ..lewm.module import FeedForward

__all__ = [
    "AntialiasedPatchCNN",
    "Attention",
    "BlurPatchEncoder",
    "CausalPredictor",
    "Embedder",
    "create_backbone",
    "FeedForward",
    "PatchConvEncoder",
    "Transformer",
    "frame_causal_mask",
]


def frame_causal_mask(num_patches: int, num_frames: int) -> torch.Tensor:
    """``(1, 1, T * P, T * P)`` of ones where a token of frame ``i`` may attend to a token of
    frame ``j <= i``, zeros elsewhere."""
    frame = torch.arange(num_frames).repeat_interleave(num_patches)
    return (frame[None, :] <= frame[:, None]).float()[None, None]


class Embedder(nn.Module):
    """``(B, T, in_chans) -> (B, T, emb_dim)``: a Conv1d over time with kernel and stride
    ``tubelet_size`` (1: each frame mapped on its own), run in float32 outside autocast."""

    def __init__(self, num_frames: int = 1, tubelet_size: int = 1, in_chans: int = 8, emb_dim: int = 10):
        super().__init__()
        for key, value in (
            ("num_frames", num_frames),
            ("tubelet_size", tubelet_size),
            ("in_chans", in_chans),
            ("emb_dim", emb_dim),
        ):
            if isinstance(value, bool) or not isinstance(value, int) or value < 1:
                raise ConfigError(f"Embedder requires {key} to be a positive int, got {value!r}")
        self.num_frames, self.tubelet_size, self.in_chans, self.emb_dim = num_frames, tubelet_size, in_chans, emb_dim
        self.patch_embed = nn.Conv1d(in_chans, emb_dim, kernel_size=tubelet_size, stride=tubelet_size)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        if x.shape[-1] != self.in_chans:
            raise SpaceError(f"Embedder requires inputs (B, T, {self.in_chans}), got {tuple(x.shape)}")
        with torch.autocast(device_type=x.device.type, enabled=False):
            x = x.to(self.patch_embed.weight.dtype)
            if self.tubelet_size == 1:  # a kernel-1 conv is a linear map of the last dim
                return F.linear(x, self.patch_embed.weight.squeeze(-1), self.patch_embed.bias)
            return self.patch_embed(x.transpose(1, 2)).transpose(1, 2)


class Attention(nn.Module):
    """Pre-norm multi-head self-attention under the frame-causal mask (buffer ``bias``,
    upstream's name; it is part of the state dict)."""

    def __init__(
        self,
        dim: int,
        heads: int = 8,
        dim_head: int = 64,
        dropout: float = 0.0,
        num_patches: int = 1,
        num_frames: int = 1,
    ):
        super().__init__()
        inner = heads * dim_head
        self.heads, self.dim_head = heads, dim_head
        self.scale = dim_head**-0.5
        self.norm = nn.LayerNorm(dim)
        self.dropout = nn.Dropout(dropout)
        self.to_qkv = nn.Linear(dim, 3 * inner, bias=False)
        if heads == 1 and dim_head == dim:
            self.to_out: nn.Module = nn.Identity()
        else:
            self.to_out = nn.Sequential(nn.Linear(inner, dim), nn.Dropout(dropout))
        self.register_buffer("bias", frame_causal_mask(num_patches, num_frames))

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        b, n, _ = x.shape
        q, k, v = (
            t.view(b, n, self.heads, self.dim_head).transpose(1, 2) for t in self.to_qkv(self.norm(x)).chunk(3, dim=-1)
        )
        mask = self.bias[:, :, :n, :n] > 0.5
        p = self.dropout.p if self.training else 0.0
        out = F.scaled_dot_product_attention(q, k, v, attn_mask=mask, dropout_p=p)
        return self.to_out(out.transpose(1, 2).reshape(b, n, self.heads * self.dim_head))


class Transformer(nn.Module):
    """``depth`` residual (attention, MLP) pairs, then a LayerNorm. ``layers[i]`` is a
    ``ModuleList([Attention, FeedForward])`` (upstream's state-dict layout)."""

    def __init__(
        self,
        dim: int,
        depth: int,
        heads: int,
        dim_head: int,
        mlp_dim: int,
        dropout: float = 0.0,
        num_patches: int = 1,
        num_frames: int = 1,
    ):
        super().__init__()
        self.norm = nn.LayerNorm(dim)
        self.layers = nn.ModuleList(
            nn.ModuleList(
                [Attention(dim, heads, dim_head, dropout, num_patches, num_frames), FeedForward(dim, mlp_dim, dropout)]
            )
            for _ in range(depth)
        )

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        for attn, ff in self.layers:
            x = x + attn(x)
            x = x + ff(x)
        return self.norm(x)


class CausalPredictor(nn.Module):
    """Next-frame predictor over patch tokens.

    ``forward(x)``: ``x: (B, T * P, dim)``, the ``P`` tokens of each of ``T <= num_frames``
    frames in time order -> ``(B, T * P, dim)``, where the tokens of output frame ``t``
    predict frame ``t + 1`` from frames ``<= t``. Learned positions cover ``num_frames * num_patches`` tokens.
    """

    def __init__(
        self,
        *,
        num_patches: int,
        num_frames: int,
        dim: int,
        depth: int,
        heads: int,
        mlp_dim: int,
        pool: str = "cls",
        dim_head: int = 64,
        dropout: float = 0.0,
        emb_dropout: float = 0.0,
        **kwargs: Any,
    ):
        super().__init__()
        if pool not in ("cls", "mean"):
            raise ConfigError(f"CausalPredictor requires pool 'cls' or 'mean', got {pool!r}")
        for key, value in (
            ("num_patches", num_patches),
            ("num_frames", num_frames),
            ("dim", dim),
            ("depth", depth),
            ("heads", heads),
            ("mlp_dim", mlp_dim),
            ("dim_head", dim_head),
        ):
            if isinstance(value, bool) or not isinstance(value, int) or value < 1:
                raise ConfigError(f"CausalPredictor requires {key} to be a positive int, got {value!r}")
        self.num_patches, self.num_frames, self.pool = num_patches, num_frames, pool
        self.pos_embedding = nn.Parameter(torch.randn(1, num_frames * num_patches, dim))
        self.dropout = nn.Dropout(emb_dropout)
        self.transformer = Transformer(dim, depth, heads, dim_head, mlp_dim, dropout, num_patches, num_frames)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        n = x.shape[1]
        if n > self.pos_embedding.shape[1] or n % self.num_patches:
            raise SpaceError(
                f"CausalPredictor requires T * {self.num_patches} tokens with T <= num_frames={self.num_frames}, "
                f"got {n} tokens"
            )
        return self.transformer(self.dropout(x + self.pos_embedding[:, :n]))


def _positive_ints(owner: str, **values: Any) -> None:
    for key, value in values.items():
        check_int(owner, key, value)


def _halvings(owner: str, image_size: int, grid: int) -> int:
    """``k`` with ``image_size == grid * 2**k``; a ConfigError when there is none."""
    side, stages = image_size, 0
    while side > grid and side % 2 == 0:
        side, stages = side // 2, stages + 1
    if side != grid:
        raise ConfigError(f"{owner} requires image_size = grid * 2**k, got image_size={image_size}, grid={grid}")
    return stages


def _check_images(owner: str, pixels: torch.Tensor, config: Any) -> None:
    """SpaceError unless ``pixels`` is ``(N, config.num_channels, config.image_size, config.image_size)``."""
    size, c = config.image_size, config.num_channels
    if pixels.ndim != 4 or pixels.shape[1] != c or tuple(pixels.shape[-2:]) != (size, size):
        raise SpaceError(
            f"{owner} requires images (N, {c}, {size}, {size}), got {tuple(pixels.shape)}; "
            "resize them to the model's image_size"
        )


class PatchConvEncoder(nn.Module):
    """Small strided CNN with patch tokens: ``(N, in_channels, image_size, image_size) ->
    last_hidden_state (N, 1 + grid**2, hidden_size)``; token 0 is the mean of the patch tokens
    (where a ViT has its CLS token), so a model that drops token 0 sees ``grid**2`` patches.

    Each stage is a 4x4 stride-2 conv + GroupNorm + GELU (``width * 2**i`` channels, capped at
    ``4 * width``) until the map is ``grid`` x ``grid``, then a 1x1 conv to ``hidden_size``.
    """

    def __init__(
        self, image_size: int = 64, in_channels: int = 3, width: int = 16, hidden_size: int = 32, grid: int = 4
    ):
        super().__init__()
        _positive_ints(
            "PatchConvEncoder",
            image_size=image_size,
            in_channels=in_channels,
            width=width,
            hidden_size=hidden_size,
            grid=grid,
        )
        stages = _halvings("PatchConvEncoder", image_size, grid)
        self.config = SimpleNamespace(
            image_size=image_size, num_channels=in_channels, hidden_size=hidden_size, grid=grid, width=width
        )
        layers: list[nn.Module] = []
        channels = in_channels
        for i in range(stages):
            out = width * min(2**i, 4)
            layers += [nn.Conv2d(channels, out, 4, stride=2, padding=1), nn.GroupNorm(max(1, out // 8), out), nn.GELU()]
            channels = out
        self.convs = nn.Sequential(*layers)
        self.head = nn.Conv2d(channels, hidden_size, 1)

    def forward(self, pixels: torch.Tensor, interpolate_pos_encoding: bool = False, **kwargs: Any) -> EncoderOutput:
        _check_images("PatchConvEncoder", pixels, self.config)
        tokens = self.head(self.convs(pixels.to(self.head.weight.dtype))).flatten(2).transpose(1, 2)  # (N, P, D)
        return EncoderOutput(torch.cat([tokens.mean(1, keepdim=True), tokens], dim=1))


class _StandardizedTokens(nn.Module):
    """A frozen patch encoder whose token values are standardized by statistics of training
    frames: subclasses give ``_tokens(pixels) -> (N, P, D)`` and call :meth:`_init_standardization`;
    ``forward`` returns ``last_hidden_state (N, 1 + P, D)``, token 0 the mean of the patch tokens.

    :meth:`fit_to_frames` sets the buffers ``mean`` and ``scale`` (saved with the model;
    identity until fitted): a small agent moves such features by about 1e-3 of what the static
    scene spans, and a predictor that must reproduce both learns only the scene (measured with
    the blurred picture: the same loss with the true and with shuffled actions); standardized,
    the agent's moves are of order 1.
    """

    config: SimpleNamespace

    def _init_standardization(self, num_tokens: int, width: int) -> None:
        self.register_buffer("mean", torch.zeros(num_tokens, width))
        self.register_buffer("scale", torch.ones(num_tokens, width))

    def _tokens(self, pixels: torch.Tensor) -> torch.Tensor:
        raise NotImplementedError

    def forward(self, pixels: torch.Tensor, interpolate_pos_encoding: bool = False, **kwargs: Any) -> EncoderOutput:
        _check_images(type(self).__name__, pixels, self.config)
        tokens = (self._tokens(pixels) - self.mean) / self.scale
        return EncoderOutput(torch.cat([tokens.mean(1, keepdim=True), tokens], dim=1))

    @torch.no_grad()
    def fit_to_frames(self, pixels: torch.Tensor, floor: float = 1e-3) -> None:
        """Set ``mean`` and ``scale`` from preprocessed frames ``(N, C, H, W)`` (N >= 2): the
        standard deviation of each value, at least ``floor`` x the largest one (values the
        frames never change stay near 0 instead of blowing up)."""
        if pixels.ndim != 4 or len(pixels) < 2:
            raise SpaceError(
                f"{type(self).__name__}.fit_to_frames requires at least 2 frames (N, C, H, W), "
                f"got {tuple(pixels.shape)}"
            )
        _check_images(type(self).__name__, pixels[:1], self.config)
        tokens = torch.cat([self._tokens(pixels[i : i + 512]) for i in range(0, len(pixels), 512)])
        std = tokens.std(0)
        self.mean.copy_(tokens.mean(0))
        self.scale.copy_(std.clamp_min(floor * float(std.max().clamp_min(1e-12))))


class BlurPatchEncoder(_StandardizedTokens):
    """A fixed (weightless) patch encoder: the picture itself, blurred. ``(N, in_channels,
    image_size, image_size) -> last_hidden_state (N, 1 + grid**2, in_channels * (image_size //
    (pool * grid))**2)``; token 0 is the mean of the patch tokens.

    The image is blurred with a Gaussian of ``sigma`` pixels (0: ``image_size / 8``), average-pooled
    by ``pool`` and cut into ``grid`` x ``grid`` cells, each cell's values a token. Distances between
    such features grow smoothly with how far apart small objects are, which a plain randomly
    initialised CNN or ViT does not give (their feature distance is about as likely to fall as to
    rise when the agent steps towards the goal). It was the ``tiny`` preset's encoder before
    :class:`AntialiasedPatchCNN`, which plans at least as well on TwoRoom (86% against 82%).

    :meth:`fit_to_frames` standardizes each token value by its mean and spread over training
    frames (see :class:`_StandardizedTokens`).
    """

    def __init__(self, image_size: int = 64, in_channels: int = 3, sigma: float = 0.0, pool: int = 8, grid: int = 2):
        super().__init__()
        _positive_ints("BlurPatchEncoder", image_size=image_size, in_channels=in_channels, pool=pool, grid=grid)
        if isinstance(sigma, bool) or not isinstance(sigma, (int, float)) or sigma < 0:
            raise ConfigError(f"BlurPatchEncoder requires sigma >= 0 (pixels; 0: image_size / 8), got {sigma!r}")
        if image_size % (pool * grid):
            raise ConfigError(
                f"BlurPatchEncoder requires image_size divisible by pool * grid, got image_size={image_size}, "
                f"pool={pool}, grid={grid}"
            )
        sigma = float(sigma) or image_size / 8
        radius = max(1, int(round(3 * sigma)))
        taps = torch.exp(-(torch.arange(-radius, radius + 1, dtype=torch.float32) ** 2) / (2 * sigma**2))
        self.register_buffer("taps", taps / taps.sum(), persistent=False)  # a function of the config: not in state_dict
        cell = image_size // (pool * grid)
        self._init_standardization(grid * grid, in_channels * cell * cell)
        self.config = SimpleNamespace(
            image_size=image_size,
            num_channels=in_channels,
            hidden_size=in_channels * cell * cell,
            grid=grid,
            pool=pool,
            sigma=sigma,
        )

    def _tokens(self, pixels: torch.Tensor) -> torch.Tensor:
        """Unstandardized patch tokens ``(N, grid**2, D)``."""
        c, grid = self.config.num_channels, self.config.grid
        x, k, r = pixels.to(self.taps.dtype), self.taps, len(self.taps) // 2
        x = F.conv2d(F.pad(x, (r, r, 0, 0), mode="replicate"), k.view(1, 1, 1, -1).expand(c, 1, 1, -1), groups=c)
        x = F.conv2d(F.pad(x, (0, 0, r, r), mode="replicate"), k.view(1, 1, -1, 1).expand(c, 1, -1, 1), groups=c)
        x = F.avg_pool2d(x, self.config.pool)  # (N, C, S, S)
        n, cell = x.shape[0], x.shape[-1] // grid
        return x.reshape(n, c, grid, cell, grid, cell).permute(0, 2, 4, 1, 3, 5).reshape(n, grid * grid, -1)


def binomial_taps(size: int) -> torch.Tensor:
    """The normalized binomial filter of ``size`` taps (``[1, 2, 1] / 4`` for 3), a
    discrete Gaussian of variance ``(size - 1) / 4``."""
    taps = torch.ones(1)
    for _ in range(size - 1):
        taps = F.pad(taps, (1, 0)) + F.pad(taps, (0, 1))
    return taps / taps.sum()


class AntialiasedPatchCNN(_StandardizedTokens):
    """A randomly initialised, anti-aliased CNN with patch tokens (``create_backbone("cnn_aa")``,
    the ``tiny`` preset's frozen encoder): ``(N, in_channels, image_size, image_size) ->
    last_hidden_state (N, 1 + grid**2, hidden_size)``; token 0 is the mean of the patch tokens.

    Each stage is a 3x3 conv + GroupNorm + GELU, then a fixed binomial low-pass of ``taps``
    taps and a stride of 2 ("blur pool", Zhang 2019, *Making convolutional networks
    shift-invariant again*), until the map is ``grid`` x ``grid``; then a 1x1 conv to
    ``hidden_size``; token values standardized over training frames (:meth:`fit_to_frames`).

    Why the low-pass: with random weights, a plain strided CNN's response to a small object
    changes unpredictably when the object moves by its own size, so the feature distance of
    two frames says nothing about how far apart the agent is in them (measured on TwoRoom: it
    falls on 55% of the expert's steps towards the goal, chance). Low-passing before every
    stride makes each stage's response move smoothly with the object, and the distance falls
    on ~70% of those steps, as much as for the blurred picture itself (72%; a trained encoder
    97%). Nothing here is learned but the standardization.

    The weights are drawn from ``seed`` (None: the caller's RNG), not from the training run's
    seed: every run with this config encodes a dataset alike, so they share its feature cache
    and differ only in what they train.
    """

    def __init__(
        self,
        image_size: int = 64,
        in_channels: int = 3,
        width: int = 16,
        hidden_size: int = 32,
        grid: int = 2,
        taps: int = 5,
        seed: int | None = 0,
    ):
        super().__init__()
        _positive_ints(
            "AntialiasedPatchCNN",
            image_size=image_size,
            in_channels=in_channels,
            width=width,
            hidden_size=hidden_size,
            grid=grid,
            taps=taps,
        )
        if seed is not None and (isinstance(seed, bool) or not isinstance(seed, int) or seed < 0):
            raise ConfigError(
                f"AntialiasedPatchCNN requires seed to be an int >= 0 or None (the global RNG), got {seed!r}"
            )
        stages = _halvings("AntialiasedPatchCNN", image_size, grid)
        self.config = SimpleNamespace(
            image_size=image_size,
            num_channels=in_channels,
            hidden_size=hidden_size,
            grid=grid,
            width=width,
            taps=taps,
            seed=seed,
        )
        self.register_buffer(
            "taps", binomial_taps(taps), persistent=False
        )  # a function of the config: not in state_dict
        self.stages = nn.ModuleList()
        with torch.random.fork_rng(devices=[]):  # the weights are a function of the config, whatever the caller's RNG
            if seed is not None:
                torch.manual_seed(seed)
            channels = in_channels
            for i in range(stages):
                out = width * min(2**i, 4)
                self.stages.append(
                    nn.Sequential(
                        nn.Conv2d(channels, out, 3, padding=1), nn.GroupNorm(max(1, out // 8), out), nn.GELU()
                    )
                )
                channels = out
            self.head = nn.Conv2d(channels, hidden_size, 1)
        self._init_standardization(grid * grid, hidden_size)

    def _tokens(self, pixels: torch.Tensor) -> torch.Tensor:
        x = pixels.to(self.head.weight.dtype)
        r = len(self.taps) // 2
        for stage in self.stages:
            x = stage(x)
            c = x.shape[1]
            taps = self.taps.to(x.dtype)
            kernel = (taps[:, None] * taps[None, :]).expand(c, 1, -1, -1)
            x = F.conv2d(F.pad(x, (r, r, r, r), mode="replicate"), kernel, stride=2, groups=c)
        return self.head(x).flatten(2).transpose(1, 2)

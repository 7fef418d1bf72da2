"""The frame decoder: latents ``(..., D)`` -> images ``(..., C, S, S)`` in the model's
normalized pixel space, trained with MSE on the frozen latents of a source world model."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import torch
import torch.nn.functional as F
from torch import nn

from ... import keys
from ...errors import ConfigError
from ..base import DecodesFrames

__all__ = ["FrameDecoder", "FrameModel", "PredictionPanel"]

BASE = 4  # side of the first feature map


class FrameDecoder(nn.Module):
    """``FrameDecoder(embed_dim, image_size, channels=3, width=16)``: a linear map to a
    ``4 x 4`` feature map, then stride-2 transposed convolutions (channels ``width * 2^k``,
    at most ``8 * width``) up to ``image_size`` (resized at the end when it is not ``4 * 2^n``)."""

    def __init__(self, embed_dim: int, image_size: int, channels: int = 3, width: int = 16):
        super().__init__()
        for name, value in (
            ("embed_dim", embed_dim),
            ("image_size", image_size),
            ("channels", channels),
            ("width", width),
        ):
            if isinstance(value, bool) or not isinstance(value, int) or value < 1:
                raise ConfigError(f"FrameDecoder requires {name} to be a positive int, got {value!r}")
        self.image_size, self.channels = image_size, channels
        ups = max(0, math.ceil(math.log2(max(image_size, BASE) / BASE)))
        widths = [width * min(8, 2 ** (ups - k)) for k in range(ups + 1)]  # coarse -> fine
        self.stem = nn.Linear(embed_dim, widths[0] * BASE * BASE)
        layers: list[nn.Module] = []
        for a, b in zip(widths[:-1], widths[1:], strict=True):
            layers += [nn.GELU(), nn.ConvTranspose2d(a, b, 4, stride=2, padding=1), nn.GroupNorm(1, b)]
        layers += [nn.GELU(), nn.Conv2d(widths[-1], channels, 3, padding=1)]
        self.body = nn.Sequential(*layers)
        self._first = widths[0]

    def forward(self, emb: torch.Tensor) -> torch.Tensor:
        """``(..., D)`` -> ``(..., C, S, S)``."""
        lead = emb.shape[:-1]
        x = self.stem(emb.reshape(-1, emb.shape[-1])).reshape(-1, self._first, BASE, BASE)
        x = self.body(x)
        if x.shape[-1] != self.image_size:
            x = F.interpolate(x, size=(self.image_size, self.image_size), mode="bilinear", align_corners=False)
        return x.reshape(*lead, *x.shape[1:])


class FrameModel(nn.Module):
    """``FrameModel(world_model, decoder)``: ``decoder`` learns to turn the frozen
    ``world_model.encode_pixels`` latents back into the frames.

    :meth:`loss` (``batch["pixels"] (B, T, C, S, S)`` preprocessed) returns ``loss`` (MSE of
    the decoded frames, in normalized pixel units). :meth:`decode` maps any latents ``(..., D)``
    (predicted ones included) to images. ``world_model`` stays frozen and in eval mode.
    """

    def __init__(self, world_model: nn.Module, decoder: nn.Module):
        super().__init__()
        if not callable(getattr(world_model, "encode_pixels", None)):
            raise ConfigError(f"FrameModel requires a world model with encode_pixels, got {type(world_model).__name__}")
        self.world_model = world_model.requires_grad_(False)
        self.decoder = decoder

    def train(self, mode: bool = True) -> FrameModel:
        super().train(mode)
        self.world_model.eval()
        return self

    def encode_pixels(self, pixels: torch.Tensor) -> torch.Tensor:
        """The source model's latents ``(..., D)`` of ``pixels (..., C, S, S)`` (one vector per frame)."""
        with torch.no_grad():
            emb = self.world_model.encode_pixels(pixels)
        if emb.shape[:-1] != pixels.shape[:-3]:
            raise ConfigError(
                f"FrameModel requires a world model with one latent vector per frame, got {tuple(emb.shape)} for "
                f"{tuple(pixels.shape[:-3])} frames (patch-token models such as PreJEPA are not supported)"
            )
        return emb

    def decode(self, emb: torch.Tensor) -> torch.Tensor:
        """``(..., D)`` latents -> ``(..., C, S, S)`` normalized images."""
        return self.decoder(emb)

    def loss(self, batch: dict) -> dict:
        pixels = batch.get(keys.PIXELS)
        if pixels is None:
            raise ConfigError(f"FrameModel.loss requires batch['pixels'], got keys {sorted(batch)}")
        emb = self.encode_pixels(pixels)
        recon = self.decode(emb)
        loss = F.mse_loss(recon, pixels)
        return {"loss": loss, "recon_loss": loss.detach()}


class PredictionPanel:
    """What a planning world model predicts the envs will see, as frames for videos.

    ``PredictionPanel(world_model, frame_model, image_mean, image_std)`` is called by
    :class:`~stable_worldmodel.policy.WorldModelPolicy` after each plan with the prepared
    ``info`` (``pixels (B, T, C, S, S)``) and the executed normalized action blocks
    ``(B, R, A)``; it rolls the model out over them and returns the decoded last prediction
    as ``(B, S, S, 3)`` uint8 (the frame the model expects when the executed blocks end).
    A model whose predicted state is not a frame latent maps it with its ``predict_embedding``
    first (Dreamer); ``frame_model=None`` decodes with the model's own ``decode`` (a model
    with ``decodes_frames = True``: Dreamer's image decoder).
    """

    def __init__(self, world_model: Any, frame_model: FrameModel | None, image_mean, image_std):
        if frame_model is None and not (isinstance(world_model, DecodesFrames) and world_model.decodes_frames):
            raise ConfigError(
                f"PredictionPanel requires a frame model, or a world model with its own decode; "
                f"{type(world_model).__name__} has none"
            )
        self.world_model, self.frame_model = world_model, frame_model
        self.mean = torch.as_tensor(image_mean, dtype=torch.float32).view(-1, 1, 1)
        self.std = torch.as_tensor(image_std, dtype=torch.float32).view(-1, 1, 1)

    def __call__(self, info: dict, actions: torch.Tensor) -> np.ndarray:
        with torch.inference_mode():
            context = {keys.PIXELS: info[keys.PIXELS]}
            t = int(context[keys.PIXELS].shape[1])
            if actions.shape[1] < t:  # one action block per context frame at least (rollout's rule)
                actions = torch.cat([actions[:, :1].expand(-1, t - actions.shape[1], -1), actions], dim=1)
            out = self.world_model.rollout(context, actions)
            last = out["predicted_emb"][:, -1]
            if self.frame_model is None:
                images = self.world_model.decode(last)
            else:
                if callable(getattr(self.world_model, "predict_embedding", None)):
                    last = self.world_model.predict_embedding(last)
                images = self.frame_model.decode(last.to(next(self.frame_model.parameters()).device))
            images = images.float().cpu() * self.std + self.mean
        return (images.clamp(0, 1) * 255).round().to(torch.uint8).permute(0, 2, 3, 1).numpy()

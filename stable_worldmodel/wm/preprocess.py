"""Image and action preprocessing shared by training and planning (needs torch).

- :func:`preprocess_images`: uint8 images ``(..., C, h, w)`` -> normalized floats
  ``(..., C, S, S)`` (scaled to [0, 1], ``(x - mean) / std``, resized to ``S`` when needed).
- :class:`Normalizer`: a z-score of one column, usable as a ``process`` entry of
  :class:`~stable_worldmodel.policy.WorldModelPolicy` (numpy ``transform`` /
  ``inverse_transform`` on ``(N, D)``) and on torch tensors (:meth:`Normalizer.torch`).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
import torch
import torch.nn.functional as F

__all__ = ["ImageTransform", "Normalizer", "preprocess_images"]


def preprocess_images(images: torch.Tensor, mean: Sequence[float], std: Sequence[float], size: int) -> torch.Tensor:
    """``(..., C, h, w)`` images (uint8 in [0, 255] or floats in [0, 1]) -> float32 ``(..., C, size, size)``."""
    x = images.float()
    if images.dtype == torch.uint8:
        x = x / 255.0
    lead, (c, h, w) = x.shape[:-3], x.shape[-3:]
    x = x.reshape(-1, c, h, w)
    if (h, w) != (size, size):
        x = F.interpolate(x, size=(size, size), mode="bilinear", align_corners=False, antialias=True)
    m = torch.as_tensor(mean, dtype=x.dtype, device=x.device).view(1, -1, 1, 1)
    s = torch.as_tensor(std, dtype=x.dtype, device=x.device).view(1, -1, 1, 1)
    return ((x - m) / s).reshape(*lead, c, size, size)


class ImageTransform:
    """Picklable ``transform`` entry for images: :func:`preprocess_images` with fixed settings."""

    def __init__(self, mean: Sequence[float], std: Sequence[float], size: int):
        self.mean, self.std, self.size = tuple(float(v) for v in mean), tuple(float(v) for v in std), int(size)

    def __call__(self, images: torch.Tensor) -> torch.Tensor:
        return preprocess_images(images, self.mean, self.std, self.size)

    def __repr__(self) -> str:
        return f"ImageTransform(mean={self.mean}, std={self.std}, size={self.size})"


class Normalizer:
    """Z-score of a ``(N, D)`` column: ``(x - mean) / std`` (a std below ``1e-6`` counts as 1)."""

    def __init__(self, mean: Sequence[float], std: Sequence[float]):
        self.mean = np.asarray(mean, dtype=np.float64).reshape(-1)
        std = np.asarray(std, dtype=np.float64).reshape(-1)
        self.std = np.where(std < 1e-6, 1.0, std)

    @classmethod
    def fit(cls, data: np.ndarray) -> Normalizer:
        """Fit on rows ``(N, D)``; rows with a NaN are skipped."""
        data = np.asarray(data, dtype=np.float64).reshape(len(data), -1)
        data = data[~np.isnan(data).any(axis=1)]
        if not len(data):
            raise ValueError("Normalizer.fit requires at least one row without NaN")
        return cls(data.mean(axis=0), data.std(axis=0))

    def transform(self, x: Any) -> np.ndarray:
        return (np.asarray(x, dtype=np.float64) - self.mean) / self.std

    def inverse_transform(self, x: Any) -> np.ndarray:
        return np.asarray(x, dtype=np.float64) * self.std + self.mean

    def torch(self, x: torch.Tensor, repeat: int = 1) -> torch.Tensor:
        """Normalize a tensor ``(..., repeat * D)`` (an action block of ``repeat`` actions)."""
        mean = torch.as_tensor(np.tile(self.mean, repeat), dtype=x.dtype, device=x.device)
        std = torch.as_tensor(np.tile(self.std, repeat), dtype=x.dtype, device=x.device)
        return (x - mean) / std

    def to_dict(self) -> dict[str, list[float]]:
        return {"mean": self.mean.tolist(), "std": self.std.tolist()}

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> Normalizer:
        return cls(data["mean"], data["std"])

    def __repr__(self) -> str:
        return f"Normalizer(mean={np.round(self.mean, 4).tolist()}, std={np.round(self.std, 4).tolist()})"

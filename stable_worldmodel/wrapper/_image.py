"""Image helpers for the wrappers (cv2 is imported on first use)."""

from __future__ import annotations

import numpy as np


def resize(img: np.ndarray, shape: tuple[int, int]) -> np.ndarray:
    """Resize an ``(H, W, C)`` uint8 image to ``shape`` = (H, W); no-op when it already fits."""
    if img.shape[0] == shape[0] and img.shape[1] == shape[1]:
        return img
    import cv2

    shrinking = img.shape[0] >= shape[0] and img.shape[1] >= shape[1]
    out = cv2.resize(img, (int(shape[1]), int(shape[0])), interpolation=cv2.INTER_AREA if shrinking else cv2.INTER_LINEAR)
    return out if out.ndim == img.ndim else out[..., None]


def check_shape(name: str, shape) -> tuple[int, int]:
    """Validate an (H, W) pair and return it as a tuple of ints."""
    from ..errors import ConfigError

    try:
        h, w = (int(s) for s in tuple(shape)[:2])
    except (TypeError, ValueError):
        raise ConfigError(f"{name} requires an (H, W) pair of positive integers, got {shape!r}") from None
    if h <= 0 or w <= 0:
        raise ConfigError(f"{name} requires an (H, W) pair of positive integers, got {shape!r}")
    return h, w

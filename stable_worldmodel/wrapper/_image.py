"""Image helpers for the wrappers (cv2 is imported on first use)."""

from __future__ import annotations

import numpy as np


def resize(img: np.ndarray, shape: tuple[int, int]) -> np.ndarray:
    """Resize an ``(H, W, C)`` uint8 image to ``shape`` = (H, W); no-op when it already fits."""
    if img.shape[0] == shape[0] and img.shape[1] == shape[1]:
        return img
    import cv2

    shrinking = img.shape[0] >= shape[0] and img.shape[1] >= shape[1]
    out = cv2.resize(
        img, (int(shape[1]), int(shape[0])), interpolation=cv2.INTER_AREA if shrinking else cv2.INTER_LINEAR
    )
    return out if out.ndim == img.ndim else out[..., None]


def check_shape(name: str, shape) -> tuple[int, int]:
    """Validate an (H, W) pair of positive integers and return it as a tuple of ints."""
    from ..errors import ConfigError

    def bad(why: str = "") -> ConfigError:
        return ConfigError(f"{name} requires an (H, W) pair of positive integers such as (64, 64), got {shape!r}{why}")

    if isinstance(shape, (str, bytes)) or not hasattr(shape, "__len__"):
        raise bad()
    if len(shape) != 2:
        raise bad(" (images are (H, W, 3): give only (H, W))" if len(shape) == 3 else "")
    out = []
    for s in shape:
        if isinstance(s, (bool, np.bool_)) or not isinstance(s, (int, np.integer)) or s <= 0:
            raise bad()
        out.append(int(s))
    return out[0], out[1]

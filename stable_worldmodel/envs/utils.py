"""Drawing helpers shared by the 2-D environments.

Everything draws anti-aliased shapes straight into an ``(H, W, 3)`` uint8 canvas at the
final resolution (sub-pixel accurate through OpenCV's fixed-point ``shift``), so an env
asked for 64x64 frames never draws at 512x512 and shrinks. Coordinates are in pixels of
the canvas; use :func:`world_to_pixels` to map from an env's world units.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

_SHIFT = 4  # 1/16 pixel precision
_ONE = 1 << _SHIFT


def _cv2():
    import cv2

    return cv2


def new_canvas(size: tuple[int, int], color: Sequence[int]) -> np.ndarray:
    """An ``(H, W, 3)`` uint8 image filled with ``color``."""
    img = np.empty((int(size[0]), int(size[1]), 3), np.uint8)
    img[:] = np.asarray(color, np.uint8)
    return img


def world_to_pixels(points: np.ndarray, world_size: float | Sequence[float], size: tuple[int, int]) -> np.ndarray:
    """Map world coordinates ``(..., 2)`` in ``[0, world_size]`` to canvas pixels ``(x, y)``."""
    ws = np.broadcast_to(np.asarray(world_size, np.float64), (2,))
    scale = np.array([size[1] / ws[0], size[0] / ws[1]])
    return np.asarray(points, np.float64) * scale


def _color(color: Sequence[int]) -> tuple[int, int, int]:
    c = np.asarray(color).reshape(-1)
    return int(c[0]), int(c[1]), int(c[2])


def fill_polygon(img: np.ndarray, points_px: np.ndarray, color: Sequence[int]) -> None:
    """Fill the polygon with vertices ``points_px`` (N, 2) in pixel (x, y) coordinates."""
    pts = np.round(np.asarray(points_px, np.float64) * _ONE).astype(np.int32).reshape(1, -1, 2)
    cv2 = _cv2()
    cv2.fillPoly(img, pts, _color(color), lineType=cv2.LINE_AA, shift=_SHIFT)


def fill_circle(img: np.ndarray, center_px: Sequence[float], radius_px: float, color: Sequence[int]) -> None:
    """Fill a disk of ``radius_px`` centred at ``center_px`` = (x, y)."""
    cv2 = _cv2()
    c = (int(round(center_px[0] * _ONE)), int(round(center_px[1] * _ONE)))
    cv2.circle(img, c, max(int(round(radius_px * _ONE)), 1), _color(color), -1, cv2.LINE_AA, _SHIFT)


def draw_polyline(
    img: np.ndarray, points_px: np.ndarray, color: Sequence[int], thickness: int = 1, closed: bool = True
) -> None:
    """Draw the outline through ``points_px`` (N, 2)."""
    cv2 = _cv2()
    pts = np.round(np.asarray(points_px, np.float64) * _ONE).astype(np.int32).reshape(1, -1, 2)
    cv2.polylines(img, pts, closed, _color(color), max(int(thickness), 1), cv2.LINE_AA, _SHIFT)


def fill_rect(img: np.ndarray, x0: float, y0: float, x1: float, y1: float, color: Sequence[int]) -> None:
    """Fill the axis-aligned rectangle with corners (x0, y0) and (x1, y1) in pixels."""
    fill_polygon(img, np.array([[x0, y0], [x1, y0], [x1, y1], [x0, y1]]), color)


def rotate(points: np.ndarray, angle: float) -> np.ndarray:
    """Rotate ``(N, 2)`` points by ``angle`` radians around the origin."""
    c, s = np.cos(angle), np.sin(angle)
    return np.asarray(points, np.float64) @ np.array([[c, s], [-s, c]])

"""Drawing of ``swm/TwoRoom-v0`` frames the way release 0.0.3 drew them (OpenCV, headless).

0.0.3 drew on a 512 x 512 pygame canvas with pymunk's debug-draw look, then resized the canvas
to the render size with OpenCV's default bilinear interpolation. We rasterize the same
primitives with OpenCV at 512 x 512 and resize the same way, so frames match 0.0.3's closely:

- a polygon shape is filled with its *light* colour (each channel times 1.2, capped at 255,
  truncated) and outlined by segments 4 px thick in its own colour (ends rounded, radius 2);
- a disk is filled with its colour, then a disk 4 px smaller with its light colour;
- layers, back to front: background, door gaps, goal disk, agent (debug draw), wall pieces,
  door gaps and border (debug draw, in the order they were added), agent again (on top).

Points are rounded with Python's ``round`` as pygame's ``to_pygame`` does.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

CANVAS = 512
_EDGE_RADIUS = 2


def light_color(color: Sequence[int]) -> tuple[int, int, int]:
    """``min(1.2 c, 255)`` per channel, computed in float32 and truncated (pymunk debug-draw fill)."""
    c = np.minimum(np.float32(1.2) * np.asarray(color[:3], np.float32), np.float32(255))
    return tuple(int(v) for v in c)


def _pt(p) -> tuple[int, int]:
    return round(float(p[0])), round(float(p[1]))


def _rgb(color: Sequence[int]) -> tuple[int, int, int]:
    return int(color[0]), int(color[1]), int(color[2])


def fill_polygon(img: np.ndarray, points, color: Sequence[int]) -> None:
    """A filled polygon through ``points`` (N, 2) in canvas pixels."""
    import cv2

    cv2.fillPoly(img, [np.array([_pt(p) for p in points], np.int32)], _rgb(color))


def fat_segment(img: np.ndarray, a, b, color: Sequence[int], radius: int = _EDGE_RADIUS) -> None:
    """A segment ``2 * radius`` px thick with rounded ends."""
    import cv2

    a, b, color = _pt(a), _pt(b), _rgb(color)
    cv2.line(img, a, b, color, thickness=2 * radius)
    dx, dy = abs(b[1] - a[1]), abs(b[0] - a[0])  # the offset of 0.0.3 (absolute values)
    length = (dx * dx + dy * dy) ** 0.5
    if length > 0:
        ox, oy = round(dx * radius / length), round(dy * radius / length)
        quad = [(a[0] - ox, a[1] - oy), (a[0] + ox, a[1] + oy), (b[0] + ox, b[1] + oy), (b[0] - ox, b[1] - oy)]
        cv2.fillPoly(img, [np.array(quad, np.int32)], color)
    cv2.circle(img, a, radius, color, -1)
    cv2.circle(img, b, radius, color, -1)


def debug_polygon(img: np.ndarray, points, color: Sequence[int]) -> None:
    """A pymunk polygon as debug draw shows it: light fill, outline in ``color``."""
    fill_polygon(img, points, light_color(color))
    for i in range(len(points)):
        fat_segment(img, points[i], points[(i + 1) % len(points)], color)


def debug_disk(img: np.ndarray, center, radius: float, color: Sequence[int]) -> None:
    """A disk in ``color`` with a light inner disk 4 px smaller."""
    import cv2

    c = _pt(center)
    cv2.circle(img, c, round(radius), _rgb(color), -1)
    inner = round(radius - 4)
    if inner > 0:
        cv2.circle(img, c, inner, light_color(color), -1)


def resize(img: np.ndarray, size: tuple[int, int]) -> np.ndarray:
    """``img`` at ``size`` = (H, W) with OpenCV's default (bilinear) interpolation, as 0.0.3."""
    import cv2

    h, w = size
    if img.shape[:2] == (h, w):
        return img
    return cv2.resize(img, (w, h))


def draw_frame(
    size: tuple[int, int],
    background: Sequence[int],
    walls: list[tuple[np.ndarray, Sequence[int]]],
    doors: list[tuple[np.ndarray, Sequence[int]]],
    border: list[tuple[np.ndarray, Sequence[int]]],
    goal: tuple[np.ndarray, float, Sequence[int]],
    agent: tuple[np.ndarray, float, Sequence[int]],
) -> np.ndarray:
    """An ``(H, W, 3)`` uint8 frame; polygons are ``(points (4, 2), color)``, disks ``(center, radius, color)``."""
    img = np.empty((CANVAS, CANVAS, 3), np.uint8)
    img[:] = _rgb(background)
    for points, color in doors:
        fill_polygon(img, points, color)
    debug_disk(img, *goal)
    debug_disk(img, *agent)
    for points, color in [*walls, *doors, *border]:
        debug_polygon(img, points, color)
    debug_disk(img, *agent)
    return resize(img, size)

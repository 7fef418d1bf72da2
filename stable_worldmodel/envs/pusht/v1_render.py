"""Frames of ``swm/PushT-v1`` drawn the way upstream 0.1.1 draws them (OpenCV, headless).

Upstream paints pymunk's debug drawing on a 512x512 canvas and resizes it (bilinear) to the
render size. Back to front: background, goal silhouette (the block's parts, filled, at the
``goal`` pose), agent, block, walls. A polygon body is filled with its light colour
(``min(1.2 c, 255)``) and outlined by 4 px segments of its colour with round ends; a disk is
its colour with a light disk 4 px smaller in radius; walls are 4 px LightGray segments.
"""

from __future__ import annotations

from collections.abc import Sequence
from functools import lru_cache

import numpy as np

from .physics import WALLS
from .shapes import to_world

CANVAS = 512
WALL_COLOR = (211, 211, 211)  # pygame's LightGray
EDGE_RADIUS = 2


def light(color: Sequence[int]) -> tuple[int, int, int]:
    """Upstream's fill colour of a body: 1.2 x its colour (float32), capped at 255, truncated."""
    return _light(tuple(int(c) for c in color))


@lru_cache(maxsize=256)
def _light(color: tuple[int, ...]) -> tuple[int, int, int]:
    c = np.minimum(np.float32(1.2) * np.asarray(color, np.float32), np.float32(255))
    return tuple(int(v) for v in c)


def _pix(points: np.ndarray) -> np.ndarray:
    return np.round(np.asarray(points, np.float64)).astype(np.int32)


def _segment(cv2, img, a, b, color, origin=(0, 0)) -> None:
    """A 4-px segment with round ends between canvas pixels ``a`` and ``b`` (integer ``(x, y)``);
    ``origin``: the canvas pixel at ``img[0, 0]``."""
    ox, oy = origin
    a, b = (a[0] - ox, a[1] - oy), (b[0] - ox, b[1] - oy)
    cv2.line(img, a, b, color, thickness=2 * EDGE_RADIUS)
    cv2.circle(img, a, EDGE_RADIUS, color, -1)
    cv2.circle(img, b, EDGE_RADIUS, color, -1)


class _Shape:
    """A body placed on the canvas for one frame: its pixel outline, colours and pixel bounds
    ``(x0, y0, x1, y1)`` (a margin past what it paints)."""

    __slots__ = ("disk", "polys", "color", "fill", "bounds")

    def __init__(self, radius, polys, pose, color):
        self.color = tuple(int(c) for c in color)
        self.fill = _light(self.color)
        if radius is not None:
            c = _pix(pose[:2])
            centre, r = (int(c[0]), int(c[1])), int(round(radius))
            self.disk, self.polys = (centre, r, int(round(radius - 4))), None
            self.bounds = (centre[0] - r - 2, centre[1] - r - 2, centre[0] + r + 3, centre[1] + r + 3)
            return
        self.disk = None
        self.polys = [_pix(to_world(poly, pose[:2], float(pose[2]))) for poly in polys]
        pts = np.concatenate(self.polys)
        lo, hi = pts.min(axis=0) - (EDGE_RADIUS + 2), pts.max(axis=0) + (EDGE_RADIUS + 3)
        self.bounds = (int(lo[0]), int(lo[1]), int(hi[0]), int(hi[1]))

    def paint(self, cv2, img, origin=(0, 0)) -> None:
        """Draw the body on ``img``, whose pixel (0, 0) is the canvas pixel ``origin``: a polygon
        filled light and outlined by segments, a disk with a light disk 4 px smaller."""
        ox, oy = origin
        if self.disk is not None:
            (x, y), r, inner = self.disk
            cv2.circle(img, (x - ox, y - oy), r, self.color, -1)
            cv2.circle(img, (x - ox, y - oy), inner, self.fill, -1)
            return
        for pts in self.polys:
            cv2.fillPoly(img, [pts - np.array([ox, oy], np.int32)], self.fill)
            corners = [tuple(p) for p in pts.tolist()]
            for i in range(len(corners)):
                _segment(cv2, img, corners[i], corners[(i + 1) % len(corners)], self.color, origin)


#: the static layers (background and goal silhouette) of recent episodes, by what they are drawn from
_STATIC: dict[tuple, np.ndarray] = {}
#: the static layers with the walls on, and resized: ``(walled 512-px layer, layer at a size)``
_SIZED: dict[tuple, tuple[np.ndarray, np.ndarray]] = {}
_STATIC_KEEP = 16
#: walls are drawn within this many pixels of the canvas edges
_WALL_ZONE = 10


def _static_key(colors, goal_pose, block) -> tuple:
    goal_color = colors.get("goal")
    return (
        tuple(int(c) for c in colors["background"]),
        None if goal_color is None else tuple(int(c) for c in goal_color),
        tuple(float(v) for v in np.asarray(goal_pose, np.float64)[:3]),
        tuple(np.asarray(p, np.float64).tobytes() for p in block[1]),
    )


def _remember(cache: dict, key, value):
    if len(cache) >= _STATIC_KEEP:
        cache.pop(next(iter(cache)))
    cache[key] = value
    return value


def _static_layer(cv2, colors, goal_pose, block, key=None) -> np.ndarray:
    """The 512-px background with the goal silhouette on it: what does not move in an episode,
    drawn once per episode (filling a 512x512x3 canvas with numpy was half of a frame's cost)."""
    key = _static_key(colors, goal_pose, block) if key is None else key
    layer = _STATIC.get(key)
    if layer is None:
        layer = np.empty((CANVAS, CANVAS, 3), np.uint8)
        layer[:] = np.asarray(colors["background"], np.uint8)
        goal_color = colors.get("goal")
        if goal_color is not None:
            goal = tuple(int(c) for c in goal_color)
            for poly in block[1]:
                cv2.fillPoly(layer, [_pix(to_world(poly, goal_pose[:2], float(goal_pose[2])))], goal)
        layer = _remember(_STATIC, key, layer)
    return layer


_WALL_MASK: list[np.ndarray] = []


def _wall_mask(cv2) -> np.ndarray:
    """The canvas pixels the walls paint (they are drawn last, in one colour)."""
    if not _WALL_MASK:
        mask = np.zeros((CANVAS, CANVAS), np.uint8)
        for a, b in WALLS:
            _segment(cv2, mask, a, b, 1)
        _WALL_MASK.append(mask.astype(bool))
    return _WALL_MASK[0]


def _steps(h: int, w: int) -> tuple[int, int] | None:
    """Canvas pixels per output pixel ``(sy, sx)`` when OpenCV's bilinear resize reads each output
    pixel from its own ``sy x sx`` block of the canvas (the size divides 512 by a power of 2, at
    least 2): then a block-aligned crop resizes to exactly the pixels of the full resize. None
    otherwise (and at 512 px, where there is nothing to resize)."""
    out = []
    for n in (h, w):
        if CANVAS % n or n == CANVAS:
            return None
        s = CANVAS // n
        if s & (s - 1):
            return None
        out.append(s)
    return out[0], out[1]


def _regions(shapes, steps) -> list[tuple[int, int, int, int]]:
    """Block-aligned canvas boxes ``(x0, y0, x1, y1)`` that hold every pixel the bodies paint: one
    per body, merged when they meet."""
    sy, sx = steps
    boxes = []
    for shape in shapes:
        x0, y0, x1, y1 = shape.bounds
        x0, y0 = max(0, x0 // sx * sx), max(0, y0 // sy * sy)
        x1, y1 = min(CANVAS, -(-x1 // sx) * sx), min(CANVAS, -(-y1 // sy) * sy)
        if x0 < x1 and y0 < y1:
            boxes.append((x0, y0, x1, y1))
    if len(boxes) == 2:
        (a0, b0, a1, b1), (c0, d0, c1, d1) = boxes
        if a0 <= c1 and c0 <= a1 and b0 <= d1 and d0 <= b1:
            boxes = [(min(a0, c0), min(b0, d0), max(a1, c1), max(b1, d1))]
    return boxes


def draw_v1_scene(size, colors, goal_pose, block, agent) -> np.ndarray:
    """An ``(H, W, 3)`` uint8 frame.

    ``colors``: dict with ``background``, ``goal`` (None: no silhouette), ``block``, ``agent``.
    ``block`` / ``agent``: ``(radius, polygons, pose)`` with the local outline of
    :func:`.v1_shapes.body_outline` and the pose (x, y, angle). The background and goal
    silhouette come from a per-episode cache (:func:`_static_layer`): the same pixels, drawn once.
    At sizes that divide 512 by a power of 2 (64, 128, ...) the static scene is also kept resized
    and a frame redraws only the canvas blocks under the bodies (:func:`_regions`): the pixels
    of the full 512-px drawing and resize, at a fraction of the cost.
    """
    import cv2

    h, w = int(size[0]), int(size[1])
    key = _static_key(colors, goal_pose, block)
    static = _static_layer(cv2, colors, goal_pose, block, key)
    shapes = (_Shape(*agent, colors["agent"]), _Shape(*block, colors["block"]))  # back to front
    steps = _steps(h, w)
    if steps is None:
        img = static.copy()
        for shape in shapes:
            shape.paint(cv2, img)
        for a, b in WALLS:
            _segment(cv2, img, a, b, WALL_COLOR)
        if (h, w) == (CANVAS, CANVAS):
            return img
        return cv2.resize(img, (w, h), interpolation=cv2.INTER_LINEAR)
    sized = _SIZED.get((key, h, w))
    if sized is None:
        walled = static.copy()
        walled[_wall_mask(cv2)] = WALL_COLOR
        sized = _remember(_SIZED, (key, h, w), (walled, cv2.resize(walled, (w, h), interpolation=cv2.INTER_LINEAR)))
    walled, small = sized
    out = small.copy()
    sy, sx = steps
    for x0, y0, x1, y1 in _regions(shapes, steps):
        crop = walled[y0:y1, x0:x1].copy()
        for shape in shapes:
            bx0, by0, bx1, by1 = shape.bounds
            if bx0 < x1 and x0 < bx1 and by0 < y1 and y0 < by1:  # a body outside the box paints none of it
                shape.paint(cv2, crop, (x0, y0))
        if min(x0, y0) < _WALL_ZONE or max(x1, y1) > CANVAS - _WALL_ZONE:  # the walls are drawn over the bodies
            crop[_wall_mask(cv2)[y0:y1, x0:x1]] = WALL_COLOR
        small_w, small_h = (x1 - x0) // sx, (y1 - y0) // sy
        out[y0 // sy : y1 // sy, x0 // sx : x1 // sx] = cv2.resize(
            crop, (small_w, small_h), interpolation=cv2.INTER_LINEAR
        )
    return out

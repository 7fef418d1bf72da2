"""Frames of ``swm/PushT-v1`` drawn the way upstream 0.1.1 draws them (OpenCV, headless).

Upstream paints pymunk's debug drawing on a 512x512 canvas and resizes it (bilinear) to the
render size. Back to front: background, goal silhouette (the block's parts, filled, at the
``goal`` pose), agent, block, walls. A polygon body is filled with its light colour
(``min(1.2 c, 255)``) and outlined by 4 px segments of its colour with round ends; a disk is
its colour with a light disk 4 px smaller in radius; walls are 4 px LightGray segments.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from .physics import WALLS
from .shapes import to_world

CANVAS = 512
WALL_COLOR = (211, 211, 211)  # pygame's LightGray
EDGE_RADIUS = 2


def light(color: Sequence[int]) -> tuple[int, int, int]:
    """Upstream's fill colour of a body: 1.2 x its colour (float32), capped at 255, truncated."""
    c = np.minimum(np.float32(1.2) * np.asarray(color, np.float32), np.float32(255))
    return tuple(int(v) for v in c)


def _pix(points: np.ndarray) -> np.ndarray:
    return np.round(np.asarray(points, np.float64)).astype(np.int32)


def _segment(cv2, img, a, b, color) -> None:
    a, b = tuple(int(v) for v in _pix(a)), tuple(int(v) for v in _pix(b))
    cv2.line(img, a, b, color, thickness=2 * EDGE_RADIUS)
    cv2.circle(img, a, EDGE_RADIUS, color, -1)
    cv2.circle(img, b, EDGE_RADIUS, color, -1)


def _body(cv2, img, radius, polys, pose, color) -> None:
    color = tuple(int(c) for c in color)
    if radius is not None:
        centre = tuple(int(v) for v in _pix(pose[:2]))
        cv2.circle(img, centre, int(round(radius)), color, -1)
        cv2.circle(img, centre, int(round(radius - 4)), light(color), -1)
        return
    for poly in polys:
        pts = to_world(poly, pose[:2], float(pose[2]))
        cv2.fillPoly(img, [_pix(pts)], light(color))
        for i in range(len(pts)):
            _segment(cv2, img, pts[i], pts[(i + 1) % len(pts)], color)


#: the static layers (background and goal silhouette) of recent episodes, by what they are drawn from
_STATIC: dict[tuple, np.ndarray] = {}
_STATIC_KEEP = 16


def _static_layer(cv2, colors, goal_pose, block) -> np.ndarray:
    """The 512-px background with the goal silhouette on it: what does not move in an episode,
    drawn once per episode (filling a 512x512x3 canvas with numpy was half of a frame's cost)."""
    goal_color = colors.get("goal")
    key = (
        tuple(int(c) for c in colors["background"]),
        None if goal_color is None else tuple(int(c) for c in goal_color),
        tuple(float(v) for v in np.asarray(goal_pose, np.float64)[:3]),
        tuple(np.asarray(p, np.float64).tobytes() for p in block[1]),
    )
    layer = _STATIC.get(key)
    if layer is None:
        layer = np.empty((CANVAS, CANVAS, 3), np.uint8)
        layer[:] = np.asarray(colors["background"], np.uint8)
        if goal_color is not None:
            goal = tuple(int(c) for c in goal_color)
            for poly in block[1]:
                cv2.fillPoly(layer, [_pix(to_world(poly, goal_pose[:2], float(goal_pose[2])))], goal)
        if len(_STATIC) >= _STATIC_KEEP:
            _STATIC.pop(next(iter(_STATIC)))
        _STATIC[key] = layer
    return layer


def draw_v1_scene(size, colors, goal_pose, block, agent) -> np.ndarray:
    """An ``(H, W, 3)`` uint8 frame.

    ``colors``: dict with ``background``, ``goal`` (None: no silhouette), ``block``, ``agent``.
    ``block`` / ``agent``: ``(radius, polygons, pose)`` with the local outline of
    :func:`.v1_shapes.body_outline` and the pose (x, y, angle). The background and goal
    silhouette come from a per-episode cache (:func:`_static_layer`): the same pixels, drawn once.
    """
    import cv2

    img = _static_layer(cv2, colors, goal_pose, block).copy()
    _body(cv2, img, *agent, colors["agent"])
    _body(cv2, img, *block, colors["block"])
    for a, b in WALLS:
        _segment(cv2, img, np.array(a, np.float64), np.array(b, np.float64), WALL_COLOR)
    h, w = int(size[0]), int(size[1])
    if (h, w) == (CANVAS, CANVAS):
        return img
    return cv2.resize(img, (w, h), interpolation=cv2.INTER_LINEAR)

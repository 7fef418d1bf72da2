"""Success geometry of ``swm/TwoRoom-v0``: overlap of the agent and goal disks as 0.0.3 measured it.

0.0.3 turned each disk into a shapely ``Point.buffer(radius, resolution=16)`` (a 64-gon with
a vertex at angle 0) and compared the intersection area with each polygon's area. Both are
convex, so the intersection is computed here by clipping one polygon with the other.
"""

from __future__ import annotations

import numpy as np

_CIRCLE = np.stack([np.cos(np.arange(64) * np.pi / 32), np.sin(np.arange(64) * np.pi / 32)], 1)


def disk_polygon(center, radius: float) -> np.ndarray:
    """The 64-gon (CCW, first vertex at angle 0) 0.0.3's shapely ``buffer(radius, resolution=16)`` gives."""
    return np.asarray(center, np.float64) + radius * _CIRCLE


def polygon_area(p: np.ndarray) -> float:
    x, y = p[:, 0], p[:, 1]
    return 0.5 * abs(float(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1))))


def convex_overlap(subject: np.ndarray, clip: np.ndarray) -> float:
    """Area of the intersection of two convex CCW polygons (Sutherland-Hodgman)."""
    out = subject
    for a, b in zip(clip, np.roll(clip, -1, axis=0), strict=False):
        if len(out) == 0:
            return 0.0
        edge = b - a
        side = edge[0] * (out[:, 1] - a[1]) - edge[1] * (out[:, 0] - a[0])  # >= 0: inside
        nxt, side_n = np.roll(out, -1, axis=0), np.roll(side, -1)
        kept = []
        for p, q, s, sn in zip(out, nxt, side, side_n, strict=False):
            if s >= 0:
                kept.append(p)
            if (s >= 0) != (sn >= 0):
                kept.append(p + (s / (s - sn)) * (q - p))
        out = np.array(kept).reshape(-1, 2)
    return polygon_area(out) if len(out) >= 3 else 0.0


def overlap_fractions(agent_xy, agent_r: float, goal_xy, goal_r: float) -> tuple[float, float]:
    """``(fraction_of_goal, fraction_of_agent)``: shared area over each disk's (64-gon) area."""
    if float(np.hypot(*(np.asarray(agent_xy, np.float64) - np.asarray(goal_xy, np.float64)))) >= agent_r + goal_r:
        return 0.0, 0.0
    a, g = disk_polygon(agent_xy, agent_r), disk_polygon(goal_xy, goal_r)
    shared = convex_overlap(a, g)
    return shared / polygon_area(g), shared / polygon_area(a)

"""Exact kinematics of a disk agent among axis-aligned walls (TwoRoom, SimplePointMaze).

The agent is a disk of radius ``r``; its configuration-space obstacles are the wall
rectangles grown by ``r`` on every side (so a wall corner acts as a square corner, at most
``r * (sqrt(2) - 1)`` more conservative than a rounded one). :func:`sweep` moves the agent
centre along the straight segment of a step, stops it at the first face it would cross
(continuous collision: no tunnelling whatever the step length) and slides it along that
face for the rest of the step. Boxes are ``(N, 4)`` arrays of ``x0, y0, x1, y1`` and are
treated as open sets: touching a face or moving along it is free.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from .. import keys
from .base import flatten_values

_EPS = 1e-9


def grow_boxes(boxes: np.ndarray, radius: float) -> np.ndarray:
    """Wall rectangles ``(N, 4)`` grown by ``radius``: the obstacles seen by the agent centre."""
    out = np.asarray(boxes, np.float64).reshape(-1, 4).copy()
    out[:, :2] -= radius
    out[:, 2:] += radius
    return out


def _slabs(p: np.ndarray, d: np.ndarray, boxes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per box and axis, the segment parameters ``(near, far)`` (N, 2) of entering / leaving its slab."""
    near = np.empty((len(boxes), 2))
    far = np.empty((len(boxes), 2))
    for a in (0, 1):
        b0, b1 = boxes[:, a], boxes[:, a + 2]
        if d[a] == 0.0:
            inside = (b0 < p[a]) & (p[a] < b1)
            near[:, a] = np.where(inside, -np.inf, np.inf)
            far[:, a] = np.where(inside, np.inf, -np.inf)
        else:
            t0, t1 = (b0 - p[a]) / d[a], (b1 - p[a]) / d[a]
            near[:, a], far[:, a] = np.minimum(t0, t1), np.maximum(t0, t1)
    return near, far


def segment_clear(start: np.ndarray, end: np.ndarray, boxes: np.ndarray) -> bool:
    """Whether the closed segment ``start -> end`` avoids the interior of every box (N, 4)."""
    p = np.asarray(start, np.float64)
    d = np.asarray(end, np.float64) - p
    if not len(boxes):
        return True
    near, far = _slabs(p, d, boxes)
    enter, leave = near.max(1), far.min(1)
    return not np.any((enter < leave) & (enter <= 1.0) & (leave >= 0.0))


def _first_hit(p: np.ndarray, d: np.ndarray, boxes: np.ndarray, lo: np.ndarray, hi: np.ndarray):
    """Earliest ``(t, axis, face)`` with ``t`` in ``[0, 1)`` where ``p + t d`` meets an obstacle."""
    best_t, best_axis, best_face = 1.0, -1, 0.0
    for a in (0, 1):  # the bounds of the free area
        if d[a] > 0 and p[a] + d[a] > hi[a]:
            t, face = (hi[a] - p[a]) / d[a], hi[a]
        elif d[a] < 0 and p[a] + d[a] < lo[a]:
            t, face = (lo[a] - p[a]) / d[a], lo[a]
        else:
            continue
        if max(t, 0.0) < best_t:
            best_t, best_axis, best_face = max(t, 0.0), a, face
    if len(boxes):
        near, far = _slabs(p, d, boxes)
        enter, leave = near.max(1), far.min(1)
        ok = (enter < leave) & (enter >= -_EPS) & (enter < best_t) & (leave > 0)
        if ok.any():
            i = int(np.flatnonzero(ok)[np.argmin(enter[ok])])
            a = int(np.argmax(near[i]))
            best_t, best_axis = max(float(enter[i]), 0.0), a
            best_face = boxes[i, a] if d[a] > 0 else boxes[i, a + 2]
    return best_t, best_axis, best_face


def sweep(
    pos: np.ndarray, delta: np.ndarray, boxes: np.ndarray, lo: np.ndarray, hi: np.ndarray, max_slides: int = 3
) -> tuple[np.ndarray, np.ndarray]:
    """Move ``pos`` (2,) by ``delta`` (2,) inside ``[lo, hi]`` without entering ``boxes`` (N, 4).

    Returns ``(new_pos, blocked)``: ``blocked`` (2,) bool marks the axes whose motion a face
    stopped (a point-mass env zeroes those velocity components).
    """
    p = np.array(pos, np.float64).reshape(2)
    d = np.array(delta, np.float64).reshape(2)
    lo, hi = np.asarray(lo, np.float64), np.asarray(hi, np.float64)
    blocked = np.zeros(2, bool)
    for _ in range(max_slides):
        if not d.any():
            break
        t, axis, face = _first_hit(p, d, boxes, lo, hi)
        if axis < 0:
            p = p + d
            break
        p = p + t * d
        p[axis] = face
        blocked[axis] = True
        d = d * (1.0 - t)
        d[axis] = 0.0
    return np.clip(p, lo, hi), blocked


def is_free(pos: np.ndarray, boxes: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> bool:
    """Whether the agent centre ``pos`` lies in ``[lo, hi]`` and inside no box."""
    p = np.asarray(pos, np.float64)
    if np.any(p < lo) or np.any(p > hi):
        return False
    return not np.any((boxes[:, 0] < p[0]) & (p[0] < boxes[:, 2]) & (boxes[:, 1] < p[1]) & (p[1] < boxes[:, 3]))


def push_out(pos: np.ndarray, boxes: np.ndarray, lo: np.ndarray, hi: np.ndarray, max_iter: int = 8) -> np.ndarray:
    """The nearest free position to ``pos`` reached by projecting onto box faces (legalizes a given start)."""
    p = np.clip(np.array(pos, np.float64).reshape(2), lo, hi)
    for _ in range(max_iter):
        if is_free(p, boxes, lo, hi):
            return p
        inside = (boxes[:, 0] < p[0]) & (p[0] < boxes[:, 2]) & (boxes[:, 1] < p[1]) & (p[1] < boxes[:, 3])
        cands = []
        for x0, y0, x1, y1 in boxes[inside]:
            cands += [(x0, p[1]), (x1, p[1]), (p[0], y0), (p[0], y1)]
        cands = np.clip(np.array(cands), lo, hi)
        dist = np.linalg.norm(cands - p, axis=1)
        free = np.array([is_free(c, boxes, lo, hi) for c in cands])
        p = cands[np.argmin(np.where(free, dist, dist + 1e6))]
    return p


def given_factors(options: Mapping[str, Any] | None) -> set[str]:
    """Dotted names of the factors that reset ``options`` set through ``"variation_values"``."""
    values = (options or {}).get(keys.VARIATION_VALUES) or {}
    return set(flatten_values(values))

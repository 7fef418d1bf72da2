"""Geometry of the PushT bodies, in the body's local frame (pure numpy, no pymunk).

A shape is built from a unit length ``u`` (the original T uses ``u = 30``: two 120x30 bars).
Physics uses the convex ``rects`` (``(x0, y0, x1, y1)`` rows) or the disk of ``radius``;
rendering uses the single ``outline`` polygon so joints between parts draw without seams.
``cog`` is the centre of gravity and ``moment`` the moment of inertia about it, for mass 1.

Local frames (y points down the screen, as in pymunk with the original PushT):

==========  ==============================================================
name        parts (in units of u)
==========  ==============================================================
tee         bar [-2, 2]x[0, 1] + stem [-0.5, 0.5]x[1, 4] (the original T)
small_tee   bar [-1.5, 1.5]x[0, 1] + stem [-0.5, 0.5]x[1, 3]
L           post [-1, 0]x[-1.5, 1.5] + foot [0, 1]x[0.5, 1.5]
Z           top [-1.5, 0.5]x[-1.5, -0.5] + bottom [-0.5, 1.5]x[0.5, 1.5] + middle
I           [-0.5, 0.5]x[-2, 2]
plus        [-1.5, 1.5]x[-0.5, 0.5] + [-0.5, 0.5]x[-1.5, 1.5]
square      [-1, 1]x[-1, 1]
box         [-2, 2]x[-1, 1]
circle      disk of radius u centred at the origin
==========  ==============================================================

The tee keeps the original's centre of gravity (the mean of its two part centroids, (0, 1.5u))
and moment of inertia (twice the crossbar's moment about the body origin, 5u^2/3 each), so
its dynamics match the PushT datasets of Diffusion Policy and DINO-WM. The other shapes use
their area-weighted centroid and exact moment.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from ...errors import unknown_name

SHAPES: tuple[str, ...] = ("tee", "small_tee", "L", "Z", "I", "plus", "square", "box", "circle")
# Rotational symmetry order of each shape (0: any rotation leaves it unchanged).
SYMMETRY = {"tee": 1, "small_tee": 1, "L": 1, "Z": 2, "I": 2, "plus": 4, "square": 4, "box": 2, "circle": 0}


@dataclass(frozen=True, eq=False)  # hashed by identity: shape_spec() caches one object per (name, unit)
class ShapeSpec:
    """Local geometry of one body (see the module docstring)."""

    name: str
    unit: float
    rects: np.ndarray  # (K, 4) convex parts (x0, y0, x1, y1); empty for the circle
    outline: np.ndarray  # (N, 2) outline polygon, or a 32-gon for the circle
    radius: float | None  # disk radius, None for polygons
    cog: np.ndarray  # (2,)
    moment: float  # for mass 1, about cog

    def polygons(self) -> list[np.ndarray]:
        """The convex parts as ``(4, 2)`` vertex arrays."""
        return [np.array([[x0, y0], [x1, y0], [x1, y1], [x0, y1]], np.float64) for x0, y0, x1, y1 in self.rects]

    def bounds(self) -> np.ndarray:
        """``(min_x, min_y, max_x, max_y)`` of the shape in its local frame."""
        pts = self.outline
        return np.array([pts[:, 0].min(), pts[:, 1].min(), pts[:, 0].max(), pts[:, 1].max()])

    def reach(self) -> float:
        """Largest distance from the body origin to a point of the shape."""
        return float(np.linalg.norm(self.outline, axis=1).max())


def _rect_poly(x0: float, y0: float, x1: float, y1: float) -> list[tuple[float, float]]:
    return [(x0, y0), (x1, y0), (x1, y1), (x0, y1)]


def _physical(rects: np.ndarray) -> tuple[np.ndarray, float]:
    """Area-weighted centroid and exact moment (mass 1) of a union of disjoint rectangles."""
    w, h = rects[:, 2] - rects[:, 0], rects[:, 3] - rects[:, 1]
    area = w * h
    mass = area / area.sum()
    centers = np.stack([(rects[:, 0] + rects[:, 2]) / 2, (rects[:, 1] + rects[:, 3]) / 2], axis=1)
    cog = (mass[:, None] * centers).sum(0)
    moment = float((mass * ((w**2 + h**2) / 12 + ((centers - cog) ** 2).sum(1))).sum())
    return cog, moment


# Outlines (clockwise on screen) and disjoint convex parts, in units of u.
_TABLE: dict[str, tuple[list[tuple[float, float]], list[tuple[float, float, float, float]]]] = {
    "tee": (
        [(-2, 0), (2, 0), (2, 1), (0.5, 1), (0.5, 4), (-0.5, 4), (-0.5, 1), (-2, 1)],
        [(-2, 0, 2, 1), (-0.5, 1, 0.5, 4)],
    ),
    "small_tee": (
        [(-1.5, 0), (1.5, 0), (1.5, 1), (0.5, 1), (0.5, 3), (-0.5, 3), (-0.5, 1), (-1.5, 1)],
        [(-1.5, 0, 1.5, 1), (-0.5, 1, 0.5, 3)],
    ),
    "L": (
        [(-1, -1.5), (0, -1.5), (0, 0.5), (1, 0.5), (1, 1.5), (-1, 1.5)],
        [(-1, -1.5, 0, 1.5), (0, 0.5, 1, 1.5)],
    ),
    "Z": (
        [(-1.5, -1.5), (0.5, -1.5), (0.5, 0.5), (1.5, 0.5), (1.5, 1.5), (-0.5, 1.5), (-0.5, -0.5), (-1.5, -0.5)],
        [(-1.5, -1.5, 0.5, -0.5), (-0.5, -0.5, 0.5, 0.5), (-0.5, 0.5, 1.5, 1.5)],
    ),
    "I": ([(-0.5, -2), (0.5, -2), (0.5, 2), (-0.5, 2)], [(-0.5, -2, 0.5, 2)]),
    "plus": (
        [
            (-0.5, -1.5),
            (0.5, -1.5),
            (0.5, -0.5),
            (1.5, -0.5),
            (1.5, 0.5),
            (0.5, 0.5),
            (0.5, 1.5),
            (-0.5, 1.5),
            (-0.5, 0.5),
            (-1.5, 0.5),
            (-1.5, -0.5),
            (-0.5, -0.5),
        ],
        [(-1.5, -0.5, 1.5, 0.5), (-0.5, -1.5, 0.5, -0.5), (-0.5, 0.5, 0.5, 1.5)],
    ),
    "square": ([(-1, -1), (1, -1), (1, 1), (-1, 1)], [(-1, -1, 1, 1)]),
    "box": ([(-2, -1), (2, -1), (2, 1), (-2, 1)], [(-2, -1, 2, 1)]),
}


def check_shape_name(name: str) -> str:
    """Return ``name`` if it is a known shape, else raise with a suggestion."""
    if name not in SHAPES:
        raise unknown_name("PushT shape", str(name), SHAPES)
    return name


@lru_cache(maxsize=256)
def shape_spec(name: str, unit: float) -> ShapeSpec:
    """The :class:`ShapeSpec` of shape ``name`` at unit length ``unit`` (cached)."""
    check_shape_name(name)
    unit = float(unit)
    if name == "circle":
        t = np.linspace(0, 2 * np.pi, 32, endpoint=False)
        outline = unit * np.stack([np.cos(t), np.sin(t)], axis=1)
        return ShapeSpec(name, unit, np.zeros((0, 4)), outline, unit, np.zeros(2), 0.5 * unit**2)
    outline_u, rects_u = _TABLE[name]
    outline = unit * np.asarray(outline_u, np.float64)
    rects = unit * np.asarray(rects_u, np.float64)
    if name == "tee":  # the original PushT block (see the module docstring)
        cog = np.array([0.0, 1.5 * unit])
        moment = 2 * (5.0 / 3.0) * unit**2
    else:
        cog, moment = _physical(rects)
    outline.setflags(write=False)
    rects.setflags(write=False)
    cog.setflags(write=False)
    return ShapeSpec(name, unit, rects, outline, None, cog, float(moment))


def distance_to_shape(spec: ShapeSpec, p: np.ndarray) -> np.ndarray:
    """Distance of local points ``(N, 2)`` to the shape (0 inside); ``(N,)``."""
    p = np.asarray(p, np.float64).reshape(-1, 2)
    if spec.radius is not None:
        return np.maximum(np.linalg.norm(p, axis=1) - spec.radius, 0.0)
    lo, hi = spec.rects[None, :, :2], spec.rects[None, :, 2:]
    d = np.maximum(np.maximum(lo - p[:, None], p[:, None] - hi), 0.0)
    return np.sqrt((d**2).sum(-1)).min(1)


def angle_error(a, b, symmetry: int = 1):
    """``|a - b|`` wrapped to [0, pi / symmetry] (array-friendly); 0 when ``symmetry`` is 0."""
    d = np.asarray(a, np.float64) - np.asarray(b, np.float64)
    if symmetry == 0:
        return np.zeros_like(d)
    period = 2 * np.pi / symmetry
    d = np.mod(d, period)
    return np.minimum(d, period - d)


def rotation(angle: float) -> np.ndarray:
    """The 2x2 matrix ``R`` with ``world = R @ local`` (pymunk's convention)."""
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[c, -s], [s, c]])


def to_world(points: np.ndarray, position: np.ndarray, angle: float) -> np.ndarray:
    """Local ``(N, 2)`` points of a body at ``position`` / ``angle`` in world coordinates."""
    return np.asarray(points, np.float64) @ rotation(angle).T + np.asarray(position, np.float64)

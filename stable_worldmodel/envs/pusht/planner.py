"""Geometry of the PushT expert, in the block's local frame (pure numpy).

- :func:`contact_plan`: points on the block's outline where the agent can push, with the
  inward push direction and the block twist that a unit push there produces. Frictionless
  quasi-static pushing (the dynamics of :mod:`.physics`): a push of depth ``s`` along ``d`` at
  ``r`` from the centre of gravity moves the block by ``s d / k`` and turns it by
  ``s (r x d) / (I k)`` with ``k = 1 + (r x d)^2 / I`` (mass 1).
- :class:`Obstacle`: the block's convex hull grown by the agent's radius plus a margin, with
  :meth:`Obstacle.next_waypoint` giving the first corner of the shortest path around it.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from .shapes import ShapeSpec, distance_to_shape

SPACING = 5.0  # distance between contact candidates along the outline
PRE_MARGIN = 8.0  # gap between agent and block at the pre-contact point
NAV_MARGIN = 4.0  # gap kept between agent and the block's hull while travelling


def convex_hull(points: np.ndarray) -> np.ndarray:
    """Counter-clockwise (in a y-up frame) hull of ``(N, 2)`` points (monotone chain)."""
    pts = sorted(set(map(tuple, np.round(np.asarray(points, np.float64), 9))))
    if len(pts) < 3:
        return np.asarray(pts)

    def half(seq):
        out: list = []
        for p in seq:
            while (
                len(out) >= 2
                and (out[-1][0] - out[-2][0]) * (p[1] - out[-2][1]) - (out[-1][1] - out[-2][1]) * (p[0] - out[-2][0])
                <= 0
            ):
                out.pop()
            out.append(p)
        return out

    lower, upper = half(pts), half(reversed(pts))
    return np.asarray(lower[:-1] + upper[:-1], np.float64)


class Obstacle:
    """A convex polygon to travel around: ``hull`` grown by ``margin`` (mitred corners)."""

    def __init__(self, hull: np.ndarray, margin: float):
        edges = np.roll(hull, -1, axis=0) - hull
        normals = np.stack([edges[:, 1], -edges[:, 0]], axis=1)
        normals /= np.linalg.norm(normals, axis=1, keepdims=True)
        center = hull.mean(0)
        if np.mean(((hull - center) * normals).sum(1)) < 0:  # make normals point outwards
            normals = -normals
        self.normals = normals
        self.offsets = (hull * normals).sum(1) + margin
        prev = np.roll(normals, 1, axis=0)  # normal of the edge ending at each vertex
        bis = prev + normals
        bis /= np.linalg.norm(bis, axis=1, keepdims=True)
        cos_half = np.clip((bis * normals).sum(1), 0.3, 1.0)
        self.corners = hull + bis * ((margin + 1.5) / cos_half)[:, None]  # waypoints, just outside

    def depth(self, p: np.ndarray) -> np.ndarray:
        """Signed distance outside the grown hull (negative inside) of points ``(N, 2)``."""
        return (np.asarray(p).reshape(-1, 2) @ self.normals.T - self.offsets).max(1)

    def blocked(self, a: np.ndarray, b: np.ndarray, eps: float = 0.5) -> np.ndarray:
        """Whether each segment ``a[i] -> b[i]`` crosses the grown hull's interior (Cyrus-Beck)."""
        a, b = np.asarray(a).reshape(-1, 2), np.asarray(b).reshape(-1, 2)
        num = self.offsets[None] - eps - a @ self.normals.T  # (S, M): inside iff num - t*den >= 0
        den = (b - a) @ self.normals.T
        with np.errstate(divide="ignore", invalid="ignore"):
            t = num / den
        t0 = np.where(den < 0, t, -np.inf).max(1, initial=0.0)
        t1 = np.where(den > 0, t, np.inf).min(1, initial=1.0)
        never = ((den == 0) & (num < 0)).any(1)
        return (t0 < t1) & ~never

    def next_waypoint(self, a: np.ndarray, b: np.ndarray, valid: np.ndarray | None = None) -> np.ndarray:
        """First point to head for on the shortest path from ``a`` to ``b`` around the hull.

        ``valid`` masks out corners that must not be used (e.g. off the table).
        """
        if not self.blocked(a, b)[0] or self.depth(b)[0] < 0:
            return b
        corners = self.corners if valid is None else self.corners[valid]
        nodes = np.vstack([a[None], corners, b[None]])
        n = len(nodes)
        i, j = np.triu_indices(n, 1)
        free = ~self.blocked(nodes[i], nodes[j])
        dist = np.full((n, n), np.inf)
        length = np.linalg.norm(nodes[i] - nodes[j], axis=1)
        dist[i[free], j[free]] = length[free]
        dist[j[free], i[free]] = length[free]
        np.fill_diagonal(dist, 0.0)
        for k in range(n):  # Floyd-Warshall on a dozen nodes
            dist = np.minimum(dist, dist[:, k : k + 1] + dist[k : k + 1, :])
        first = np.linalg.norm(nodes[1:] - a, axis=1) + dist[1:, -1]
        first[~np.isfinite(dist[0, 1:])] = np.inf
        direct = np.isfinite(dist[0, 1:]) & (dist[0, 1:] == np.linalg.norm(nodes[1:] - a, axis=1))
        first[~direct] = np.inf
        if not np.isfinite(first).any():
            return b
        return nodes[1 + int(np.argmin(first))]


@dataclass(frozen=True)
class ContactPlan:
    """Push candidates of one (block, agent size) pair, in the block's local frame."""

    points: np.ndarray  # (N, 2) contact points on the outline
    normals: np.ndarray  # (N, 2) outward normals (the agent pushes along -normal)
    pre: np.ndarray  # (N, 2) where the agent waits before pushing
    origin_twist: np.ndarray  # (N, 2) motion of the body origin per unit push depth
    spin: np.ndarray  # (N,) rotation per unit push depth (rad)
    obstacle: Obstacle


def _outline_samples(spec: ShapeSpec) -> tuple[np.ndarray, np.ndarray]:
    if spec.radius is not None:
        t = np.linspace(0, 2 * np.pi, max(int(2 * np.pi * spec.radius / SPACING), 8), endpoint=False)
        n = np.stack([np.cos(t), np.sin(t)], axis=1)
        return spec.radius * n, n
    poly = spec.outline
    pts, nrm = [], []
    for a, b in zip(poly, np.roll(poly, -1, axis=0), strict=False):
        e = b - a
        length = float(np.linalg.norm(e))
        n = np.array([e[1], -e[0]]) / length
        k = max(int(np.ceil(length / SPACING)), 1)
        t = (np.arange(k) + 0.5) / k
        pts.append(a + t[:, None] * e)
        nrm.append(np.repeat(n[None], k, axis=0))
    return np.vstack(pts), np.vstack(nrm)


@lru_cache(maxsize=64)
def contact_plan(spec: ShapeSpec, agent_radius: float) -> ContactPlan:
    """Push candidates for a block ``spec`` and a disk agent of ``agent_radius`` (cached)."""
    p, n = _outline_samples(spec)
    n = np.where((distance_to_shape(spec, p + 0.5 * n) < 0.25)[:, None], -n, n)  # point outwards
    pre = p + n * (agent_radius + PRE_MARGIN)
    hull = convex_hull(spec.outline)
    obstacle = Obstacle(hull, agent_radius + NAV_MARGIN)
    touch = p + n * agent_radius
    ok = (distance_to_shape(spec, pre) > agent_radius + PRE_MARGIN - 0.5) & (
        distance_to_shape(spec, touch) > agent_radius - 0.5
    )
    ok &= obstacle.depth(pre) > 0.5
    p, n, pre = p[ok], n[ok], pre[ok]
    d = -n
    r = p - spec.cog
    rxd = r[:, 0] * d[:, 1] - r[:, 1] * d[:, 0]
    k = 1.0 + rxd**2 / spec.moment
    spin = rxd / (spec.moment * k)
    origin = d / k[:, None] + np.stack([spin * spec.cog[1], -spin * spec.cog[0]], axis=1)
    return ContactPlan(p, n, pre, origin, spin, obstacle)

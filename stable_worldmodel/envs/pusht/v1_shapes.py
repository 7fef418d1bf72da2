"""Bodies of ``swm/PushT-v1`` as upstream 0.1.1 builds them (pymunk imported lazily).

Upstream's shape names, in the order of its ``agent.shape`` / ``block.shape`` factors:
``("o", "L", "T", "Z", "square", "I", "small_tee", "+")``. A shape is a list of parts whose
vertices are given in units of the ``scale`` factor (pymunk takes the convex hull of each part):

==========  ================================================================  ==============
name        parts (units of scale s)                                           moment
==========  ================================================================  ==============
o           disk of radius 0.375 s (kinematic body)                            -
L           [0, 1]x[0, 2] + [0, 2]x[-1, 0]                                     sum of parts
T           bar [-2, 2]x[0, 1] + stem [-0.5, 0.5]x[1, 4], s fixed at 30        2 x the bar
Z           [0, 2]x[0, 1] + [-1, 1]x[-1, 0]                                    sum of parts
square      [-1, 1]^2                                                          the part
I           [-0.5, 0.5]x[-2, 2]                                                the part
small_tee   [-1.5, 1.5]x[0, 1] + [-0.5, 0.5]x[1, 2]                            sum of parts
\\+          [-1.5, 1.5]x[-0.5, 0.5] + [-0.5, 0.5]x[0.5, 1.5] + mirror           3 x the bar
==========  ================================================================  ==============

Every polygon shape makes a dynamic body of mass 1 (also when used as the agent) whose centre
of gravity is the mean of its parts' centroids; ``moment_for_poly`` is taken about the body
origin, part by part, as upstream does.
"""

from __future__ import annotations

import numpy as np

V1_SHAPES: tuple[str, ...] = ("o", "L", "T", "Z", "square", "I", "small_tee", "+")
CIRCLE_RADIUS = 0.375  # x scale
TEE_SCALE = 30.0  # upstream's T ignores the scale factor


def _rect(x0: float, y0: float, x1: float, y1: float) -> list[tuple[float, float]]:
    return [(x0, y1), (x1, y1), (x1, y0), (x0, y0)]


# name: (parts in units of s, indices of the parts whose moments add up to the body's moment)
_TABLE: dict[str, tuple[list[list[tuple[float, float]]], tuple[int, ...]]] = {
    "L": ([_rect(0, 0, 1, 2), _rect(0, -1, 2, 0)], (0, 1)),
    "T": ([_rect(-2, 0, 2, 1), _rect(-0.5, 1, 0.5, 4)], (0, 0)),
    "Z": ([_rect(0, 0, 2, 1), _rect(-1, -1, 1, 0)], (0, 1)),
    "square": ([_rect(-1, -1, 1, 1)], (0,)),
    "I": ([_rect(-0.5, -2, 0.5, 2)], (0,)),
    "small_tee": ([_rect(-1.5, 0, 1.5, 1), _rect(-0.5, 1, 0.5, 2)], (0, 1)),
    "+": ([_rect(-1.5, -0.5, 1.5, 0.5), _rect(-0.5, 0.5, 0.5, 1.5), _rect(-0.5, -1.5, 0.5, -0.5)], (0, 0, 0)),
}


def shape_parts(name: str, scale: float) -> list[np.ndarray]:
    """The local ``(4, 2)`` vertex arrays of shape ``name`` (not the circle) at ``scale``."""
    s = TEE_SCALE if name == "T" else float(scale)
    return [np.asarray(part, np.float64) * s for part in _TABLE[name][0]]


def make_body(space, name: str, scale: float):
    """Add a body of upstream shape ``name`` at the origin of ``space``; return it."""
    import pymunk

    if name == "o":
        body = pymunk.Body(body_type=pymunk.Body.KINEMATIC)
        space.add(body, pymunk.Circle(body, CIRCLE_RADIUS * float(scale)))
        return body
    parts = shape_parts(name, scale)
    moment = sum(pymunk.moment_for_poly(1.0, [tuple(p) for p in parts[i]]) for i in _TABLE[name][1])
    body = pymunk.Body(1.0, moment)
    shapes = [pymunk.Poly(body, [tuple(p) for p in part]) for part in parts]
    cog = np.mean([tuple(s.center_of_gravity) for s in shapes], axis=0)
    body.center_of_gravity = (float(cog[0]), float(cog[1]))
    space.add(body, *shapes)
    return body


def body_outline(body) -> tuple[float | None, list[np.ndarray]]:
    """``(radius, polygons)`` of a body in its local frame: a disk radius, or the hull polygons."""
    import pymunk

    radius, polys = None, []
    for shape in body.shapes:
        if isinstance(shape, pymunk.Circle):
            radius = float(shape.radius)
        else:
            polys.append(np.array([tuple(v) for v in shape.get_vertices()], np.float64))
    return radius, polys

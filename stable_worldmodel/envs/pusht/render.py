"""Drawing of a PushT scene straight at the requested resolution (anti-aliased, headless).

World units (the 512x512 table) map linearly to pixels; the layers are, back to front:
background, goal silhouette (the block's shape at the goal pose), block, agent.
"""

from __future__ import annotations

from collections.abc import Sequence
from functools import lru_cache

import numpy as np

from .. import utils as draw
from .physics import WINDOW
from .shapes import ShapeSpec, to_world


def draw_body(img: np.ndarray, spec: ShapeSpec, position, angle: float, color: Sequence[int]) -> None:
    """Fill the shape ``spec`` posed at ``position`` / ``angle`` (world units) into ``img``."""
    scale = np.array([img.shape[1] / WINDOW, img.shape[0] / WINDOW])
    if spec.radius is not None:
        draw.fill_circle(img, np.asarray(position, np.float64) * scale, spec.radius * scale[0], color)
        return
    draw.fill_polygon(img, to_world(spec.outline, position, angle) * scale, color)


@lru_cache(maxsize=16)
def _background(size: tuple[int, int], color: tuple[int, int, int]) -> np.ndarray:
    img = draw.new_canvas(size, color)
    img.setflags(write=False)
    return img


def draw_scene(
    size: tuple[int, int],
    background: Sequence[int],
    goal: tuple[ShapeSpec, np.ndarray, float, Sequence[int]] | None,
    block: tuple[ShapeSpec, np.ndarray, float, Sequence[int]],
    agent: tuple[ShapeSpec, np.ndarray, float, Sequence[int]],
) -> np.ndarray:
    """An ``(H, W, 3)`` uint8 frame; each body is ``(spec, position, angle, color)``."""
    img = _background(tuple(size), tuple(int(c) for c in background)).copy()
    for body in (goal, block, agent):
        if body is not None:
            draw_body(img, *body)
    return img

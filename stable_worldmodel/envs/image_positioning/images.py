"""Procedurally generated images (sprites) for ImagePositioning; nothing is downloaded.

A sprite is a square tile of side 1 centred at the origin (local coordinates in
``[-0.5, 0.5]^2``, ``y`` down) holding a few coloured polygons. Every sprite carries a
marker triangle in its top-left corner, so that no rotation maps a sprite onto itself and
the angle can be read from an image. The set is a pure function of ``(seed, n)``.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property, lru_cache

import numpy as np

from .. import utils

_TILE = np.array([[-0.5, -0.5], [0.5, -0.5], [0.5, 0.5], [-0.5, 0.5]])


@dataclass(frozen=True, eq=False)
class Sprite:
    """A tile colour plus polygons ``(K, 2)`` in tile units, each with its RGB colour."""

    tile_color: tuple[int, int, int]
    parts: tuple[tuple[np.ndarray, tuple[int, int, int]], ...]

    @cached_property
    def packed(self) -> tuple[np.ndarray, np.ndarray, tuple[tuple[int, int, int], ...]]:
        """Tile and part vertices stacked ``(sum K, 2)``, the split indices, and the colours."""
        polys = [_TILE, *(poly for poly, _ in self.parts)]
        splits = np.cumsum([len(p) for p in polys])[:-1]
        return np.concatenate(polys), splits, (self.tile_color, *(c for _, c in self.parts))


def _regular_polygon(k: int, radius: float, phase: float) -> np.ndarray:
    t = phase + 2 * np.pi * np.arange(k) / k
    return radius * np.stack([np.cos(t), np.sin(t)], axis=1)


def _color(rng: np.random.Generator, avoid: np.ndarray | None = None) -> tuple[int, int, int]:
    """A random saturated colour, at least some distance away from ``avoid``."""
    for _ in range(32):
        c = rng.integers(0, 256, 3)
        c[rng.integers(3)] = rng.integers(0, 60)  # one dark channel: saturated colours
        if avoid is None or np.abs(c - avoid).sum() > 180:
            break
    return int(c[0]), int(c[1]), int(c[2])


def _sprite(rng: np.random.Generator) -> Sprite:
    tile = _color(rng)
    tile_arr = np.array(tile)
    marker = np.array([[-0.5, -0.5], [0.05, -0.5], [-0.5, 0.05]])  # top-left corner triangle
    parts = [(marker, _color(rng, tile_arr))]
    for _ in range(int(rng.integers(1, 4))):
        k = int(rng.choice([3, 4, 5, 12]))  # triangle, square, pentagon, disk
        radius = float(rng.uniform(0.1, 0.22))
        center = rng.uniform(-0.25, 0.25, 2) + np.array([0.05, 0.05])
        poly = _regular_polygon(k, radius, float(rng.uniform(0, 2 * np.pi))) + center
        parts.append((np.clip(poly, -0.5, 0.5), _color(rng, tile_arr)))
    return Sprite(tile, tuple(parts))


@lru_cache(maxsize=64)
def make_sprites(seed: int, n: int) -> tuple[Sprite, ...]:
    """``n`` sprites drawn from a generator seeded with ``seed`` (cached)."""
    rng = np.random.default_rng([int(seed), 0x51A7E])
    return tuple(_sprite(rng) for _ in range(n))


def draw_sprite(img: np.ndarray, sprite: Sprite, center: np.ndarray, angle: float, side: float) -> None:
    """Draw ``sprite`` into ``img`` (H, W, 3) with its centre at ``center`` (canvas units in [0, 1]).

    ``side`` is the tile side in canvas units; ``angle`` (radians) turns the tile clockwise on
    screen.
    """
    points, splits, colors = sprite.packed
    px = utils.world_to_pixels(utils.rotate(points * side, angle) + center, 1.0, img.shape[:2])
    for poly, color in zip(np.split(px, splits), colors, strict=False):
        utils.fill_polygon(img, poly, color)

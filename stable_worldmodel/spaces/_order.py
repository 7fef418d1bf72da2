"""Setting ``Dict.sampling_order``: one list of dotted paths spread over the Dicts of a tree.

Each Dict keeps its own ``_order`` (its child keys); sampling walks the tree in those orders,
so a Dict's subtree is always drawn at once. ``Dict.sampling_order`` reads back every node path
in that walk, nested Dicts included::

    root: z, game, a            game: level, world, speed        world: w, h
    set  ["a", "game.world.h"]  ->  root: a, game, z   game: world, level, speed   world: h, w
    read ["a", "game", "game.world", "game.world.h", "game.world.w", "game.level", "game.speed", "z"]
"""

from __future__ import annotations

from collections.abc import Iterable
from typing import Any

from ..errors import SpaceError, did_you_mean
from ._report import warn

__all__ = ["apply_sampling_order"]


def apply_sampling_order(root: Any, order: Iterable[str]) -> None:
    """Reorder the Dicts of ``root`` (a ``Dict``) so that the paths in ``order`` are sampled in that order.

    ``order`` holds top-level keys and/or dotted node paths, as ``root.sampling_order`` lists them.
    Each Dict samples its children in the order of their first mention; the children it does not
    mention follow in their current order, with one warning, in every Dict that ``order`` reaches
    (``root`` always). Dicts it does not reach keep their order. Unknown, repeated or interleaved
    paths (``["g.x", "a", "g.y"]`` would split Dict ``g``) raise SpaceError and change nothing.
    """
    if isinstance(order, str) or not isinstance(order, Iterable):
        raise SpaceError(f"Dict requires sampling_order as a list of keys or dotted paths, got {order!r}")
    paths = list(order)
    known = list(root._node_paths())
    unknown = [p for p in paths if not isinstance(p, str) or root._lookup(p) is None]
    if unknown:
        hint = "".join(did_you_mean(str(path), known) for path in unknown)
        raise SpaceError(
            f"Dict requires sampling_order paths of this space, got unknown {unknown}.{hint} Known: {known}"
        )
    repeated = sorted({p for p in paths if paths.count(p) > 1})
    if repeated:
        raise SpaceError(f"Dict requires sampling_order without repeated paths, got {repeated} more than once")

    mentioned: dict[str, list[str]] = {"": []}  # Dict path prefix ("" or "game.") -> children by first mention
    for path in paths:
        parts = path.split(".")
        for depth, key in enumerate(parts):
            children = mentioned.setdefault("".join(f"{part}." for part in parts[:depth]), [])
            if key not in children:
                children.append(key)
    new_orders: list[tuple[Any, list[str]]] = []
    missing: list[str] = []
    for prefix, children in mentioned.items():
        node = root._lookup(prefix[:-1]) if prefix else root
        rest = [key for key in node._order if key not in children]
        missing += [prefix + key for key in rest]
        new_orders.append((node, children + rest))

    old_orders = [(node, node._order) for node, _ in new_orders]
    for node, keys in new_orders:
        node._order = keys
    result = root.sampling_order
    positions = [result.index(p) for p in paths]
    if positions != sorted(positions):
        for node, keys in old_orders:
            node._order = keys
        raise SpaceError(
            f"Dict requires sampling_order to keep each nested Dict's paths together (a Dict samples its subtree "
            f"at once), got {paths}; the closest order it can take is {result}"
        )
    if missing:
        warn(f"Dict sampling_order does not name {missing}; sampling them last, in their current order")

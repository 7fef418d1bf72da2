"""Random perfect mazes by Eller's algorithm, as release 0.0.3's ``simple_nav.env.ellers_maze`` draws them.

The grid is ``width`` x ``height`` (both odd, >= 3) cells indexed ``[y, x]``. Maze *rooms* sit at
odd coordinates ``(2 i + 1, 2 j + 1)``; the cells between two rooms are walls unless the
algorithm opens them, and the outer ring is always wall. Rooms are processed row by row, each
room labelled with the set of rooms it is already connected to:

1. rooms of the row without a label get fresh labels (left to right);
2. (not on the last row) each pair of side-by-side rooms with different labels is joined with
   probability ``p_horizontal`` (one ``rng.random()`` per such pair, left to right); joining
   relabels the right room's set with the left one's;
3. (not on the last row) for every set present in the row (in the order of its leftmost room),
   its rooms are shuffled (``rng.shuffle``) and each opens downwards with probability
   ``p_vertical`` (one ``rng.random()`` per room), the last one always, so every set goes on;
   the rooms below inherit the label;
4. on the last row every pair of side-by-side rooms with different labels is joined (no draws).

The result is a spanning tree of the rooms: exactly one path between any two open cells. The
draws come from ``numpy.random.default_rng(seed)`` in the order above, so a given
``(seed, p_horizontal, p_vertical)`` gives 0.0.3's maze.
"""

from __future__ import annotations

import numpy as np

from ...errors import ConfigError


def check_maze_size(owner: str, width: int, height: int) -> None:
    """ConfigError naming ``owner`` unless both sides are odd ints >= 3."""
    for name, side in (("width", width), ("height", height)):
        if isinstance(side, bool) or not isinstance(side, (int, np.integer)) or side < 3 or side % 2 == 0:
            raise ConfigError(f"{owner} requires an odd maze {name} >= 3, got {side!r}")


def maze_walls(
    width: int, height: int, seed: int | None = None, p_horizontal: float = 0.5, p_vertical: float = 0.5
) -> np.ndarray:
    """The maze as a ``(height, width)`` bool array, True on walls (the outer ring included)."""
    check_maze_size("maze_walls", width, height)
    for name, p in (("p_horizontal", p_horizontal), ("p_vertical", p_vertical)):
        if not 0.0 <= float(p) <= 1.0:
            raise ConfigError(f"maze_walls requires {name} in [0, 1], got {p!r}")
    p_join, p_down = float(p_horizontal), float(p_vertical)
    rng = np.random.default_rng(seed)
    cols, rows = (width - 1) // 2, (height - 1) // 2
    wall = np.ones((height, width), bool)
    label = [0] * cols  # the set of each room of the current row (0: none yet)
    fresh = 1

    def join(i: int, y: int) -> None:
        """Open the wall between rooms ``i`` and ``i + 1`` of grid row ``y``; merge their sets."""
        wall[y, 2 * i + 2] = False
        gone, kept = label[i + 1], label[i]
        for k in range(cols):
            if label[k] == gone:
                label[k] = kept

    for j in range(rows):
        y = 2 * j + 1
        for i in range(cols):
            if label[i] == 0:
                label[i], fresh = fresh, fresh + 1
            wall[y, 2 * i + 1] = False
        last = j == rows - 1
        for i in range(cols - 1):
            if label[i] != label[i + 1] and (last or rng.random() < p_join):
                join(i, y)
        if last:
            break
        members: dict[int, list[int]] = {}
        for i in range(cols):
            members.setdefault(label[i], []).append(i)
        below = [0] * cols
        for name, rooms in members.items():
            order = list(rooms)
            rng.shuffle(order)
            for n, i in enumerate(order):
                if rng.random() < p_down or n == len(order) - 1:
                    wall[y + 1, 2 * i + 1] = False
                    below[i] = name
        label = below
    return wall


def ellers_maze(
    width: int, height: int, seed: int | None = None, p_horizontal: float = 0.5, p_vertical: float = 0.5
) -> list[tuple[int, int]]:
    """0.0.3's function: the ``(x, y)`` wall cells inside the outer ring, row by row."""
    wall = maze_walls(width, height, seed, p_horizontal, p_vertical)
    ys, xs = np.nonzero(wall[1:-1, 1:-1])
    return [(int(x) + 1, int(y) + 1) for y, x in zip(ys, xs, strict=True)]

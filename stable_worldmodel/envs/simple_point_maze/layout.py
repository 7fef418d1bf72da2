"""Maze layouts of SimplePointMaze and the grid queries shared by the env and its expert.

A layout is a square grid of strings: ``#`` wall, ``.`` free. Cell ``(i, j)`` (row, column)
spans ``[j, j + 1] x [i, i + 1]`` in world units (x right, y down).
"""

from __future__ import annotations

from collections import deque
from functools import cached_property

import numpy as np


class Maze:
    """One layout with its wall rectangles, free cells and shortest path lengths (BFS, 4-connected)."""

    def __init__(self, rows: tuple[str, ...]):
        self.grid = np.array([[c == "#" for c in row] for row in rows], bool)
        if self.grid.shape[0] != self.grid.shape[1]:
            raise ValueError(f"Maze requires a square grid, got shape {self.grid.shape}")
        self.size = self.grid.shape[0]
        self.free_cells = [tuple(c) for c in np.argwhere(~self.grid)]
        self.index = {c: k for k, c in enumerate(self.free_cells)}

    @cached_property
    def wall_boxes(self) -> np.ndarray:
        """Walls as ``(N, 4)`` rectangles ``x0, y0, x1, y1``, horizontal runs merged."""
        boxes = []
        for i, row in enumerate(self.grid):
            j = 0
            while j < self.size:
                if row[j]:
                    k = j
                    while k < self.size and row[k]:
                        k += 1
                    boxes.append((j, i, k, i + 1))
                    j = k
                else:
                    j += 1
        return np.array(boxes, np.float64)

    @cached_property
    def distances(self) -> np.ndarray:
        """``(F, F)`` path lengths in cells between free cells (``F`` free cells; large if unreachable)."""
        n = len(self.free_cells)
        out = np.full((n, n), 10**6, np.int64)
        for src in range(n):
            out[src, src] = 0
            queue = deque([self.free_cells[src]])
            while queue:
                i, j = queue.popleft()
                for nb in ((i + 1, j), (i - 1, j), (i, j + 1), (i, j - 1)):
                    k = self.index.get(nb)
                    if k is not None and out[src, k] > out[src, self.index[(i, j)]] + 1:
                        out[src, k] = out[src, self.index[(i, j)]] + 1
                        queue.append(nb)
        return out

    def cell(self, pos: np.ndarray) -> tuple[int, int]:
        """The (row, column) holding world point ``pos`` = (x, y), clipped to the grid."""
        j, i = np.clip(np.floor(np.asarray(pos, np.float64)).astype(int), 0, self.size - 1)
        return int(i), int(j)

    def centre(self, cell: tuple[int, int]) -> np.ndarray:
        """World (x, y) of the centre of ``cell`` = (row, column)."""
        return np.array([cell[1] + 0.5, cell[0] + 0.5])

    def is_wall(self, pos: np.ndarray) -> bool:
        return bool(self.grid[self.cell(pos)])

    def path(self, start: tuple[int, int], goal: tuple[int, int]) -> list[tuple[int, int]]:
        """Cells of a shortest path from ``start`` to ``goal`` (both included; ``[start]`` if unreachable)."""
        if start not in self.index or goal not in self.index:
            return [start]
        dist = self.distances[self.index[goal]]
        cells = [start]
        while cells[-1] != goal and dist[self.index[cells[-1]]] < 10**6:
            i, j = cells[-1]
            nbs = [c for c in ((i + 1, j), (i - 1, j), (i, j + 1), (i, j - 1)) if c in self.index]
            cells.append(min(nbs, key=lambda c: dist[self.index[c]]))
        return cells


LAYOUTS: tuple[Maze, ...] = (
    Maze(("#######", "#...#.#", "#.#.#.#", "#.#...#", "#.###.#", "#.....#", "#######")),
    Maze(("#######", "#.....#", "#####.#", "#.....#", "#.#####", "#.....#", "#######")),
    Maze(("#######", "#.....#", "#.#.#.#", "#.....#", "#.#.#.#", "#.....#", "#######")),
)
"""Layout 0 (default) has branches and a dead end, 1 is a snake, 2 is an open grid of pillars."""

"""The OGBench mazes as data: maps, tasks, teleports, cell geometry and shortest paths.

Pure numpy (no simulator import): the env (:mod:`.maze_env`) builds its walls from it and the
expert (:mod:`.maze_expert`) plans on it. Maps and tasks are OGBench's (``ogbench.locomaze.maze``):
``#`` is a wall block of ``unit`` x ``unit`` (4 m by default), ``.`` a free cell; cell ``(i, j)``
(row, column) has its centre at ``x = j * unit - 4``, ``y = i * unit - 4``.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass

import numpy as np

from ...errors import ConfigError, did_you_mean

OFFSET = 4.0  # OGBench's _offset_x / _offset_y (whatever the unit)
NOISE = 1.0  # OGBench's _noise: start / goal jitter of +-NOISE * unit / 4 per axis

MAPS: dict[str, tuple[str, ...]] = {
    "arena": (
        "########",
        "#......#",
        "#......#",
        "#......#",
        "#......#",
        "#......#",
        "#......#",
        "########",
    ),
    "medium": (
        "########",
        "#..##..#",
        "#..#...#",
        "##...###",
        "#..#...#",
        "#.#..#.#",
        "#...#..#",
        "########",
    ),
    "large": (
        "############",
        "#....#.....#",
        "#.##.#.#.#.#",
        "#......#...#",
        "#.####.###.#",
        "#..#.#.....#",
        "##.#.#.#.###",
        "#..#...#...#",
        "############",
    ),
    "giant": (
        "################",
        "#.#......##....#",
        "#.#.##.#.#..##.#",
        "#...#..#...#...#",
        "#.###.######.#.#",
        "#...#...#....#.#",
        "###.#.#..#.#.###",
        "#...#..#...#...#",
        "#.#.#.######.#.#",
        "#.###...#...##.#",
        "#.....#...#....#",
        "################",
    ),
    "teleport": (
        "############",
        "#.....#.#..#",
        "##.#...#..##",
        "##.###.....#",
        "#....#.#.#.#",
        "#.##.#.#.#.#",
        "#.##.#.#.#.#",
        "#....#...#.#",
        "############",
    ),
}
MAZE_TYPES = tuple(MAPS)

#: OGBench's evaluation tasks per maze: (start cell, goal cell); task ids count from 1
TASKS: dict[str, tuple[tuple[tuple[int, int], tuple[int, int]], ...]] = {
    "arena": (((1, 1), (6, 6)),),
    "medium": (((1, 1), (6, 6)), ((6, 1), (1, 6)), ((5, 3), (4, 2)), ((6, 5), (6, 1)), ((2, 6), (1, 1))),
    "large": (((1, 1), (7, 10)), ((5, 4), (7, 1)), ((7, 4), (1, 10)), ((3, 8), (5, 4)), ((1, 1), (5, 4))),
    "giant": (((1, 1), (10, 14)), ((1, 14), (10, 1)), ((8, 14), (1, 1)), ((8, 3), (5, 12)), ((5, 9), (3, 8))),
    "teleport": (((1, 10), (7, 1)), ((1, 1), (7, 10)), ((5, 6), (7, 10)), ((7, 1), (7, 10)), ((5, 6), (7, 1))),
}
#: OGBench's soccer tasks (``maze_env_type="ball"``): (agent start, ball start, goal) cells
BALL_TASKS: dict[str, tuple[tuple[tuple[int, int], tuple[int, int], tuple[int, int]], ...]] = {
    "arena": (
        ((1, 6), (2, 3), (5, 2)),
        ((2, 2), (5, 5), (2, 2)),
        ((6, 1), (2, 3), (6, 6)),
        ((6, 6), (1, 1), (6, 1)),
        ((4, 6), (6, 2), (1, 6)),
    ),
    "medium": (
        ((1, 1), (3, 4), (6, 6)),
        ((6, 1), (6, 5), (1, 1)),
        ((5, 3), (4, 2), (6, 5)),
        ((6, 5), (1, 1), (5, 3)),
        ((1, 6), (6, 1), (1, 6)),
    ),
}
#: the single-task default of each kind (OGBench's ``reward_task_id=0``)
DEFAULT_TASK = {"maze": 1, "ball": 4}
#: teleport maze: entering within 1.5 * radius of an inbound pad moves the agent to a random outbound one
TELEPORT_IN = ((4, 6), (5, 1))
TELEPORT_OUT = ((1, 7), (6, 1), (6, 10))
TELEPORT_RADIUS = 1.0


def check_maze_type(owner: str, maze_type: str, allowed: tuple[str, ...] = MAZE_TYPES) -> str:
    if maze_type not in allowed:
        raise ConfigError(
            f"{owner} requires maze_type in {list(allowed)}, got {maze_type!r}.{did_you_mean(str(maze_type), allowed)}"
        )
    return maze_type


@dataclass(frozen=True)
class MazeLayout:
    """One maze: its map (``grid[i, j]`` True for a wall) and the size of a cell (``unit``)."""

    maze_type: str = "large"
    unit: float = 4.0

    @property
    def grid(self) -> np.ndarray:
        return np.array([[c == "#" for c in row] for row in MAPS[self.maze_type]])

    @property
    def shape(self) -> tuple[int, int]:
        return len(MAPS[self.maze_type]), len(MAPS[self.maze_type][0])

    def ij_to_xy(self, ij) -> np.ndarray:
        i, j = ij
        return np.array([j * self.unit - OFFSET, i * self.unit - OFFSET], np.float64)

    def xy_to_ij(self, xy) -> tuple[int, int]:
        """The cell of ``xy`` (OGBench's rounding), clipped to the map."""
        h, w = self.shape
        i = int(np.floor((float(xy[1]) + OFFSET + 0.5 * self.unit) / self.unit))
        j = int(np.floor((float(xy[0]) + OFFSET + 0.5 * self.unit) / self.unit))
        return min(max(i, 0), h - 1), min(max(j, 0), w - 1)

    def free(self, ij) -> bool:
        h, w = self.shape
        i, j = ij
        return 0 <= i < h and 0 <= j < w and MAPS[self.maze_type][i][j] == "."

    def free_cells(self) -> list[tuple[int, int]]:
        h, w = self.shape
        return [(i, j) for i in range(h) for j in range(w) if self.free((i, j))]

    def wall_boxes(self) -> np.ndarray:
        """Every wall block as ``(x0, y0, x1, y1)`` rows."""
        half = self.unit / 2
        boxes = [(*(self.ij_to_xy(ij) - half), *(self.ij_to_xy(ij) + half)) for ij in self.wall_cells()]
        return np.asarray(boxes, np.float64).reshape(-1, 4)

    def wall_cells(self) -> list[tuple[int, int]]:
        h, w = self.shape
        return [(i, j) for i in range(h) for j in range(w) if not self.free((i, j))]

    def nearest_free(self, xy) -> tuple[int, int]:
        """The cell of ``xy``, or the free cell whose centre is nearest when that one is a wall."""
        ij = self.xy_to_ij(xy)
        if self.free(ij):
            return ij
        cells = self.free_cells()
        dist = [float(np.linalg.norm(self.ij_to_xy(c) - np.asarray(xy, np.float64)[:2])) for c in cells]
        return cells[int(np.argmin(dist))]

    def path(self, start, goal, avoid=()) -> list[tuple[int, int]]:
        """A shortest 4-connected path of free cells from ``start`` to ``goal`` (both included);
        ``[start]`` when the goal cannot be reached. Cells of ``avoid`` (other than ``start`` and
        ``goal``) are passed through only when no path goes around them."""
        start, goal = tuple(start), tuple(goal)
        if start == goal or not self.free(goal):
            return [start]
        avoid = {tuple(c) for c in avoid} - {start, goal}
        if avoid:
            around = self._bfs(start, goal, avoid)
            if around is not None:
                return around
        return self._bfs(start, goal, set()) or [start]

    def _bfs(self, start, goal, blocked: set) -> list[tuple[int, int]] | None:
        parent: dict[tuple[int, int], tuple[int, int] | None] = {goal: None}
        queue = deque([goal])
        while queue:  # BFS from the goal, so following parents from start walks towards it
            cell = queue.popleft()
            if cell == start:
                break
            for di, dj in ((-1, 0), (0, -1), (1, 0), (0, 1)):
                nxt = (cell[0] + di, cell[1] + dj)
                if nxt not in parent and nxt not in blocked and self.free(nxt):
                    parent[nxt] = cell
                    queue.append(nxt)
        if start not in parent:
            return None
        out = [start]
        while parent[out[-1]] is not None:
            out.append(parent[out[-1]])
        return out

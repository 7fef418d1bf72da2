"""Frames of ``swm/SimplePointMaze-v0`` drawn with matplotlib (Agg, headless), as release 0.1.1 draws them.

The scene is a 5 x 5 inch figure at 100 dpi (500 x 500 px) whose single axes spans the
world ``[0, 5]^2`` (y up, no ticks, black frame) after ``tight_layout(pad=0)``. Walls are
filled rectangles, the goal a half-transparent disk, the agent an opaque disk. A frame of
another size is the 500 x 500 frame shrunk with ``cv2.INTER_AREA``.
"""

from __future__ import annotations

import numpy as np

FIGURE_INCHES = 5.0
DPI = 100
NATIVE = int(FIGURE_INCHES * DPI)  # 500 px


class MazeCanvas:
    """One reusable matplotlib figure; :meth:`draw` returns an RGB uint8 frame."""

    def __init__(self, width: float, height: float):
        from matplotlib.backends.backend_agg import FigureCanvasAgg
        from matplotlib.figure import Figure

        self.width, self.height = float(width), float(height)
        self.figure = Figure(figsize=(FIGURE_INCHES, FIGURE_INCHES), dpi=DPI)
        FigureCanvasAgg(self.figure)
        self.axes = self.figure.add_subplot(1, 1, 1)

    def draw(self, scene: dict, size: tuple[int, int] = (NATIVE, NATIVE)) -> np.ndarray:
        """Draw ``scene`` and return an (H, W, 3) uint8 frame of ``size`` = (H, W).

        ``scene``: ``background`` (3,) uint8; ``walls``: list of ``(x, y, w, h)``; ``wall_color``;
        ``goal``: ``(center, radius, color)`` or None; ``agent``: ``(center, radius, color)``.
        """
        from matplotlib.patches import Circle, Rectangle

        ax = self.axes
        ax.clear()
        ax.set_xlim(0, self.width)
        ax.set_ylim(0, self.height)
        ax.set_aspect("equal")
        ax.set_xticks([])
        ax.set_yticks([])
        ax.set_facecolor(np.asarray(scene["background"]) / 255.0)
        wall_color = np.asarray(scene["wall_color"]) / 255.0
        for x, y, w, h in scene["walls"]:
            ax.add_patch(Rectangle((x, y), w, h, facecolor=wall_color))
        if scene.get("goal") is not None:
            center, radius, color = scene["goal"]
            ax.add_patch(Circle(center, radius, facecolor=np.asarray(color) / 255.0, alpha=0.5))
        center, radius, color = scene["agent"]
        ax.add_patch(Circle(center, radius, facecolor=np.asarray(color) / 255.0))
        self.figure.tight_layout(pad=0)
        self.figure.canvas.draw()
        frame = np.asarray(self.figure.canvas.buffer_rgba())[:, :, :3].copy()
        h, w = size
        if frame.shape[:2] != (h, w):
            import cv2

            frame = cv2.resize(frame, (w, h), interpolation=cv2.INTER_AREA)
        return frame

    def close(self) -> None:
        self.figure.clear()

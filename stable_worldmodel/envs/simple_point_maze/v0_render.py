"""Frames of ``swm/SimplePointMaze-v0`` drawn with matplotlib (Agg, headless), as release 0.1.1 draws them.

The scene is a 5 x 5 inch figure at 100 dpi (500 x 500 px) whose single axes spans the
world ``[0, 5]^2`` (y up, no ticks, black frame) after ``tight_layout(pad=0)``. Walls are
filled rectangles, the goal a half-transparent disk, the agent an opaque disk. A frame of
another size is the 500 x 500 frame shrunk with ``cv2.INTER_AREA``.

Matplotlib takes ~15 ms a frame, so it draws only what does not move in an episode (background,
walls, goal, frame), once; each frame then blends the agent's disk into that layer with
antialiasing by pixel coverage (``clip(r - d + 1/2, 0, 1)`` at the pixel centre), which differs
from Agg's only on the disk's edge pixels: frames within 0.05/255 mean absolute difference of
drawing everything with matplotlib (:meth:`MazeCanvas.draw_full`, tested).
"""

from __future__ import annotations

import numpy as np

FIGURE_INCHES = 5.0
DPI = 100
NATIVE = int(FIGURE_INCHES * DPI)  # 500 px
#: pixels from the image edge where the axes frame (0.8 pt, drawn last) may cover the agent
_FRAME_PX = 3


class MazeCanvas:
    """One reusable matplotlib figure; :meth:`draw` returns an RGB uint8 frame."""

    def __init__(self, width: float, height: float):
        from matplotlib.backends.backend_agg import FigureCanvasAgg
        from matplotlib.figure import Figure

        self.width, self.height = float(width), float(height)
        self.figure = Figure(figsize=(FIGURE_INCHES, FIGURE_INCHES), dpi=DPI)
        FigureCanvasAgg(self.figure)
        self.axes = self.figure.add_subplot(1, 1, 1)
        self._static: np.ndarray | None = None  # the layer under the agent, drawn once per scene
        self._static_key: tuple | None = None
        self._transform: tuple[np.ndarray, np.ndarray] | None = None
        self._under: np.ndarray | None = None  # the static layer without the axes frame
        self._small: tuple[tuple[int, int], np.ndarray] | None = None  # the static layer resized
        self._frame_alpha: np.ndarray | None = None  # the axes frame's opacity, (500, 500, 1)

    def draw(self, scene: dict, size: tuple[int, int] = (NATIVE, NATIVE)) -> np.ndarray:
        """Draw ``scene`` and return an (H, W, 3) uint8 frame of ``size`` = (H, W).

        ``scene``: ``background`` (3,) uint8; ``walls``: list of ``(x, y, w, h)``; ``wall_color``;
        ``goal``: ``(center, radius, color)`` or None; ``agent``: ``(center, radius, color)``.
        The layer under the agent is drawn by matplotlib once per scene; the agent is blended in.
        """
        key = _static_key(scene)
        if self._static_key != key:
            layer = self._render({**scene, "agent": None})
            ax = self.axes
            origin = ax.transData.transform((0.0, 0.0))
            unit = ax.transData.transform((1.0, 1.0)) - origin  # display px per world unit (x, y)
            self._static, self._static_key, self._transform = layer, key, (origin, unit)
            self._under, self._small = None, None
        center, radius, color = scene["agent"]
        origin, unit = self._transform
        x, y = origin + np.asarray(center, np.float64).reshape(2) * unit  # display px, y up
        y, r = NATIVE - y, float(np.asarray(radius).reshape(-1)[0]) * unit[0]
        frame = self._static.copy()
        if min(x, y) - r < _FRAME_PX or max(x, y) + r > NATIVE - _FRAME_PX:  # under the axes frame, drawn last
            under, alpha = self._frame_layers(scene)
            box = _blend_disk(frame, x, y, r, color, under=under, frame_alpha=alpha)
        else:
            box = _blend_disk(frame, x, y, r, color)
        blocks = _blocks(size)
        if blocks is None or box is None:
            return _shrink(frame, size)
        # OpenCV's area resize reads each block of `step` input pixels into its own `out` output
        # pixels at these sizes: only the blocks under the agent change
        h, w = int(size[0]), int(size[1])
        if self._small is None or self._small[0] != (h, w):
            self._small = ((h, w), _shrink(self._static, size))
        small = self._small[1].copy()
        (sy, oy), (sx, ox) = blocks
        y0, y1, x0, x1 = box
        y0, x0 = y0 // sy * sy, x0 // sx * sx
        y1, x1 = min(NATIVE, -(-y1 // sy) * sy), min(NATIVE, -(-x1 // sx) * sx)
        small[y0 // sy * oy : y1 // sy * oy, x0 // sx * ox : x1 // sx * ox] = _shrink(
            frame[y0:y1, x0:x1], ((y1 - y0) // sy * oy, (x1 - x0) // sx * ox)
        )
        return small

    def _frame_layers(self, scene: dict) -> tuple[np.ndarray, np.ndarray]:
        """The layer under the agent without the axes frame, and the frame's opacity per pixel
        (black over white), drawn once per scene / canvas, for agents at the frame."""
        if self._under is None:
            self._under = self._render({**scene, "agent": None}, frame=False)
        if self._frame_alpha is None:
            white = {"background": (255, 255, 255), "walls": [], "wall_color": (0, 0, 0), "goal": None, "agent": None}
            self._frame_alpha = 1.0 - self._render(white)[..., :1].astype(np.float64) / 255.0
        return self._under, self._frame_alpha

    def draw_full(self, scene: dict, size: tuple[int, int] = (NATIVE, NATIVE)) -> np.ndarray:
        """The whole frame drawn by matplotlib (what :meth:`draw` reproduces)."""
        return _shrink(self._render(scene), size)

    def _render(self, scene: dict, frame: bool = True) -> np.ndarray:
        """The scene drawn by matplotlib, 500 x 500 RGB; ``scene["agent"]`` None leaves the agent
        out, ``frame=False`` the axes frame."""
        from matplotlib.patches import Circle, Rectangle

        ax = self.axes
        ax.clear()
        for spine in ax.spines.values():
            spine.set_visible(frame)
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
        if scene.get("agent") is not None:
            center, radius, color = scene["agent"]
            ax.add_patch(Circle(center, radius, facecolor=np.asarray(color) / 255.0))
        self.figure.tight_layout(pad=0)
        self.figure.canvas.draw()
        return np.asarray(self.figure.canvas.buffer_rgba())[:, :, :3].copy()

    def close(self) -> None:
        self.figure.clear()
        self._static, self._static_key, self._under, self._small = None, None, None, None


def _static_key(scene: dict) -> tuple:
    goal = scene.get("goal")
    return (
        np.asarray(scene["background"]).tobytes(),
        tuple(tuple(float(v) for v in wall) for wall in scene["walls"]),
        np.asarray(scene["wall_color"]).tobytes(),
        None if goal is None else tuple(np.asarray(part, np.float64).tobytes() for part in goal),
    )


def _blend_disk(
    frame: np.ndarray,
    cx: float,
    cy: float,
    radius: float,
    color,
    under: np.ndarray | None = None,
    frame_alpha: np.ndarray | None = None,
) -> tuple[int, int, int, int] | None:
    """An opaque disk centred at image coordinates ``(cx, cy)`` (x right, y down, pixel ``(i, j)``
    spanning ``[j, j + 1] x [i, i + 1]``), antialiased by coverage, blended into ``frame``; with
    ``under`` (the layer without the black axes frame) and ``frame_alpha`` (its opacity), blended
    into ``under`` and darkened by the frame drawn over it. Returns the pixel box it changed,
    ``(y0, y1, x0, x1)``, or None."""
    h, w = frame.shape[:2]
    x0, x1 = max(0, int(np.floor(cx - radius - 1))), min(w, int(np.ceil(cx + radius + 1)) + 1)
    y0, y1 = max(0, int(np.floor(cy - radius - 1))), min(h, int(np.ceil(cy + radius + 1)) + 1)
    if x0 >= x1 or y0 >= y1:
        return None
    dx = np.arange(x0, x1) + 0.5 - cx
    dy = np.arange(y0, y1) + 0.5 - cy
    cover = np.clip(radius + 0.5 - np.sqrt(dy[:, None] ** 2 + dx[None, :] ** 2), 0.0, 1.0)[..., None]
    base = frame if under is None else under
    blended = base[y0:y1, x0:x1] * (1.0 - cover) + np.asarray(color, np.float64).reshape(1, 1, 3) * cover
    if frame_alpha is not None:
        blended *= 1.0 - frame_alpha[y0:y1, x0:x1]
    frame[y0:y1, x0:x1] = np.rint(blended).astype(np.uint8)
    return y0, y1, x0, x1


def _blocks(size: tuple[int, int]) -> tuple[tuple[int, int], tuple[int, int]] | None:
    """Per axis ``(step, out)``: ``step`` input pixels shrink to ``out`` output pixels of their
    own under OpenCV's area resize, for sizes whose scale from 500 is a short binary fraction
    (64, 128, 32, 250, ...: every coordinate it derives is exact). None otherwise."""
    from fractions import Fraction
    from math import gcd

    out = []
    for n in size:
        den = Fraction(NATIVE, int(n)).denominator
        if n >= NATIVE or den & (den - 1):
            return None
        g = gcd(NATIVE, int(n))
        out.append((NATIVE // g, int(n) // g))
    return out[0], out[1]


def _shrink(frame: np.ndarray, size: tuple[int, int]) -> np.ndarray:
    h, w = size
    if frame.shape[:2] == (h, w):
        return frame
    import cv2

    return cv2.resize(frame, (w, h), interpolation=cv2.INTER_AREA)

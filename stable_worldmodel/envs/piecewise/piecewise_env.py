"""``swm/Piecewise-v0``: upstream's Piecewise, a Gaussian dot in one open room whose zones push it.

Written from the behaviour of upstream's ``stable_worldmodel/envs/piecewise/piecewise_env.py``
(same id, spaces, factors, dynamics and info), so data recorded with upstream's env means the same
here:

- **World**: a ``224 x 224`` pixel square (y down) framed by 4-px border lines just outside
  ``[14, 210]``, with no inner wall. The play field ``[14, 210)^2`` is divided into a
  ``grid_n x grid_n`` grid of zones (constructor argument, default 2), numbered row by row
  (``row * grid_n + col``).
- **Step**: the action is clipped to ``[-1, 1]^2``; the agent moves by
  ``agent.speed * action + zones.bias_<k>``, ``k`` the zone of its position before the move, and
  its centre is clamped to ``[14 + r, 210 - r]`` (``r`` = ``agent.radius``).
- **Observation**: a flat ``Box(0, 224, (4,))`` float32: agent (x, y), target (x, y).
- **Success** (``terminated``): the agent centre within 16 px of the target; reward 0; never
  truncated by the env (the swm tools cut episodes at 100 steps).
- **Factors** (upstream's): ``agent.{color, radius, position, speed}``,
  ``target.{color, radius, position}``, ``background.color``, ``border.color``,
  ``rendering.{render_target, render_zones, render_bias_field}``, ``task.min_steps`` (kept for
  upstream's data tools, no effect on the dynamics) and per zone ``zones.bias_<k>`` (``[-5, 5]^2``,
  default 0) and ``zones.color_<k>`` (pastel hues). ``grid_n = 2`` gives 21 factors.
- **Reset**: the variation space is seeded with the reset seed, reset to its defaults, and
  ``agent.position`` and ``target.position`` are resampled (``options["variation"]`` names others;
  ``options["variation_values"]`` sets factors). ``options["state"]`` places the agent,
  ``options["target_state"]`` (upstream's) or ``options["goal_state"]`` the target.
- **Info**: upstream's ``env_name``, ``state`` / ``proprio`` (agent position), ``goal_state``
  (target position), ``distance_to_target``; plus ``goal`` (the frame with the agent drawn at the
  target, upstream's ``_target_img``), ``goal_proprio`` and the private ``_dynamics``
  (``[grid_n, speed, bias_0 x, bias_0 y, bias_1 x, ...]``) that the batched expert reads.
- **Rendering** (drawn directly at ``render_size``, default 224 x 224): background, zone colors
  (``render_zones``), border lines, the target dot (``render_target`` or the constructor's
  ``render_target``), the bias arrows (``render_bias_field``), the agent dot. Rectangles are drawn
  with their exact pixel coverage, dots are Gaussians (std = radius, peak normalised to 1 on the
  pixel grid) alpha-blended and truncated to uint8 as upstream; at 224 x 224 the frames are
  upstream's pixel for pixel except the arrows.

Deliberate differences from upstream: numpy instead of torch; frames drawn at any size (upstream:
224 only); the bias arrows are drawn with OpenCV (upstream: a matplotlib quiver, 3 x 3 arrows per
zone, the same scale: a ``(5, 5)`` bias spans 15 % of a zone); a reset without a seed seeds the
variation space from the env's generator (so ``reset(seed=s)`` then ``reset()`` repeats);
``render_mode`` None is accepted; typed errors instead of asserts.
"""

from __future__ import annotations

import colorsys
import math
from typing import Any

import gymnasium as gym
import numpy as np

from ... import keys, spaces
from ...errors import ConfigError
from ..base import DatasetResetMixin, check_render_size, reset_point_task
from ..base import rgb_factor as _rgb
from ..base import scalar_factor as _box1

__all__ = ["DEFAULT_VARIATIONS", "PiecewiseEnv", "zone_index"]

DEFAULT_VARIATIONS = ("agent.position", "target.position")
IMG_SIZE = 224
BORDER_SIZE = 14
BORDER_LINE = 4
SUCCESS_DISTANCE = 16.0
MAX_BIAS = 5.0
DYNAMICS = "_dynamics"  # private info: grid_n, speed, then each zone's bias (x, y)
_ARROWS_PER_ZONE = 3
_ARROW_COLOR = (17, 17, 17)
_ARROW_ALPHA = 0.85


def zone_index(pos: np.ndarray, grid_n: int) -> np.ndarray:
    """Zone index (``row * grid_n + col``) of positions ``(..., 2)``; outside the play field the
    nearest zone (upstream's ``_get_zone``)."""
    pos = np.asarray(pos, np.float64)
    play = float(IMG_SIZE - 2 * BORDER_SIZE)
    cr = np.clip(np.trunc((pos - BORDER_SIZE) / play * grid_n), 0, grid_n - 1).astype(np.int64)
    return cr[..., 1] * grid_n + cr[..., 0]


def _position(init) -> spaces.Box:
    lo, hi = float(BORDER_SIZE), float(IMG_SIZE - BORDER_SIZE - 1)
    return spaces.Box(
        np.array([lo, lo], np.float32),
        np.array([hi, hi], np.float32),
        shape=(2,),
        dtype=np.float32,
        init_value=np.array(init, np.float32),
    )


class PiecewiseEnv(DatasetResetMixin, gym.Env):
    """Upstream's Piecewise navigation env (see the module docstring)."""

    metadata = {"render_modes": ["rgb_array"], "render_fps": 10}

    IMG_SIZE = IMG_SIZE
    BORDER_SIZE = BORDER_SIZE

    def __init__(
        self,
        render_mode: str | None = "rgb_array",
        render_target: bool = False,
        grid_n: int = 2,
        init_value: dict | None = None,
        render_size: tuple[int, int] = (IMG_SIZE, IMG_SIZE),
    ):
        if render_mode not in (None, "rgb_array"):
            raise ConfigError(f"PiecewiseEnv requires render_mode 'rgb_array' or None, got {render_mode!r}")
        if isinstance(grid_n, bool) or not isinstance(grid_n, (int, np.integer)) or not 1 <= grid_n <= 16:
            raise ConfigError(f"PiecewiseEnv requires grid_n to be an int in [1, 16], got {grid_n!r}")
        self.render_mode = render_mode
        self.render_target_flag = bool(render_target)
        self.grid_n = int(grid_n)
        self.env_name = "Piecewise"
        self.observation_space = gym.spaces.Box(0, IMG_SIZE, shape=(4,), dtype=np.float32)
        self.action_space = gym.spaces.Box(-1.0, 1.0, shape=(2,), dtype=np.float32)
        self.variation_space = self._build_variation_space()
        if init_value is not None:
            self.variation_space.set_init_value(init_value)
        self.render_size = check_render_size("PiecewiseEnv", render_size)
        self.agent_position = np.zeros(2, np.float32)
        self.target_position = np.zeros(2, np.float32)
        self._static: np.ndarray | None = None  # background, zones, border, target dot, arrows
        self._target_img: np.ndarray | None = None

    # -- variation space ----------------------------------------------------------------------
    def _build_variation_space(self) -> spaces.Dict:
        n_zones = self.grid_n * self.grid_n
        zones: dict[str, Any] = {}
        for i in range(n_zones):
            zones[f"bias_{i}"] = spaces.Box(
                np.array([-MAX_BIAS, -MAX_BIAS], np.float32),
                np.array([MAX_BIAS, MAX_BIAS], np.float32),
                shape=(2,),
                dtype=np.float32,
                init_value=np.zeros(2, np.float32),
            )
            r, g, b = colorsys.hsv_to_rgb(i / n_zones, 0.25, 1.0)  # evenly spaced pastel hues
            zones[f"color_{i}"] = _rgb([int(r * 255), int(g * 255), int(b * 255)])
        zone_order = [f"bias_{i}" for i in range(n_zones)] + [f"color_{i}" for i in range(n_zones)]
        return spaces.Dict(
            {
                "agent": spaces.Dict(
                    {
                        "color": _rgb([255, 0, 0]),
                        "radius": _box1(7.0, 14.0, 7.0),
                        "position": _position([60.0, 112.0]),
                        "speed": _box1(1.75, 10.5, 5.0),
                    },
                    sampling_order=["color", "radius", "position", "speed"],
                ),
                "target": spaces.Dict(
                    {
                        "color": _rgb([0, 255, 0]),
                        "radius": _box1(7.0, 14.0, 7.0),
                        "position": _position([164.0, 112.0]),
                    },
                    sampling_order=["color", "radius", "position"],
                ),
                "background": spaces.Dict({"color": _rgb([255, 255, 255])}),
                "border": spaces.Dict({"color": _rgb([0, 0, 0])}),
                "rendering": spaces.Dict(
                    {
                        "render_target": spaces.Discrete(2, init_value=0),
                        "render_zones": spaces.Discrete(2, init_value=0),
                        "render_bias_field": spaces.Discrete(2, init_value=0),
                    }
                ),
                "task": spaces.Dict({"min_steps": spaces.Discrete(100, start=15, init_value=25)}),
                "zones": spaces.Dict(zones, sampling_order=zone_order),
            },
            sampling_order=["background", "border", "agent", "task", "target", "rendering", "zones"],
        )

    # -- gym API --------------------------------------------------------------------------------
    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None):
        super().reset(seed=seed)
        # upstream reseeds from fresh entropy when seed is None: reset_point_task draws from the env's generator
        self.agent_position, self.target_position = reset_point_task(
            self, "PiecewiseEnv", seed, dict(options or {}), DEFAULT_VARIATIONS
        )
        self._static = None
        self._target_img = None
        return self._get_obs(), self._get_info()

    def step(self, action):
        action = np.clip(np.asarray(action, np.float32).reshape(2), -1.0, 1.0)
        v = self.variation_space
        speed = np.float32(np.asarray(v["agent"]["speed"].value).item())
        bias = np.asarray(v["zones"][f"bias_{self.zone(self.agent_position)}"].value, np.float32)
        moved = self.agent_position + action * speed + bias
        r = float(np.asarray(v["agent"]["radius"].value).item())
        self.agent_position = np.clip(moved, BORDER_SIZE + r, IMG_SIZE - BORDER_SIZE - r).astype(np.float32)
        info = self._get_info()
        terminated = bool(info["distance_to_target"] < SUCCESS_DISTANCE)
        return self._get_obs(), 0.0, terminated, False, info

    def render(self) -> np.ndarray:
        """The current frame, ``(*render_size, 3)`` uint8."""
        return self._render_frame(self.agent_position)

    def set_render_size(self, size: tuple[int, int]) -> None:
        """Draw frames and the goal image at ``size`` = (H, W) from now on."""
        size = check_render_size("PiecewiseEnv", size)
        if size != self.render_size:
            self.render_size = size
            self._static = None
            self._target_img = None

    def eval_state(self, goal_state: np.ndarray, cur_state: np.ndarray) -> tuple[bool, float]:
        """``(success, distance)``: the agent at ``cur_state[:2]`` within 16 px of ``goal_state[:2]``."""
        g = np.asarray(goal_state, np.float32).reshape(-1)[:2]
        c = np.asarray(cur_state, np.float32).reshape(-1)[:2]
        dist = float(np.linalg.norm(c - g))
        return dist < SUCCESS_DISTANCE, dist

    def zone(self, pos: np.ndarray) -> int:
        """The zone index of ``pos`` (upstream's ``_get_zone``)."""
        return int(zone_index(np.asarray(pos, np.float64).reshape(-1)[:2], self.grid_n))

    # -- upstream's setters (dataset callables) ---------------------------------------------------
    def _set_state(self, state) -> None:
        self.agent_position = np.asarray(state, np.float32).reshape(-1)[:2].copy()

    def _set_goal_state(self, goal_state) -> None:
        self.target_position = np.asarray(goal_state, np.float32).reshape(-1)[:2].copy()
        self.variation_space["target"]["position"].set_value(self.target_position.copy())
        self._static = None
        self._target_img = None

    # -- internals --------------------------------------------------------------------------------
    def _get_obs(self) -> np.ndarray:
        return np.concatenate([self.agent_position, self.target_position]).astype(np.float32)

    def _dynamics(self) -> np.ndarray:
        v = self.variation_space
        biases = [np.asarray(v["zones"][f"bias_{i}"].value, np.float32) for i in range(self.grid_n**2)]
        speed = np.asarray(v["agent"]["speed"].value, np.float32).reshape(1)
        return np.concatenate([np.array([self.grid_n], np.float32), speed, *biases]).astype(np.float32)

    def _get_info(self) -> dict[str, Any]:
        if self._target_img is None:
            self._target_img = self._render_frame(self.target_position)
        agent, target = self.agent_position.copy(), self.target_position.copy()
        return {
            "env_name": self.env_name,
            keys.PROPRIO: agent.copy(),
            keys.STATE: agent,
            keys.GOAL_STATE: target.copy(),
            keys.GOAL_PROPRIO: target,
            keys.GOAL: self._target_img.copy(),
            "distance_to_target": float(np.linalg.norm(self.agent_position - self.target_position)),
            DYNAMICS: self._dynamics(),
        }

    def _axes(self) -> tuple[np.ndarray, np.ndarray, float, float]:
        """World coordinates of the output pixel centres (y, x) and the world size of a pixel (sy, sx)."""
        h, w = self.render_size
        sy, sx = IMG_SIZE / h, IMG_SIZE / w
        ys = ((np.arange(h) + 0.5) * sy - 0.5).astype(np.float32)
        xs = ((np.arange(w) + 0.5) * sx - 0.5).astype(np.float32)
        return ys, xs, sy, sx

    def _coverage(self, n: int, scale: float, lo: float, hi: float) -> np.ndarray:
        """Fraction of each of ``n`` output pixels (``scale`` world px each) inside ``[lo, hi)``."""
        edges = np.arange(n + 1, dtype=np.float64) * scale
        return np.clip(np.minimum(edges[1:], hi) - np.maximum(edges[:-1], lo), 0.0, None) / scale

    def _paint(self, img: np.ndarray, cover: np.ndarray, color) -> None:
        """Blend ``color`` into ``img`` with per-pixel coverage ``cover`` (H, W) in [0, 1]."""
        a = cover[..., None]
        out = img.astype(np.float64) * (1.0 - a) + np.asarray(color, np.float64) * a
        img[:] = np.round(out).astype(np.uint8)

    def _draw_static(self) -> np.ndarray:
        v = self.variation_space
        h, w = self.render_size
        _, _, sy, sx = self._axes()
        img = np.empty((h, w, 3), np.uint8)
        img[:] = np.asarray(v["background"]["color"].value, np.uint8)
        n, bs, play = self.grid_n, BORDER_SIZE, IMG_SIZE - 2 * BORDER_SIZE
        if int(v["rendering"]["render_zones"].value):
            for row in range(n):
                cy = self._coverage(h, sy, bs + int(row * play / n), bs + int((row + 1) * play / n))
                for col in range(n):
                    cx = self._coverage(w, sx, bs + int(col * play / n), bs + int((col + 1) * play / n))
                    self._paint(img, np.outer(cy, cx), v["zones"][f"color_{row * n + col}"].value)
        t = BORDER_LINE
        band_y = np.maximum(self._coverage(h, sy, bs - t, bs), self._coverage(h, sy, IMG_SIZE - bs, IMG_SIZE - bs + t))
        band_x = np.maximum(self._coverage(w, sx, bs - t, bs), self._coverage(w, sx, IMG_SIZE - bs, IMG_SIZE - bs + t))
        border = np.maximum(band_y[:, None], band_x[None, :])
        self._paint(img, border, v["border"]["color"].value)
        if int(v["rendering"]["render_target"].value) or self.render_target_flag:
            self._blend_dot(img, self.target_position, v["target"]["radius"].value, v["target"]["color"].value)
        if int(v["rendering"]["render_bias_field"].value):
            self._draw_bias_field(img)
        return img

    def _render_frame(self, agent_pos: np.ndarray) -> np.ndarray:
        if self._static is None:
            self._static = self._draw_static()
        v = self.variation_space
        img = self._static.copy()
        self._blend_dot(img, agent_pos, v["agent"]["radius"].value, v["agent"]["color"].value)
        return img

    def _blend_dot(self, img: np.ndarray, pos: np.ndarray, radius, color) -> None:
        """Alpha-blend a Gaussian dot (std ``radius`` world px, peak normalised to 1 on the pixel grid)
        into ``img`` in place, in float32 and truncated to uint8, as upstream."""
        ys, xs, _, _ = self._axes()
        std = max(1e-6, float(np.asarray(radius).item()))
        p = np.asarray(pos, np.float32).reshape(-1)
        dy, dx = ys - p[1], xs - p[0]
        dist2 = dy[:, None] * dy[:, None] + dx[None, :] * dx[None, :]
        dot = np.exp((-dist2 / np.float32(2.0 * std * std)).astype(np.float64)).astype(np.float32)
        peak = dot.max()
        if peak > 0:
            dot = dot / peak
        a = np.clip(dot, 0.0, 1.0)[..., None]
        out = img.astype(np.float32) * (np.float32(1.0) - a) + np.asarray(color, np.float32).reshape(3) * a
        img[:] = out.astype(np.uint8)

    def _draw_bias_field(self, img: np.ndarray) -> None:
        """Each zone's bias as 3 x 3 arrows from points spread over the zone (tail at the point); a
        bias of ``(5, 5)`` spans 15 % of a zone, as upstream's quiver."""
        import cv2

        v = self.variation_space
        h, w = self.render_size
        n, bs, play = self.grid_n, BORDER_SIZE, IMG_SIZE - 2 * BORDER_SIZE
        cell = play / n
        scale = cell * 0.15 / (MAX_BIAS * math.sqrt(2))  # world px per bias unit
        px = np.array([w / IMG_SIZE, h / IMG_SIZE])
        shift = 4
        shaft = 0.006 * IMG_SIZE * min(px)  # upstream's quiver width, in output px
        width = max(1, int(round(shaft)))
        overlay = np.zeros((h, w), np.uint8)
        k = _ARROWS_PER_ZONE
        for row in range(n):
            for col in range(n):
                bias = np.asarray(v["zones"][f"bias_{row * n + col}"].value, np.float64)
                vec = bias * scale
                length = float(np.linalg.norm(vec))
                for si in range(k):
                    for sj in range(k):
                        tail = np.array(
                            [bs + col * cell + (sj + 0.5) * cell / k, bs + row * cell + (si + 0.5) * cell / k]
                        )
                        tail_px = tail * px
                        if length * min(px) < 0.5:  # too short to show a direction: a dot
                            c = tuple(int(round(q * (1 << shift))) for q in tail_px)
                            cv2.circle(
                                overlay, c, max(1, int(round(shaft * (1 << shift)))), 255, -1, cv2.LINE_AA, shift
                            )
                            continue
                        tip_px = (tail + vec) * px
                        d = (tip_px - tail_px) / max(np.linalg.norm(tip_px - tail_px), 1e-9)
                        head = min(max(4.0 * shaft, 1.5), 0.5 * float(np.linalg.norm(tip_px - tail_px)))
                        normal = np.array([-d[1], d[0]])
                        base = tip_px - d * head
                        tri = np.array([tip_px, base + normal * head / 2, base - normal * head / 2])
                        pts = np.round(np.array([tail_px, base]) * (1 << shift)).astype(np.int32)
                        cv2.line(overlay, tuple(pts[0]), tuple(pts[1]), 255, width, cv2.LINE_AA, shift)
                        cv2.fillPoly(
                            overlay, np.round(tri * (1 << shift)).astype(np.int32)[None], 255, cv2.LINE_AA, shift
                        )
        self._paint(img, overlay.astype(np.float64) / 255.0 * _ARROW_ALPHA, _ARROW_COLOR)

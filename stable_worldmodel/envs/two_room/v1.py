"""``swm/TwoRoom-v2``: upstream 0.1.1's TwoRoom (a Gaussian dot crossing a wall through a door).

Our TwoRoom with swept collisions, goals always in the other room and any render size is
``swm/TwoRoom-v2`` (:mod:`.env`); 0.0.3's pymunk TwoRoom is ``swm/TwoRoom-v0``. This module keeps
the id's upstream meaning, written from the observed behaviour of 0.1.1, so datasets recorded and
models trained on upstream's TwoRoom work here unchanged:

- **World**: a ``224 x 224`` pixel square (y down) framed by 4-px border lines just outside
  ``[14, 210]``, split by a wall of ``wall.thickness`` pixels centred on 112 (vertical when
  ``wall.axis`` is 1, horizontal when 0) with ``door.number`` openings of half-extent
  ``door.size[k]`` centred at ``door.position[k]`` along the wall.
- **Step**: the action is clipped to ``[-1, 1]^2`` and the agent moves by ``agent.speed *
  action``; the new centre is clamped inside the border (keeping ``agent.radius`` clear) and, if
  it would enter the wall band (grown by the radius) outside every door (grown by 1.75 px), it
  is put back 0.5 px before the band on the side it started from.
- **Observation**: a flat ``Box(10)`` float32: agent (x, y), target (x, y), then each door's
  centre (x, y) on the wall, zeros for absent doors.
- **Success** (``terminated``): the agent centre within 16 px of the target; reward 0; never
  truncated by the env (``swm`` tools cut episodes at 100 steps by default).
- **Reset**: the variation space is seeded with the reset seed, reset to its defaults, and
  ``agent.position`` and ``target.position`` are resampled (``options["variation"]`` names
  others; ``options["variation_values"]`` sets factors). The agent is never drawn inside the wall
  band; the target is drawn anywhere in ``[14, 209]^2`` (either room). ``options["state"]`` /
  ``options["target_state"]`` (or ``"goal_state"``) place the agent / the target.
- **Info**: upstream's ``env_name``, ``state`` / ``proprio`` (agent position), ``goal_state``
  (target position) and ``distance_to_target``; plus ``goal`` (the frame with the agent drawn at
  the target, which upstream keeps in ``_target_img`` only) and ``goal_proprio``.
- **Rendering**: ``224 x 224`` RGB (``set_render_size`` resizes frames and the goal image with
  PIL's bilinear filter, as upstream's World does): background, door, wall and border pixels, then the agent as a
  Gaussian dot (std = ``agent.radius``, peak normalised to 1) alpha-blended in float32 and
  truncated to uint8, as upstream; the target dot only when ``render_target`` (or the
  ``rendering.render_target`` factor) is on. The static layer (with the target dot) is drawn and
  resized once per goal, and a frame redraws only the output pixels the agent's dot reaches (the
  same pixels as resizing the whole frame, for sizes whose scale from 224 is a short binary
  fraction such as 64; other sizes resize whole frames), so a frame costs a fraction of upstream's.

Deliberate differences: positions and observations are numpy float32 arrays (upstream: torch
tensors); a reset without a seed seeds the variation space from the env's own generator (so
``reset(seed=s)`` then ``reset()`` repeats, as Gymnasium requires; upstream draws fresh entropy);
``render_mode`` None is accepted.
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np

from ... import keys, spaces
from ...errors import ConfigError
from ..base import DatasetResetMixin, check_render_size, reset_point_task
from ..base import rgb_factor as _rgb
from ..base import scalar_factor as _box1

DEFAULT_VARIATIONS = ("agent.position", "target.position")
IMG_SIZE = 224
BORDER_SIZE = 14
BORDER_LINE = 4
WALL_CENTER = 112
MAX_DOOR = 3
SUCCESS_DISTANCE = 16.0
DOOR_MARGIN = 1.75
WALL_PUSHBACK = 0.5
TARGET_IMAGE = "goal"
LAYOUT = "_layout"  # private: wall axis, wall position, agent radius, speed, door centres (3), door half-extents (3)
#: a dot weight below this leaves a uint8 pixel as it is (1 - a rounds to 1 in float32): the
#: dot is computed only where it is larger (within ~5.9 std of the centre)
_DOT_CUTOFF_STD = 6.0


class TwoRoomV1Env(DatasetResetMixin, gym.Env):
    """Upstream 0.1.1's TwoRoom (see the module docstring)."""

    metadata = {"render_modes": ["rgb_array"], "render_fps": 10}

    IMG_SIZE = IMG_SIZE
    BORDER_SIZE = BORDER_SIZE
    DOT_STD = 7.0
    PADDING = 14
    MAX_SPEED = 10.5
    WALL_CENTER = WALL_CENTER
    WALL_WIDTH_DEFAULT = 10
    MAX_DOOR = MAX_DOOR

    def __init__(
        self, render_mode: str | None = "rgb_array", render_target: bool = False, init_value: dict | None = None
    ):
        if render_mode not in (None, "rgb_array"):
            raise ConfigError(f"TwoRoomV1Env requires render_mode 'rgb_array' or None, got {render_mode!r}")
        self.render_mode = render_mode
        self.render_target_flag = bool(render_target)
        self.env_name = "TwoRoom"
        self.observation_space = gym.spaces.Box(0, IMG_SIZE, shape=(4 + 2 * MAX_DOOR,), dtype=np.float32)
        self.action_space = gym.spaces.Box(-1.0, 1.0, shape=(2,), dtype=np.float32)
        self.variation_space = self._build_variation_space()
        if init_value is not None:
            self.variation_space.set_init_value(init_value)
        self.agent_position = np.zeros(2, np.float32)
        self.target_position = np.zeros(2, np.float32)
        self._target_img: np.ndarray | None = None
        self._static: np.ndarray | None = None
        self._layer: tuple[np.ndarray, np.ndarray | None] | None = None
        self._layer_key: tuple | None = None
        self._target_sized: np.ndarray | None = None
        self._target_key: tuple | None = None
        self.wall_axis, self.wall_thickness, self.num_doors = 1, self.WALL_WIDTH_DEFAULT, 1
        self.door_positions = np.zeros(MAX_DOOR, np.float32)
        self.door_sizes = np.zeros(MAX_DOOR, np.float32)
        self.wall_pos = float(WALL_CENTER)
        self._ys = np.arange(IMG_SIZE, dtype=np.float32)
        self.render_size = (IMG_SIZE, IMG_SIZE)

    # -- variation space --------------------------------------------------------------------
    def _build_variation_space(self) -> spaces.Dict:
        lo, hi = float(BORDER_SIZE), float(IMG_SIZE - BORDER_SIZE - 1)

        def position(init, constrain_fn=None):
            return spaces.Box(
                np.array([lo, lo], np.float32),
                np.array([hi, hi], np.float32),
                shape=(2,),
                dtype=np.float32,
                init_value=np.array(init, np.float32),
                constrain_fn=constrain_fn,
            )

        # Keys in alphabetical order, as Gymnasium sorts upstream's plain dicts: the per-key seeds
        # follow this order, so a reset seed draws the factors upstream draws.
        return spaces.Dict(
            {
                "agent": spaces.Dict(
                    {
                        "color": _rgb([255, 0, 0]),
                        "position": position([60.0, 112.0], self._constrain_agent_not_in_wall),
                        "radius": _box1(7.0, 14.0, 7.0),
                        "speed": _box1(1.75, 10.5, 5.0),
                    },
                    sampling_order=["color", "radius", "position", "speed"],
                ),
                "background": spaces.Dict({"color": _rgb([255, 255, 255])}),
                "door": spaces.Dict(
                    {
                        "color": _rgb([255, 255, 255]),
                        "number": spaces.Discrete(MAX_DOOR, start=1, init_value=1),
                        "position": spaces.MultiDiscrete(nvec=[IMG_SIZE] * MAX_DOOR, init_value=[49] * MAX_DOOR),
                        "size": spaces.MultiDiscrete(
                            nvec=[21] * MAX_DOOR,
                            start=[1] * MAX_DOOR,
                            init_value=[14] * MAX_DOOR,
                            constrain_fn=self._check_door_fit,
                        ),
                    },
                    sampling_order=["color", "number", "size", "position"],
                ),
                "rendering": spaces.Dict({"render_target": spaces.Discrete(2, init_value=0)}),
                "target": spaces.Dict(
                    {"color": _rgb([0, 255, 0]), "position": position([164.0, 112.0]), "radius": _box1(7.0, 14.0, 7.0)},
                    sampling_order=["color", "radius", "position"],
                ),
                "task": spaces.Dict({"min_steps": spaces.Discrete(100, start=15, init_value=25)}),
                "wall": spaces.Dict(
                    {
                        "axis": spaces.Discrete(2, init_value=1),
                        "border_color": _rgb([0, 0, 0]),
                        "color": _rgb([0, 0, 0]),
                        "thickness": spaces.Discrete(35, start=7, init_value=10),
                    },
                    sampling_order=["color", "border_color", "thickness", "axis"],
                ),
            },
            sampling_order=["background", "wall", "agent", "door", "task", "target", "rendering"],
        )

    def _constrain_agent_not_in_wall(self, pos) -> bool:
        """The agent disk clear of the wall band (either room)."""
        v = self.variation_space
        half = int(v["wall"]["thickness"].value) // 2
        r = float(np.asarray(v["agent"]["radius"].value).item())
        coord = float(pos[0] if int(v["wall"]["axis"].value) == 1 else pos[1])
        return not (WALL_CENTER - half - r <= coord <= WALL_CENTER + half + r)

    def _check_door_fit(self, sizes) -> bool:
        """At least one active door's half-extent is 1.1x the agent radius."""
        v = self.variation_space
        n = int(v["door"]["number"].value)
        r = float(np.asarray(v["agent"]["radius"].value).item())
        return any(float(s) >= 1.1 * r for s in np.asarray(sizes)[:n])

    # -- gym API ----------------------------------------------------------------------------
    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None):
        super().reset(seed=seed)
        # upstream reseeds from fresh entropy when seed is None: reset_point_task draws from the env's generator
        self.agent_position, self.target_position = reset_point_task(
            self, "TwoRoomV1Env", seed, dict(options or {}), DEFAULT_VARIATIONS
        )
        self._cache_params()
        self._static = self._draw_static()
        self._target_img = self._render_frame(self.target_position)
        return self._get_obs(), self._get_info()

    def step(self, action):
        action = np.clip(np.asarray(action, np.float32).reshape(2), -1.0, 1.0)
        speed = np.float32(np.asarray(self.variation_space["agent"]["speed"].value).item())
        moved = self.agent_position + action * speed
        self.agent_position = self._apply_collisions(self.agent_position, moved)
        info = self._get_info()
        terminated = bool(info["distance_to_target"] < SUCCESS_DISTANCE)
        return self._get_obs(), 0.0, terminated, False, info

    def render(self) -> np.ndarray:
        """The current frame, ``(*render_size, 3)`` uint8 (224 x 224 unless :meth:`set_render_size`).

        The layer under the agent (static pixels and the target dot) is drawn and resized once per
        goal; a frame redraws only the output pixels whose filter window the agent's dot reaches
        (PIL's resize of that box of the 224-px frame: the same pixels as resizing all of it)."""
        big, small = self._layers()
        window = _resize_window(self.render_size) if small is not None else None
        if window is None:
            return self._sized(self._render_frame(self.agent_position))
        v = self.variation_space
        dot = self._dot(self.agent_position, v["agent"]["radius"].value)
        if dot is None:
            return small.copy()
        (y0, y1, x0, x1), _ = dot
        (oy0, oy1, cy0, cy1, by0, by1), (ox0, ox1, cx0, cx1, bx0, bx1) = window.rows(y0, y1), window.cols(x0, x1)
        crop = big[cy0:cy1, cx0:cx1].copy()
        self._blend(crop, dot, v["agent"]["color"].value, origin=(cy0, cx0))
        from PIL import Image

        out = small.copy()
        box = (bx0 - cx0, by0 - cy0, bx1 - cx0, by1 - cy0)
        out[oy0:oy1, ox0:ox1] = np.asarray(
            Image.fromarray(crop).resize((ox1 - ox0, oy1 - oy0), Image.BILINEAR, box=box)
        )
        return out

    def set_render_size(self, size: tuple[int, int]) -> None:
        """Frames and the goal image at ``size`` = (H, W): drawn at 224 x 224, then resized with
        PIL's bilinear filter, as upstream's World resizes them (so 64-px observations match
        datasets recorded with upstream)."""
        self.render_size = check_render_size("TwoRoomV1Env", size)

    def _sized(self, frame: np.ndarray) -> np.ndarray:
        if self.render_size == (IMG_SIZE, IMG_SIZE):
            return frame
        from PIL import Image

        h, w = self.render_size
        return np.asarray(Image.fromarray(frame).resize((w, h), Image.BILINEAR))

    def eval_state(self, goal_state: np.ndarray, cur_state: np.ndarray) -> tuple[bool, float]:
        """``(success, distance)``: the agent at ``cur_state[:2]`` within 16 px of ``goal_state[:2]``."""
        g = np.asarray(goal_state, np.float32).reshape(-1)[:2]
        c = np.asarray(cur_state, np.float32).reshape(-1)[:2]
        dist = float(np.linalg.norm(c - g))
        return dist < SUCCESS_DISTANCE, dist

    # -- upstream's setters (dataset callables) -----------------------------------------------
    def _set_state(self, state) -> None:
        self.agent_position = np.asarray(state, np.float32).reshape(-1)[:2].copy()

    def _set_goal_state(self, goal_state) -> None:
        self.target_position = np.asarray(goal_state, np.float32).reshape(-1)[:2].copy()
        self.variation_space["target"]["position"].set_value(self.target_position.copy())
        self._target_img = self._render_frame(self.target_position)

    # -- internals ----------------------------------------------------------------------------
    def _cache_params(self) -> None:
        v = self.variation_space
        self.wall_thickness = int(v["wall"]["thickness"].value)
        self.wall_axis = int(v["wall"]["axis"].value)
        self.num_doors = int(v["door"]["number"].value)
        self.door_positions = np.asarray(v["door"]["position"].value[: self.num_doors], np.float32)
        self.door_sizes = np.asarray(v["door"]["size"].value[: self.num_doors], np.float32)
        self.wall_pos = float(WALL_CENTER)

    def _in_any_door(self, coord: float) -> bool:
        return any(
            c - s - DOOR_MARGIN <= coord <= c + s + DOOR_MARGIN
            for c, s in zip(self.door_positions.tolist(), self.door_sizes.tolist(), strict=True)
        )

    def _apply_collisions(self, start: np.ndarray, moved: np.ndarray) -> np.ndarray:
        r = float(np.asarray(self.variation_space["agent"]["radius"].value).item())
        lo, hi = BORDER_SIZE + r, IMG_SIZE - BORDER_SIZE - r
        out = np.array([min(max(float(moved[0]), lo), hi), min(max(float(moved[1]), lo), hi)], np.float32)
        half = self.wall_thickness // 2
        across = 0 if self.wall_axis == 1 else 1  # the coordinate that crosses the wall
        near, far = WALL_CENTER - half - r, WALL_CENTER + half + r
        if float(start[across]) < WALL_CENTER:
            if float(out[across]) > near and not self._in_any_door(float(out[1 - across])):
                out[across] = near - WALL_PUSHBACK
        elif float(out[across]) < far and not self._in_any_door(float(out[1 - across])):
            out[across] = far + WALL_PUSHBACK
        return out

    def _get_obs(self) -> np.ndarray:
        doors = np.zeros(2 * MAX_DOOR, np.float32)
        for k in range(self.num_doors):
            centre = float(self.door_positions[k])
            doors[2 * k : 2 * k + 2] = (self.wall_pos, centre) if self.wall_axis == 1 else (centre, self.wall_pos)
        return np.concatenate([self.agent_position, self.target_position, doors]).astype(np.float32)

    def _get_info(self) -> dict[str, Any]:
        agent, target = self.agent_position.copy(), self.target_position.copy()
        return {
            "env_name": self.env_name,
            keys.PROPRIO: agent.copy(),
            keys.STATE: agent,
            keys.GOAL_STATE: target.copy(),
            keys.GOAL_PROPRIO: target,
            "distance_to_target": float(np.linalg.norm(self.agent_position - self.target_position)),
            TARGET_IMAGE: self._sized_target(),
            LAYOUT: self._layout(),
        }

    def _layout(self) -> np.ndarray:
        v = self.variation_space
        out = np.zeros(4 + 2 * MAX_DOOR, np.float32)
        out[:4] = (
            self.wall_axis,
            self.wall_pos,
            np.asarray(v["agent"]["radius"].value).item(),
            np.asarray(v["agent"]["speed"].value).item(),
        )
        out[4 : 4 + self.num_doors] = self.door_positions
        out[4 + MAX_DOOR : 4 + MAX_DOOR + self.num_doors] = self.door_sizes
        return out

    def _draw_static(self) -> np.ndarray:
        """Background, door, wall and border pixels: ``(224, 224, 3)`` uint8."""
        v = self.variation_space
        n = IMG_SIZE
        img = np.empty((n, n, 3), np.uint8)
        img[:] = np.asarray(v["background"]["color"].value, np.uint8)
        half = self.wall_thickness // 2
        band = (self._ys >= WALL_CENTER - half) & (self._ys <= WALL_CENTER + half)  # along the crossing axis
        span = np.zeros(n, bool)  # along the wall
        for c, s in zip(self.door_positions.tolist(), self.door_sizes.tolist(), strict=True):
            span |= (self._ys >= c - s) & (self._ys <= c + s)
        # masks indexed [row (y), column (x)]
        if self.wall_axis == 1:
            door, wall = span[:, None] & band[None, :], ~span[:, None] & band[None, :]
        else:
            door, wall = band[:, None] & span[None, :], band[:, None] & ~span[None, :]
        wall = wall.copy()
        b, t = BORDER_SIZE, BORDER_LINE
        wall[:, b - t : b] = wall[:, n - b : n - b + t] = True
        wall[b - t : b, :] = wall[n - b : n - b + t, :] = True
        img[door] = np.asarray(v["door"]["color"].value, np.uint8)
        img[wall] = np.asarray(v["wall"]["color"].value, np.uint8)
        return img

    def _render_frame(self, agent_pos: np.ndarray) -> np.ndarray:
        v = self.variation_space
        img = self._layers()[0].copy()
        self._blend_dot(img, agent_pos, v["agent"]["radius"].value, v["agent"]["color"].value)
        return img

    def _layers(self) -> tuple[np.ndarray, np.ndarray | None]:
        """What lies under the agent: static pixels and the target dot when it is shown, at 224 px,
        and resized to :attr:`render_size` (None at 224 px); redrawn when the target, the render
        size or the static layer changes."""
        v = self.variation_space
        if self._static is None:
            self._cache_params()
            self._static = self._draw_static()
        show_target = bool(v["rendering"]["render_target"].value) or self.render_target_flag
        # the layer holds the static array it was drawn on: a new one (a reset) never looks the same
        key = (self._static, self.render_size, show_target, self.target_position.tobytes())
        if self._layer_key is None or self._layer_key[0] is not key[0] or self._layer_key[1:] != key[1:]:
            big = self._static.copy()
            if show_target:
                self._blend_dot(big, self.target_position, v["target"]["radius"].value, v["target"]["color"].value)
            small = None if self.render_size == (IMG_SIZE, IMG_SIZE) else self._sized(big)
            self._layer, self._layer_key = (big, small), key
        return self._layer

    def _sized_target(self) -> np.ndarray | None:
        """The goal image at :attr:`render_size`, resized once per goal."""
        if self._target_img is None:
            return None
        key = (self._target_img, self.render_size)  # held, so a new goal image never looks the same
        if self._target_key is None or self._target_key[0] is not key[0] or self._target_key[1] != key[1]:
            self._target_sized, self._target_key = self._sized(self._target_img), key
        return self._target_sized.copy()

    def _dot(self, pos: np.ndarray, radius) -> tuple[tuple[int, int, int, int], np.ndarray] | None:
        """A Gaussian dot (std ``radius``, peak 1 on the pixel grid) at ``pos``: its pixel bounds
        ``(y0, y1, x0, x1)`` in the 224-px frame and its alpha there, ``(y1 - y0, x1 - x0)``."""
        std = max(1e-6, float(np.asarray(radius).item()))
        x, y = float(pos[0]), float(pos[1])
        reach = int(np.ceil(_DOT_CUTOFF_STD * std)) + 1
        x0, x1 = max(0, int(np.floor(x)) - reach), min(IMG_SIZE, int(np.floor(x)) + reach + 2)
        y0, y1 = max(0, int(np.floor(y)) - reach), min(IMG_SIZE, int(np.floor(y)) + reach + 2)
        if x0 >= x1 or y0 >= y1:
            return None
        dx = self._ys[x0:x1] - np.float32(x)
        dy = self._ys[y0:y1] - np.float32(y)
        dist2 = dy[:, None] * dy[:, None] + dx[None, :] * dx[None, :]
        # exp in float64 rounded to float32: matches upstream's torch frames to within 1 of 255 on 1e-5 of the pixels
        dot = np.exp((-dist2 / np.float32(2.0 * std * std)).astype(np.float64)).astype(np.float32)
        peak = dot.max()
        if peak > 0:
            dot = dot / peak
        return (y0, y1, x0, x1), np.clip(dot, 0, 1)

    @staticmethod
    def _blend(img: np.ndarray, dot, color, origin: tuple[int, int] = (0, 0)) -> None:
        """Alpha-blend ``dot`` (from :meth:`_dot`) into ``img``, whose pixel (0, 0) is the frame's
        ``origin``, where they overlap; in float32, truncated to uint8, as upstream."""
        (y0, y1, x0, x1), alpha = dot
        oy, ox = origin
        h, w = img.shape[:2]
        ty0, ty1, tx0, tx1 = max(y0, oy), min(y1, oy + h), max(x0, ox), min(x1, ox + w)
        if ty0 >= ty1 or tx0 >= tx1:
            return
        a = alpha[ty0 - y0 : ty1 - y0, tx0 - x0 : tx1 - x0]
        keep = np.float32(1.0) - a
        patch = img[ty0 - oy : ty1 - oy, tx0 - ox : tx1 - ox]
        for k, c in enumerate(np.asarray(color, np.float32).reshape(3)):  # a plane at a time: 3x faster than (h, w, 3)
            plane = patch[..., k]
            blended = plane.astype(np.float32)
            blended *= keep
            blended += a * c
            np.copyto(plane, blended, casting="unsafe")  # truncated, as astype(uint8)

    def _blend_dot(self, img: np.ndarray, pos: np.ndarray, radius, color) -> None:
        """Alpha-blend a Gaussian dot (std ``radius``, peak 1 on the pixel grid) into ``img`` in place."""
        dot = self._dot(pos, radius)
        if dot is not None:
            self._blend(img, dot, color)


class _ResizeWindow:
    """Which output pixels of PIL's bilinear 224 -> ``size`` resize read which input pixels, for a
    size whose scale is a short binary fraction (then a ``box`` resize of a crop computes exactly
    the pixels of the full resize: every coordinate PIL derives is exact in float32)."""

    def __init__(self, size: tuple[int, int]):
        self.axes = [self._axis(n) for n in size]

    @staticmethod
    def _axis(n: int) -> tuple[list[int], list[int], list[int], list[int], float]:
        scale = IMG_SIZE / n
        support = max(scale, 1.0)  # the bilinear filter's support (1) times the filter scale
        centre = (np.arange(n) + 0.5) * scale
        lo = np.clip((centre - support + 0.5).astype(int), 0, IMG_SIZE)
        hi = np.clip((centre + support + 0.5).astype(int), 0, IMG_SIZE)
        # lo and hi grow with the output index: by input pixel, the first output reading past it
        # and one past the last output reading before it
        first = np.searchsorted(hi, np.arange(IMG_SIZE + 1), side="right")
        last = np.searchsorted(lo, np.arange(IMG_SIZE + 1), side="left")
        return first.tolist(), last.tolist(), lo.tolist(), hi.tolist(), scale

    def _span(self, axis: int, p0: int, p1: int) -> tuple[int, int, int, int, float, float]:
        """For the input span ``[p0, p1)``: the outputs ``[o0, o1)`` whose filter reads it, the
        inputs ``[c0, c1)`` those outputs read, and their ``box`` bounds."""
        first, last, lo, hi, scale = self.axes[axis]
        o0, o1 = first[p0], last[p1]
        return o0, o1, lo[o0], hi[o1 - 1], o0 * scale, o1 * scale

    def rows(self, p0: int, p1: int):
        return self._span(0, p0, p1)

    def cols(self, p0: int, p1: int):
        return self._span(1, p0, p1)


#: resize windows by render size; None where the crop would not be exact (the full resize is used)
_RESIZE_WINDOWS: dict[tuple[int, int], _ResizeWindow | None] = {}


def _resize_window(size: tuple[int, int]) -> _ResizeWindow | None:
    from fractions import Fraction

    if size not in _RESIZE_WINDOWS:
        dens = [Fraction(IMG_SIZE, n).denominator for n in size]
        exact = size != (IMG_SIZE, IMG_SIZE) and all(d <= 256 and d & (d - 1) == 0 for d in dens)  # powers of 2
        _RESIZE_WINDOWS[size] = _ResizeWindow(size) if exact else None
    return _RESIZE_WINDOWS[size]

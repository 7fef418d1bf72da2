"""What the classic-control envs share: reset with factors, goals, info, validation and drawing.

Each env (``cartpole.py`` ...) owns its dynamics (Gymnasium's equations, written out here so
that every constant can be a factor), its start and goal, its success rule and its picture.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import gymnasium as gym
import numpy as np

from ... import keys, spaces
from ...errors import ConfigError, SpaceError
from .. import utils
from ..base import DatasetResetMixin, check_render_size, check_variation_option

ENV_NAME = "env_name"  # upstream's info key: the Gymnasium id the env reproduces


# -- factor spaces ------------------------------------------------------------------------------
def scalar(low: float, high: float, init: float) -> spaces.Box:
    """A physical constant: float32 ``Box(low, high, (1,))`` (upstream's shape and dtype)."""
    return spaces.Box(low, high, shape=(1,), dtype=np.float32, init_value=np.array([init], np.float32))


def rgb(low: float, high: float, init: Sequence[float]) -> spaces.Box:
    """A color: float32 ``Box(low, high, (3,))`` in [0, 1] units (upstream's)."""
    return spaces.Box(low, high, shape=(3,), dtype=np.float32, init_value=np.asarray(init, np.float32))


def to_u8(color: Any) -> np.ndarray:
    """A [0, 1] color factor as uint8 RGB."""
    return np.clip(np.round(np.asarray(color, np.float64).reshape(3) * 255.0), 0, 255).astype(np.uint8)


def wrap_angle(angle: Any) -> Any:
    """Angles in [-pi, pi)."""
    return (np.asarray(angle, np.float64) + np.pi) % (2 * np.pi) - np.pi


# -- drawing ------------------------------------------------------------------------------------
class Canvas:
    """An ``(H, W, 3)`` uint8 frame addressed in a reference screen of ``ref_w x ref_h`` units, y up.

    The classic-control envs describe their scene in Gymnasium's pygame screen (600 x 400 or
    500 x 500 pixels, y up before pygame's flip); the canvas maps that screen onto the requested
    size (each axis by its own scale, as a resize of Gymnasium's frame would) and draws with
    OpenCV's anti-aliased, sub-pixel primitives (:mod:`stable_worldmodel.envs.utils`).
    """

    def __init__(self, size: tuple[int, int], ref_wh: tuple[float, float], background: np.ndarray):
        """``background``: a color, or an ``(H, W, 3)`` image to draw on (copied)."""
        bg = np.asarray(background)
        self.img = bg.copy() if bg.ndim == 3 else utils.new_canvas(size, bg)
        self.ref_w, self.ref_h = float(ref_wh[0]), float(ref_wh[1])
        self.sx, self.sy = size[1] / self.ref_w, size[0] / self.ref_h

    def px(self, points: Any) -> np.ndarray:
        """Reference-screen points ``(N, 2)`` (y up) as canvas pixels ``(x, y)`` (y down)."""
        p = np.asarray(points, np.float64).reshape(-1, 2)
        return np.stack([p[:, 0] * self.sx, (self.ref_h - p[:, 1]) * self.sy], 1)

    def polygon(self, points: Any, color: np.ndarray) -> None:
        utils.fill_polygon(self.img, self.px(points), color)

    def circle(self, center: Sequence[float], radius: float, color: np.ndarray) -> None:
        """A disk of ``radius`` reference units (an ellipse when the two scales differ), as a polygon
        fine enough that its edges stay under a tenth of a pixel from the true outline."""
        rx, ry = radius * self.sx, radius * self.sy
        n = int(np.clip(np.ceil(np.pi / np.arccos(max(1.0 - 0.1 / max(rx, ry, 0.1), -1.0))), 8, 128))
        t = np.linspace(0.0, 2 * np.pi, n, endpoint=False)
        c = self.px(center)[0]
        utils.fill_polygon(self.img, np.stack([c[0] + rx * np.cos(t), c[1] + ry * np.sin(t)], 1), color)

    def line(self, p0: Sequence[float], p1: Sequence[float], color: np.ndarray, width: float = 1.0) -> None:
        """A segment ``width`` reference units wide (at least one canvas pixel, so it never vanishes)."""
        a, b = self.px(p0)[0], self.px(p1)[0]
        d = b - a
        n = np.hypot(*d)
        if n == 0:
            return
        # half the width in canvas pixels, measured across the segment
        normal = np.array([-d[1], d[0]]) / n
        half = 0.5 * max(width * float(np.hypot(normal[0] * self.sx, normal[1] * self.sy)), 1.0)
        off = normal * half
        utils.fill_polygon(self.img, np.array([a + off, b + off, b - off, a - off]), color)

    def polyline(self, points: Any, color: np.ndarray, width: float = 1.0) -> None:
        """An open polyline ``width`` reference units wide (a whole number of canvas pixels, at least one)."""
        thickness = max(int(round(width * min(self.sx, self.sy))), 1)
        utils.draw_polyline(self.img, self.px(points), color, thickness, closed=False)


def rotate(points: Any, angle: float) -> np.ndarray:
    """``(N, 2)`` points turned counter-clockwise by ``angle`` (y up), as pygame's ``rotate_rad``."""
    c, s = np.cos(angle), np.sin(angle)
    return np.asarray(points, np.float64).reshape(-1, 2) @ np.array([[c, s], [-s, c]])


# -- the env ------------------------------------------------------------------------------------
class ClassicControlEnv(DatasetResetMixin, gym.Env):
    """Base of the classic-control envs; subclasses fill the hooks below.

    Internally the env keeps its physical state ``self._s`` (float64, Gymnasium's ``state``);
    what it shows is Gymnasium's observation (``features``: float64 for the success test,
    float32 in the observation and in ``info["state"]``, as upstream).
    """

    metadata = {"render_modes": ["rgb_array"], "render_fps": 30}
    ENV_NAME = ""  # the Gymnasium id whose dynamics the env reproduces (info["env_name"], as upstream)
    RENDER_SIZE = (400, 600)  # Gymnasium's screen as (H, W): the default frame size
    FEATURES = 0  # length of the observation / state vector

    def __init__(self, render_mode: str | None = "rgb_array", render_size: Sequence[int] | None = None):
        owner = type(self).__name__
        if render_mode not in (None, "rgb_array"):
            raise ConfigError(
                f"{owner} requires render_mode 'rgb_array' or None (frames are drawn headless), got {render_mode!r}"
            )
        self.render_mode = render_mode
        self.render_size = check_render_size(owner, self.RENDER_SIZE if render_size is None else render_size)
        self.env_name = self.ENV_NAME
        self.variation_space = self.build_variation_space()
        self._names = self.variation_space.names()
        self._p: dict[str, float] = {}
        self._colors: dict[str, np.ndarray] = {}
        self._read_factors()
        self._s = np.zeros(self.state_size(), np.float64)
        self._goal_s = self._s.copy()
        self._goal = self.features(self._goal_s)
        self._goal_img: np.ndarray | None = None

    # -- hooks --------------------------------------------------------------------------------
    @classmethod
    def build_variation_space(cls) -> spaces.Dict:
        """The factors of variation (upstream's names, ranges and defaults)."""
        raise NotImplementedError

    def state_size(self) -> int:
        """Length of the physical state."""
        raise NotImplementedError

    def sample_start(self) -> np.ndarray:
        """Gymnasium's start state, drawn from ``self.np_random``."""
        raise NotImplementedError

    def default_goal(self) -> np.ndarray:
        """The physical goal state of the episode (may draw from ``self.np_random``)."""
        raise NotImplementedError

    def features(self, s: np.ndarray) -> np.ndarray:
        """Gymnasium's observation of physical state ``s``, float64."""
        raise NotImplementedError

    def from_features(self, f: np.ndarray) -> np.ndarray:
        """The physical state whose observation is ``f`` (``FEATURES`` numbers, validated)."""
        raise NotImplementedError

    def draw(self, s: np.ndarray) -> np.ndarray:
        """The frame of physical state ``s`` at ``render_size``."""
        raise NotImplementedError

    # -- protocol hooks -----------------------------------------------------------------------
    def set_render_size(self, size: tuple[int, int]) -> None:
        """Draw frames and the goal image at ``size`` = (H, W)."""
        size = check_render_size(type(self).__name__, size)
        if size != self.render_size:
            self.render_size, self._goal_img = size, None

    def eval_state(self, goal_state: np.ndarray, cur_state: np.ndarray) -> tuple[bool, float]:
        """``(success, distance)`` of ``cur_state`` against ``goal_state`` (observation vectors)."""
        raise NotImplementedError

    # -- gym API ------------------------------------------------------------------------------
    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None):
        super().reset(seed=seed)
        if options is not None and not isinstance(options, Mapping):
            raise ConfigError(f"{type(self).__name__}.reset requires options as a dict or None, got {options!r}")
        options = dict(options or {})
        self._s = np.asarray(self.sample_start(), np.float64)  # first, as Gymnasium: its start for the seed
        # upstream seeds the factors with the reset seed; without one, from the env's generator (not fresh entropy)
        vseed = int(seed) if seed is not None else int(self.np_random.integers(0, 2**31 - 1))
        check_variation_option(options, self._names)
        # upstream resamples every factor unless options["variation"] names some ([] resamples none)
        spaces.reset_variation_space(self.variation_space, vseed, options, self._names)
        self._read_factors()
        self._goal_s = np.asarray(self.default_goal(), np.float64)
        if options.get(keys.STATE) is not None:
            self._s = self.from_features(self._option(options[keys.STATE], keys.STATE))
        if options.get(keys.GOAL_STATE) is not None:
            self._goal_s = self.from_features(self._option(options[keys.GOAL_STATE], keys.GOAL_STATE))
        self._goal = self.features(self._goal_s)
        self._goal_img = None
        return self._obs(), self._info()

    def reset_options_from_dataset(
        self, start_row: Mapping[str, np.ndarray], goal_row: Mapping[str, np.ndarray]
    ) -> dict[str, Any]:
        """Start at ``start_row``'s state with ``goal_row``'s as goal and the row's recorded factors;
        factors the row does not record stay at their defaults (not resampled)."""
        return {keys.VARIATION: [], **super().reset_options_from_dataset(start_row, goal_row)}

    def render(self) -> np.ndarray:
        """The current frame, ``render_size`` + ``(3,)`` uint8."""
        return self.draw(self._s)

    def close(self) -> None:
        """Nothing to free (frames are drawn with numpy / OpenCV)."""

    # -- helpers for the envs -----------------------------------------------------------------
    def _read_factors(self) -> None:
        v = self.variation_space.value
        self._p = {k: float(np.asarray(x).reshape(-1)[0]) for k, x in v.get("physics", {}).items()}
        self._colors = {k: to_u8(x) for k, x in v.get("visuals", {}).items()}

    def _success(self) -> tuple[bool, float]:
        return self.eval_state(self._goal, self.features(self._s))

    def _obs(self) -> np.ndarray:
        return self.features(self._s).astype(np.float32)

    def _info(self) -> dict[str, Any]:
        if self._goal_img is None:  # the goal image only changes on reset or a new render size
            self._goal_img = self.draw(self._goal_s)
        state, goal = self._obs(), self._goal.astype(np.float32)
        return {
            ENV_NAME: self.env_name,
            keys.STATE: state,
            keys.PROPRIO: state.copy(),
            keys.GOAL: self._goal_img.copy(),  # check_env rejects infos that share arrays
            keys.GOAL_STATE: goal,
            keys.GOAL_PROPRIO: goal.copy(),
        }

    def _option(self, value: Any, what: str) -> np.ndarray:
        """Reset option ``what`` as ``FEATURES`` finite float64 numbers (ConfigError otherwise)."""
        try:
            arr = np.asarray(value, np.float64).reshape(-1)
        except (TypeError, ValueError) as exc:
            raise ConfigError(
                f"{type(self).__name__} requires reset option {what!r} as {self.FEATURES} numbers "
                f"(the observation layout), got {value!r}"
            ) from exc
        if arr.shape[0] != self.FEATURES or not np.all(np.isfinite(arr)):
            raise ConfigError(
                f"{type(self).__name__} requires reset option {what!r} as {self.FEATURES} finite numbers "
                f"(the observation layout), got {value!r}"
            )
        return arr

    def _pair(self, goal_state: Any, cur_state: Any) -> tuple[np.ndarray, np.ndarray]:
        """``eval_state``'s arguments as float64 vectors of ``FEATURES`` numbers (ConfigError otherwise)."""
        out = []
        for what, v in (("goal_state", goal_state), ("cur_state", cur_state)):
            arr = np.asarray(v, np.float64).reshape(-1)
            if arr.shape[0] != self.FEATURES:
                raise ConfigError(
                    f"{type(self).__name__}.eval_state requires {what} of {self.FEATURES} numbers "
                    f"(the observation layout), got shape {np.shape(v)}"
                )
            out.append(arr)
        return out[0], out[1]

    def _discrete(self, action: Any, n: int) -> int:
        """A ``Discrete(n)`` action as an int (SpaceError naming it otherwise)."""
        arr = np.asarray(action)
        if arr.size == 1 and (np.issubdtype(arr.dtype, np.integer) or np.issubdtype(arr.dtype, np.floating)):
            a = arr.reshape(-1)[0]
            if np.isfinite(a) and float(a) == int(a) and 0 <= int(a) < n:
                return int(a)
        raise SpaceError(
            f"{type(self).__name__}.step requires an action in Discrete({n}) (0 .. {n - 1}), got {action!r}"
        )

    def _continuous(self, action: Any) -> float:
        """A one-number ``Box`` action as a float (SpaceError naming it otherwise)."""
        try:
            arr = np.asarray(action, np.float64).reshape(-1)
        except (TypeError, ValueError):
            arr = np.array([np.nan, np.nan])
        if arr.shape[0] != 1 or not np.isfinite(arr[0]):
            raise SpaceError(f"{type(self).__name__}.step requires one finite action value, got {action!r}")
        return float(arr[0])


def batch_factor(infos: Mapping[str, Any], name: str, default: float, n: int) -> np.ndarray:
    """Factor ``name`` per env ``(n,)`` from ``infos["variation.<name>"]`` (World records the factors
    named in ``reset(options={"variation": [...]})``), else ``default``."""
    key = f"{keys.VARIATION}.{name}"
    if key not in infos:
        return np.full(n, float(default))
    v = np.asarray(infos[key], np.float64)
    return v.reshape(n, -1)[:, -1] if v.size else np.full(n, float(default))

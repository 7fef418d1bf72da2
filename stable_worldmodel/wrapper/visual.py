"""Pixel perturbations (distractors, noise, augmentations) applied to rendered frames.

Each wrapper here changes the images an env shows, never its dynamics: the frame returned by
``render()`` and every ``info["pixels"]`` / ``info["pixels.<view>"]`` of ``reset`` and ``step``
(goal images and observations are left alone). Put one outside a ``MegaWrapper`` to perturb the
recorded pixels, or inside it to perturb what ``render()`` hands to ``AddPixelsWrapper``.

Randomness. A wrapper with a ``seed`` argument draws from its own ``numpy.random.Generator``:
``seed=s`` builds it as ``np.random.default_rng(s)`` and it is never reseeded (as in upstream
0.1.1, so the same seed gives the same frames). With ``seed=None`` it follows Gymnasium's
convention instead: every ``reset(seed=s)`` restarts it as ``np.random.default_rng(s)``, and it
draws fresh OS entropy until a seeded reset comes.

``cv2`` and ``imageio`` are imported on first use, so importing this module stays cheap.
"""

from __future__ import annotations

import math
import numbers
import pathlib
from collections.abc import Callable
from functools import partial

import gymnasium as gym
import numpy as np

from .. import keys
from ..errors import ArgumentTypeError, ConfigError, SpaceError, check_int

__all__ = [
    "BlurWrapper",
    "ChromaKeyWrapper",
    "ColorJitterWrapper",
    "CutoutWrapper",
    "GrayscaleWrapper",
    "MovingPatchWrapper",
    "NoiseWrapper",
    "OcclusionWrapper",
    "RandomConvWrapper",
    "RandomShiftWrapper",
    "ResolutionWrapper",
    "constant",
    "cosine",
    "exponential",
    "linear",
    "sinusoidal",
]

#: file suffixes ChromaKeyWrapper reads as videos (anything else is read as one image)
VIDEO_EXTS = frozenset({".mp4", ".mov", ".avi", ".webm", ".gif", ".mkv"})


# -- schedules for NoiseWrapper(std=...): step -> value (partials, so they pickle) --------------------
def _constant(step: int, value: float) -> float:
    return value


def _linear(step: int, start: float, end: float, horizon: int) -> float:
    progress = min(step / max(1, horizon), 1.0)
    return start + (end - start) * progress


def _cosine(step: int, start: float, end: float, horizon: int) -> float:
    progress = min(step / max(1, horizon), 1.0)
    return end + 0.5 * (start - end) * (1.0 + math.cos(math.pi * progress))


def _exponential(step: int, start: float, decay: float, floor: float) -> float:
    return max(start * decay**step, floor)


def _sinusoidal(step: int, low: float, high: float, period: float) -> float:
    middle, amplitude = 0.5 * (high + low), 0.5 * (high - low)
    return middle + amplitude * math.sin(2.0 * math.pi * step / max(1.0, period))


def constant(value) -> Callable[[int], float]:
    """Schedule that returns ``value`` at every step."""
    return partial(_constant, value=value)


def linear(start, end, horizon) -> Callable[[int], float]:
    """Schedule going linearly from ``start`` (step 0) to ``end`` (step ``horizon``), then staying at ``end``."""
    return partial(_linear, start=start, end=end, horizon=horizon)


def cosine(start, end, horizon) -> Callable[[int], float]:
    """Schedule going from ``start`` to ``end`` along half a cosine over ``horizon`` steps, then staying at ``end``."""
    return partial(_cosine, start=start, end=end, horizon=horizon)


def exponential(start, decay, floor=0.0) -> Callable[[int], float]:
    """Schedule ``start * decay ** step``, never below ``floor``."""
    return partial(_exponential, start=start, decay=decay, floor=floor)


def sinusoidal(low, high, period) -> Callable[[int], float]:
    """Schedule oscillating between ``low`` and ``high`` with a period of ``period`` steps (starts mid-way, rising)."""
    return partial(_sinusoidal, low=low, high=high, period=period)


# -- argument checks ----------------------------------------------------------------------------------
def _number(owner: str, key: str, value, low: float | None = None, strict: bool = False) -> float:
    """``value`` as a finite float (``> low`` when ``strict``, else ``>= low``), or a ConfigError."""
    ok = isinstance(value, numbers.Real) and not isinstance(value, bool) and math.isfinite(value)
    if ok and low is not None:
        ok = value > low if strict else value >= low
    if not ok:
        bound = "" if low is None else f" {'>' if strict else '>='} {low:g}"
        raise ConfigError(f"{owner} requires {key} to be a finite number{bound}, got {value!r}")
    return float(value)


def _fraction_range(owner: str, key: str, value) -> tuple[float, float]:
    """A ``(low, high)`` pair of fractions of the frame size with ``0 <= low <= high``."""
    try:
        low, high = (float(v) for v in value)
        ok = math.isfinite(low) and math.isfinite(high) and 0.0 <= low <= high
    except (TypeError, ValueError):
        ok = False
    if not ok:
        raise ConfigError(
            f"{owner} requires {key} to be a (low, high) pair of fractions of the frame size with "
            f"0 <= low <= high, such as (0.1, 0.3), got {value!r}"
        )
    return low, high


def _fill_color(owner: str, value):
    """A fill value: one number (every channel) or one number per channel."""
    arr = np.asarray(value)
    if arr.ndim > 1 or arr.size == 0 or not (np.issubdtype(arr.dtype, np.number) or arr.dtype == bool):
        raise ConfigError(f"{owner} requires color to be a number or one number per channel, got {value!r}")
    return value


def _require_rgb(owner: str, frame: np.ndarray) -> None:
    if frame.ndim != 3 or frame.shape[-1] != 3:
        raise SpaceError(f"{owner} requires (H, W, 3) RGB frames, got an array of shape {frame.shape}")


def _sample_box(rng: np.random.Generator, size: tuple[float, float], h: int, w: int) -> tuple[int, int, int, int]:
    """A random rectangle ``(top, left, height, width)`` inside an ``h x w`` frame; sides are fractions in ``size``."""
    box_h = max(1, int(rng.uniform(*size) * h))
    box_w = max(1, int(rng.uniform(*size) * w))
    top = int(rng.integers(0, max(1, h - box_h + 1)))
    left = int(rng.integers(0, max(1, w - box_w + 1)))
    return top, left, box_h, box_w


# -- base class ---------------------------------------------------------------------------------------
class _PixelWrapper(gym.Wrapper):
    """Applies :meth:`_perturb` to ``render()`` and to ``info["pixels"]`` / ``info["pixels.<view>"]``.

    Subclasses implement ``_perturb(frame) -> frame`` and may hook ``_on_reset`` (before the
    wrapped env resets) and ``_after_step`` (after the step's frames were perturbed).
    """

    def __init__(self, env: gym.Env, seed=None):
        super().__init__(env)
        self._seed = seed
        self._rng = self._generator(seed)

    def _generator(self, seed) -> np.random.Generator:
        try:
            return np.random.default_rng(seed)
        except TypeError as exc:
            raise ArgumentTypeError(
                f"{type(self).__name__} requires seed to be None, an int >= 0 or a numpy SeedSequence/Generator, "
                f"got {seed!r}"
            ) from exc
        except ValueError as exc:
            raise ConfigError(f"{type(self).__name__} requires seed to be None or an int >= 0, got {seed!r}") from exc

    def _perturb(self, frame: np.ndarray) -> np.ndarray:
        raise NotImplementedError("_perturb(frame) -> frame")

    def _on_reset(self) -> None:
        pass

    def _after_step(self) -> None:
        pass

    def _perturb_views(self, frames):
        if frames is None:
            return None
        if isinstance(frames, dict):  # several views from render(): each one perturbed
            return {name: self._perturb(np.asarray(f)) for name, f in frames.items()}
        if isinstance(frames, (list, tuple)):
            return type(frames)(self._perturb(np.asarray(f)) for f in frames)
        return self._perturb(frames)

    def _perturb_info(self, info: dict) -> dict:
        info = dict(info)
        for key, value in info.items():
            if key == keys.PIXELS or key.startswith(keys.PIXELS + "."):
                info[key] = self._perturb(value)
        return info

    def render(self):
        return self._perturb_views(self.env.render())

    def reset(self, *, seed=None, options=None):
        if seed is not None and self._seed is None:
            self._rng = self._generator(seed)
        self._on_reset()
        obs, info = self.env.reset(seed=seed, options=options)
        return obs, self._perturb_info(info)

    def step(self, action):
        obs, reward, terminated, truncated, info = self.env.step(action)
        info = self._perturb_info(info)
        self._after_step()
        return obs, reward, terminated, truncated, info


# -- wrappers -----------------------------------------------------------------------------------------
def _load_media(path: pathlib.Path) -> np.ndarray:
    import imageio.v3 as iio

    if path.suffix.lower() in VIDEO_EXTS:
        return np.stack(list(iio.imiter(path)))
    return np.asarray(iio.imread(path))


class ChromaKeyWrapper(_PixelWrapper):
    """Green screen: pixels near a key color are replaced by the pixels of an image or video.

    A pixel is replaced when its Euclidean RGB distance to one of the key colors is at most
    ``tolerance``. The background is resized (``INTER_AREA``) to each frame's size. A video
    background moves one frame forward on every perturbed frame (``render()`` and each
    ``pixels*`` info entry) and loops; it does not restart on reset.

    Args:
        env: the env to wrap.
        key_color: one RGB triple, or a sequence of them.
        media: an ``(H, W, 3)`` image or ``(T, H, W, 3)`` video array, or a path to an image or
            video file (suffixes in :data:`VIDEO_EXTS` are read as videos).
        tolerance: largest RGB distance to a key color that is still replaced (``0``: exact match).
    """

    def __init__(self, env: gym.Env, key_color, media, tolerance: float = 0.0):
        super().__init__(env)
        name = type(self).__name__
        colors = np.asarray(key_color)
        if colors.size == 0 or colors.size % 3 or not np.issubdtype(colors.dtype, np.number):
            raise ConfigError(f"{name} requires key_color to be an RGB triple or a sequence of them, got {key_color!r}")
        self.key_colors = colors.reshape(-1, 3).astype(np.int32)
        self.tolerance = _number(name, "tolerance", tolerance, low=0.0)
        if isinstance(media, (str, pathlib.Path)):
            media = _load_media(pathlib.Path(media))
        media = np.asarray(media)
        if media.ndim not in (3, 4) or media.shape[-1] != 3 or 0 in media.shape:
            raise ConfigError(
                f"{name} requires media to be an (H, W, 3) image or a (T, H, W, 3) video (drop an alpha channel "
                f"with media[..., :3]), got an array of shape {media.shape}"
            )
        self.media = media
        self.is_video = media.ndim == 4
        self.frame_index = 0  # next video frame
        self._resized: dict[tuple[int, int], np.ndarray] = {}  # still image, per frame size

    def _background(self, h: int, w: int) -> np.ndarray:
        if not self.is_video and (h, w) in self._resized:
            return self._resized[(h, w)]
        bg = self.media[self.frame_index] if self.is_video else self.media
        if bg.shape[:2] != (h, w):
            import cv2

            bg = cv2.resize(bg, (w, h), interpolation=cv2.INTER_AREA)
        if self.is_video:
            self.frame_index = (self.frame_index + 1) % len(self.media)
        else:
            self._resized[(h, w)] = bg
        return bg

    def _perturb(self, frame):
        _require_rgb(type(self).__name__, frame)
        bg = self._background(*frame.shape[:2])
        diff = frame.astype(np.int32)[None] - self.key_colors[:, None, None, :]
        distance = np.sqrt((diff * diff).sum(axis=-1).astype(np.float64))  # (keys, H, W)
        mask = (distance <= self.tolerance).any(axis=0)
        out = frame.copy()
        out[mask] = bg[mask]
        return out


class NoiseWrapper(_PixelWrapper):
    """Adds Gaussian noise whose standard deviation can follow a schedule over env steps.

    ``std`` is a number or a callable ``step -> std`` (:func:`constant`, :func:`linear`, :func:`cosine`,
    :func:`exponential`, :func:`sinusoidal` or your own). ``step`` is :attr:`step_count`, the number
    of ``env.step`` calls made so far through this wrapper (it is not reset by ``reset``; a step's own
    frames are perturbed before the count goes up). When the std is ``<= 0`` the frame is returned as
    it is. The noisy values are clipped to ``[0, 255]`` and cast back to the frame's dtype (truncating).

    Args:
        env: the env to wrap.
        std: noise standard deviation in pixel units (a number ``>= 0``) or a schedule.
        seed: seed of the noise generator (see the module docstring).
    """

    def __init__(self, env: gym.Env, std: float | Callable[[int], float] = 10.0, seed: int | None = None):
        super().__init__(env, seed)
        self.std = std if callable(std) else constant(_number(type(self).__name__, "std", std, low=0.0))
        self._steps = 0

    @property
    def step_count(self) -> int:
        """Number of ``env.step`` calls made through this wrapper."""
        return self._steps

    def _perturb(self, frame):
        std = float(self.std(self._steps))
        if std <= 0:
            return frame
        noisy = frame.astype(np.float32) + self._rng.normal(0.0, std, frame.shape)
        return np.clip(noisy, 0, 255).astype(frame.dtype)

    def _after_step(self):
        self._steps += 1


class ColorJitterWrapper(_PixelWrapper):
    """Random brightness, contrast, saturation and hue change, drawn anew at every reset.

    Factors are drawn uniformly: brightness and contrast and saturation multipliers in
    ``[max(0, 1 - x), 1 + x]``, hue shift in ``[-hue, hue]`` (fraction of the colour wheel).
    Brightness scales the frame, contrast scales each channel's distance to its mean, then
    saturation and hue are changed in OpenCV's 8-bit HSV space. Frames must be ``(H, W, 3)`` RGB.

    Args:
        env: the env to wrap.
        brightness, contrast, saturation, hue: jitter strengths, each ``>= 0`` (0 turns that part off).
        seed: seed of the generator (see the module docstring); the first factors are drawn at construction.
    """

    def __init__(
        self,
        env: gym.Env,
        brightness: float = 0.2,
        contrast: float = 0.2,
        saturation: float = 0.2,
        hue: float = 0.05,
        seed: int | None = None,
    ):
        super().__init__(env, seed)
        name = type(self).__name__
        self.brightness = _number(name, "brightness", brightness, low=0.0)
        self.contrast = _number(name, "contrast", contrast, low=0.0)
        self.saturation = _number(name, "saturation", saturation, low=0.0)
        self.hue = _number(name, "hue", hue, low=0.0)
        self._draw_factors()

    def _draw_factors(self) -> None:
        def around_one(x: float) -> float:
            return float(self._rng.uniform(max(0.0, 1.0 - x), 1.0 + x))

        self.brightness_factor = around_one(self.brightness)
        self.contrast_factor = around_one(self.contrast)
        self.saturation_factor = around_one(self.saturation)
        self.hue_shift = float(self._rng.uniform(-self.hue, self.hue))

    def _on_reset(self):
        self._draw_factors()

    def _perturb(self, frame):
        import cv2

        _require_rgb(type(self).__name__, frame)
        img = frame.astype(np.float32) * self.brightness_factor
        channel_mean = img.mean(axis=(0, 1), keepdims=True)
        img = (img - channel_mean) * self.contrast_factor + channel_mean
        hsv = cv2.cvtColor(np.clip(img, 0, 255).astype(np.uint8), cv2.COLOR_RGB2HSV).astype(np.float32)
        hsv[..., 0] = (hsv[..., 0] + self.hue_shift * 180.0) % 180.0  # OpenCV hue runs over [0, 180)
        hsv[..., 1] = np.clip(hsv[..., 1] * self.saturation_factor, 0, 255)
        return cv2.cvtColor(hsv.astype(np.uint8), cv2.COLOR_HSV2RGB).astype(frame.dtype)


class BlurWrapper(_PixelWrapper):
    """Gaussian blur (``cv2.GaussianBlur``).

    Args:
        env: the env to wrap.
        kernel: kernel side in pixels, ``>= 0``; an even value is raised to the next odd one (0 -> 1, no blur).
        sigma: Gaussian standard deviation; ``0`` derives it from ``kernel``.
    """

    def __init__(self, env: gym.Env, kernel: int = 5, sigma: float = 0.0):
        super().__init__(env)
        self.kernel = check_int(type(self).__name__, "kernel", kernel, minimum=0) | 1
        self.sigma = _number(type(self).__name__, "sigma", sigma)

    def _perturb(self, frame):
        import cv2

        return cv2.GaussianBlur(frame, (self.kernel, self.kernel), self.sigma)


class OcclusionWrapper(_PixelWrapper):
    """Covers the frame with ``num_patches`` fixed rectangles, placed anew at every reset.

    The rectangles are drawn on the first frame after a reset (each side a uniform fraction of the
    frame side in ``size``, position uniform inside the frame) and stay put for the episode.

    Args:
        env: the env to wrap.
        num_patches: number of rectangles (``>= 0``).
        size: ``(low, high)`` range of each side as a fraction of the frame side.
        color: fill value, one number or one per channel.
        seed: seed of the generator (see the module docstring).
    """

    def __init__(self, env: gym.Env, num_patches: int = 1, size=(0.1, 0.3), color=0, seed: int | None = None):
        super().__init__(env, seed)
        name = type(self).__name__
        self.num_patches = check_int(name, "num_patches", num_patches, minimum=0)
        self.size = _fraction_range(name, "size", size)
        self.color = _fill_color(name, color)
        self.patches: list[tuple[int, int, int, int]] | None = None  # (top, left, height, width)

    def _on_reset(self):
        self.patches = None

    def _perturb(self, frame):
        if self.patches is None:
            h, w = frame.shape[:2]
            self.patches = [_sample_box(self._rng, self.size, h, w) for _ in range(self.num_patches)]
        out = frame.copy()
        for top, left, box_h, box_w in self.patches:
            out[top : top + box_h, left : left + box_w] = self.color
        return out


class MovingPatchWrapper(_PixelWrapper):
    """Overlays ``num_patches`` solid rectangles that drift across the frame and bounce off its edges.

    At the first frame after a reset each rectangle gets a size (sides a uniform fraction of the frame
    side in ``size``), a position and a direction (uniform angle); after every ``env.step`` it moves by
    ``speed`` pixels along that direction, mirrored at the frame edges. A step's own frames show the
    rectangles where they were before that step's move.

    Args:
        env: the env to wrap.
        num_patches: number of rectangles (``>= 0``).
        size: ``(low, high)`` range of each side as a fraction of the frame side.
        color: fill value, one number or one per channel.
        speed: distance moved per step, in pixels (``>= 0``).
        seed: seed of the generator (see the module docstring).
    """

    def __init__(
        self,
        env: gym.Env,
        num_patches: int = 1,
        size=(0.1, 0.2),
        color=255,
        speed: float = 2.0,
        seed: int | None = None,
    ):
        super().__init__(env, seed)
        name = type(self).__name__
        self.num_patches = check_int(name, "num_patches", num_patches, minimum=0)
        self.size = _fraction_range(name, "size", size)
        self.color = _fill_color(name, color)
        self.speed = _number(name, "speed", speed, low=0.0)
        self.patches: list[list[float]] | None = None  # [y, x, height, width, vy, vx]
        self._frame_hw: tuple[int, int] | None = None

    def _place(self, h: int, w: int) -> list[float]:
        rng = self._rng
        box_h = max(1, int(rng.uniform(*self.size) * h))
        box_w = max(1, int(rng.uniform(*self.size) * w))
        y = float(rng.uniform(0, max(1, h - box_h)))
        x = float(rng.uniform(0, max(1, w - box_w)))
        angle = float(rng.uniform(0, 2 * math.pi))
        return [y, x, box_h, box_w, self.speed * math.sin(angle), self.speed * math.cos(angle)]

    @staticmethod
    def _bounce(pos: float, vel: float, limit: float) -> tuple[float, float]:
        """Mirror ``pos`` into ``[0, limit]`` (as often as needed), flipping ``vel`` at each mirror."""
        if limit <= 0:
            return 0.0, vel
        while pos < 0 or pos > limit:
            pos = -pos if pos < 0 else 2 * limit - pos
            vel = -vel
        return pos, vel

    def _on_reset(self):
        self.patches = None
        self._frame_hw = None

    def _after_step(self):
        if self.patches is None or self._frame_hw is None:
            return
        h, w = self._frame_hw
        for p in self.patches:
            p[0], p[4] = self._bounce(p[0] + p[4], p[4], h - p[2])
            p[1], p[5] = self._bounce(p[1] + p[5], p[5], w - p[3])

    def _perturb(self, frame):
        if self.patches is None:
            self._frame_hw = frame.shape[:2]
            self.patches = [self._place(*self._frame_hw) for _ in range(self.num_patches)]
        out = frame.copy()
        for y, x, box_h, box_w, _, _ in self.patches:
            top, left = int(y), int(x)
            out[top : top + box_h, left : left + box_w] = self.color
        return out


class RandomShiftWrapper(_PixelWrapper):
    """DrQ-style random shift: pads each frame by ``pad`` pixels (edge replicated) and crops back at a random offset.

    A new offset is drawn for every frame (each of ``render()`` and each ``pixels*`` info entry).

    Args:
        env: the env to wrap.
        pad: largest shift in pixels, ``>= 0`` (0: frames unchanged).
        seed: seed of the generator (see the module docstring).
    """

    def __init__(self, env: gym.Env, pad: int = 4, seed: int | None = None):
        super().__init__(env, seed)
        self.pad = check_int(type(self).__name__, "pad", pad, minimum=0)

    def _perturb(self, frame):
        p = self.pad
        widths = [(p, p), (p, p)] + [(0, 0)] * (frame.ndim - 2)
        padded = np.pad(frame, widths, mode="edge")
        dy = int(self._rng.integers(0, 2 * p + 1))
        dx = int(self._rng.integers(0, 2 * p + 1))
        h, w = frame.shape[:2]
        return padded[dy : dy + h, dx : dx + w]


class CutoutWrapper(_PixelWrapper):
    """Fills ``num`` random rectangles of every frame with ``color`` (new rectangles for each frame).

    Args:
        env: the env to wrap.
        num: rectangles per frame (``>= 0``).
        size: ``(low, high)`` range of each side as a fraction of the frame side.
        color: fill value, one number or one per channel.
        seed: seed of the generator (see the module docstring).
    """

    def __init__(self, env: gym.Env, num: int = 1, size=(0.1, 0.2), color=0, seed: int | None = None):
        super().__init__(env, seed)
        name = type(self).__name__
        self.num = check_int(name, "num", num, minimum=0)
        self.size = _fraction_range(name, "size", size)
        self.color = _fill_color(name, color)

    def _perturb(self, frame):
        h, w = frame.shape[:2]
        out = frame.copy()
        for _ in range(self.num):
            top, left, box_h, box_w = _sample_box(self._rng, self.size, h, w)
            out[top : top + box_h, left : left + box_w] = self.color
        return out


class RandomConvWrapper(_PixelWrapper):
    """Passes RGB frames through a random 3 -> 3 channel convolution whose weights are drawn anew at every reset.

    Weights are ``N(0, 1 / (3 k^2))``; the filter is applied as a correlation with reflected borders
    (``cv2.filter2D``), and the result is clipped to ``[0, 255]`` and cast back to the frame's dtype.

    Args:
        env: the env to wrap.
        kernel_size: kernel side ``k``, ``>= 0``; an even value is raised to the next odd one.
        seed: seed of the generator (see the module docstring); the first weights are drawn at construction.
    """

    def __init__(self, env: gym.Env, kernel_size: int = 3, seed: int | None = None):
        super().__init__(env, seed)
        self.kernel_size = check_int(type(self).__name__, "kernel_size", kernel_size, minimum=0) | 1
        self._draw_weights()

    def _draw_weights(self) -> None:
        k = self.kernel_size
        std = math.sqrt(1.0 / (3 * k * k))
        self.weights = self._rng.normal(0.0, std, (3, k, k, 3)).astype(np.float32)  # (out, k, k, in)

    def _on_reset(self):
        self._draw_weights()

    def _perturb(self, frame):
        import cv2

        _require_rgb(type(self).__name__, frame)
        img = frame.astype(np.float32)
        out = np.empty_like(img)
        for c_out in range(3):
            acc = np.zeros(img.shape[:2], np.float32)
            for c_in in range(3):
                acc += cv2.filter2D(img[..., c_in], -1, self.weights[c_out, :, :, c_in])
            out[..., c_out] = acc
        return np.clip(out, 0, 255).astype(frame.dtype)


class GrayscaleWrapper(_PixelWrapper):
    """Turns RGB frames to grayscale (``cv2.COLOR_RGB2GRAY`` luma).

    Args:
        env: the env to wrap.
        keep_channels: True gives ``(H, W, 3)`` frames with three equal channels, False ``(H, W)`` frames.
    """

    def __init__(self, env: gym.Env, keep_channels: bool = True):
        super().__init__(env)
        self.keep_channels = bool(keep_channels)

    def _perturb(self, frame):
        import cv2

        _require_rgb(type(self).__name__, frame)
        gray = cv2.cvtColor(frame, cv2.COLOR_RGB2GRAY)
        return np.repeat(gray[..., None], 3, axis=-1) if self.keep_channels else gray


class ResolutionWrapper(_PixelWrapper):
    """Lowers the effective resolution: shrinks each frame by ``scale`` (``INTER_AREA``), then scales it
    back to its size with nearest-neighbour interpolation (blocky pixels).

    Args:
        env: the env to wrap.
        scale: size factor of the intermediate frame, ``> 0`` (sides are rounded, at least 1 pixel).
    """

    def __init__(self, env: gym.Env, scale: float = 0.5):
        super().__init__(env)
        self.scale = _number(type(self).__name__, "scale", scale, low=0.0, strict=True)

    def _perturb(self, frame):
        import cv2

        h, w = frame.shape[:2]
        small_w = max(1, int(round(w * self.scale)))
        small_h = max(1, int(round(h * self.scale)))
        small = cv2.resize(frame, (small_w, small_h), interpolation=cv2.INTER_AREA)
        return cv2.resize(small, (w, h), interpolation=cv2.INTER_NEAREST)

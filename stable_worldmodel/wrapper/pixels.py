"""AddPixelsWrapper: put the rendered frame(s) into ``info``."""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any, Protocol, runtime_checkable

import gymnasium as gym
import numpy as np

from .. import keys
from ..envs.base import SupportsRenderSize
from ._image import check_shape, resize


@runtime_checkable
class SupportsMultiview(Protocol):
    """An env that renders several views at once (dict name -> image, or a list)."""

    def render_multiview(self) -> dict[str, np.ndarray] | list[np.ndarray]: ...


class AddPixelsWrapper(gym.Wrapper):
    """Adds rendered pixels to ``info`` after ``reset`` and ``step``.

    - single view: ``info["pixels"]``; a dict of views: ``info["pixels.<name>"]``; a list or
      tuple: ``info["pixels.<i>"]``. The views come from ``render_multiview()`` when the env
      has it (:class:`SupportsMultiview`), else from ``render()``, which may return one image
      or such a dict/list. ``info["render_time"]`` is the render+resize time in seconds.
    - Envs that implement :class:`~stable_worldmodel.envs.base.SupportsRenderSize` are asked once
      to draw at ``pixels_shape``; other frames are resized (cv2, area interpolation).
    - ``torchvision_transform`` (any callable on an (H, W, 3) uint8 array) is applied last.
    """

    def __init__(
        self, env: gym.Env, pixels_shape: tuple[int, int] = (84, 84), torchvision_transform: Callable | None = None
    ):
        super().__init__(env)
        self.pixels_shape = check_shape("AddPixelsWrapper pixels_shape", pixels_shape)
        self.torchvision_transform = torchvision_transform
        if isinstance(env.unwrapped, SupportsRenderSize):
            env.unwrapped.set_render_size(self.pixels_shape)
        self._multiview = isinstance(env.unwrapped, SupportsMultiview)

    def _frame(self, img: Any) -> Any:
        img = resize(np.asarray(img), self.pixels_shape)
        return self.torchvision_transform(img) if self.torchvision_transform is not None else img

    def _add_pixels(self, info: dict[str, Any]) -> dict[str, Any]:
        start = time.perf_counter()
        views = self.env.unwrapped.render_multiview() if self._multiview else self.env.render()
        if isinstance(views, dict):
            for name, img in views.items():
                info[f"{keys.PIXELS}.{name}"] = self._frame(img)
        elif isinstance(views, (list, tuple)):
            for i, img in enumerate(views):
                info[f"{keys.PIXELS}.{i}"] = self._frame(img)
        else:
            info[keys.PIXELS] = self._frame(views)
        info[keys.RENDER_TIME] = time.perf_counter() - start
        return info

    def reset(self, *, seed: int | None = None, options: dict | None = None):
        obs, info = self.env.reset(seed=seed, options=options)
        return obs, self._add_pixels(dict(info))

    def step(self, action):
        obs, reward, terminated, truncated, info = self.env.step(action)
        return obs, reward, terminated, truncated, self._add_pixels(dict(info))

"""``VideoDataset``: numeric columns in one ``.npz``, one MP4 per episode and image column.

Layout::

    <root>/
      meta.json                  {"format": "video", "images": {"pixels": [H, W, C]}, "fps": 30}
      columns.npz                numeric columns (N, ...) plus ep_len and ep_offset
      pixels/episode_000004.mp4  H.264 video of episode 4 of column ``pixels``

Decoding uses PyAV (``pip install "stable-worldmodel[video]"``), or decord when installed and
``decoder="decord"``. The last decoded episodes are kept in memory. H.264 is lossy.
"""

from __future__ import annotations

import os
from collections import OrderedDict
from collections.abc import Callable, Sequence
from pathlib import Path

import numpy as np

from .._optional import require
from ..errors import ConfigError
from .dataset import Dataset
from .folder import _DirectoryDataset, split_columns, write_meta
from .video import write_mp4

EPISODES_IN_MEMORY = 4


class VideoDataset(_DirectoryDataset):
    """Windows of a video dataset (see the module docstring); arguments as :class:`HDF5Dataset`."""

    kind = "video"

    def __init__(
        self,
        name: str | os.PathLike,
        frameskip: int = 1,
        num_steps: int = 1,
        transform: Callable[[dict], dict] | None = None,
        keys_to_load: Sequence[str] | None = None,
        cache_dir: str | os.PathLike | None = None,
        decoder: str = "av",
    ):
        if decoder not in ("av", "decord"):
            raise ConfigError(f"VideoDataset requires decoder 'av' or 'decord', got {decoder!r}")
        require(decoder, extra="video", purpose="VideoDataset")
        super().__init__(name, frameskip=frameskip, num_steps=num_steps, transform=transform, keys_to_load=keys_to_load, cache_dir=cache_dir)
        self.decoder = decoder
        self._decoded: OrderedDict = OrderedDict()

    def __getstate__(self) -> dict:
        state = self.__dict__.copy()
        state["_decoded"] = OrderedDict()
        return state

    def _episode_frames(self, col: str, ep: int) -> np.ndarray:
        key = (col, ep)
        frames = self._decoded.get(key)
        if frames is None:
            frames = self._decode(self.path / col / f"episode_{ep:06d}.mp4")
            h, w, c = self._images[col]
            frames = frames[:, :h, :w, :1] if c == 1 else frames[:, :h, :w, :3]
            self._decoded[key] = frames
            if len(self._decoded) > EPISODES_IN_MEMORY:
                self._decoded.popitem(last=False)
        else:
            self._decoded.move_to_end(key)
        return frames

    def _decode(self, path: Path) -> np.ndarray:
        if self.decoder == "decord":  # pragma: no cover - optional
            decord = require("decord", extra="video")
            return decord.VideoReader(str(path)).get_batch(list(range(len(decord.VideoReader(str(path)))))).asnumpy()
        av = require("av", extra="video")
        with av.open(str(path)) as container:
            return np.stack([f.to_ndarray(format="rgb24") for f in container.decode(video=0)])

    def _read_images(self, col: str, start: int, stop: int) -> np.ndarray:
        parts = []
        while start < stop:
            ep = int(np.searchsorted(self._offsets, start, side="right") - 1)
            first = int(self._offsets[ep])
            end = min(stop, first + int(self._lengths[ep]))
            parts.append(self._episode_frames(col, ep)[start - first : end - first])
            start = end
        if not parts:
            h, w, c = self._images[col]
            return np.empty((0, h, w, c), np.uint8)
        return np.concatenate(parts) if len(parts) > 1 else parts[0]


def write_video_dataset(dataset: Dataset, path: str | os.PathLike, fps: int = 30) -> Path:
    """Convert ``dataset`` (e.g. an :class:`HDF5Dataset`) to a video dataset at ``path``."""
    path = Path(path)
    numeric, images = split_columns(dataset)
    offsets, lengths = numeric["ep_offset"], numeric["ep_len"]
    for col, data in images.items():
        for ep, (o, n) in enumerate(zip(offsets, lengths)):
            write_mp4(path / col / f"episode_{ep:06d}.mp4", data[int(o) : int(o) + int(n)], fps=fps, quality=10)
    write_meta(path, "video", numeric, images, fps=fps)
    return path

"""``VideoDataset``: numeric columns in ``.npz`` files, one MP4 per episode and media column.

Layouts in :mod:`._layout` (released: ``<key>/ep_{e}.mp4``; our earlier one:
``<key>/episode_{e:06d}.mp4`` next to ``meta.json``). Decoding uses PyAV
(``pip install "stable-worldmodel[video]"``), or decord when ``decoder="decord"`` (the
default, ``None``, takes PyAV when installed, else decord). The last decoded episodes are kept
in memory. H.264 is lossy.
"""

from __future__ import annotations

import json
import os
from collections import OrderedDict
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from .._optional import is_available, require
from ..errors import ConfigError, DatasetFormatError
from ._layout import FRAMES_FILE
from .dataset import Dataset
from .folder import FolderDataset, FolderWriter, episodes_of
from .video import write_mp4

EPISODES_IN_MEMORY = 4
DECODERS = ("av", "decord")


def decode_video(path: Path, decoder: str) -> np.ndarray:
    """Every frame of the video at ``path`` as ``(T, H, W, 3)`` uint8."""
    if not path.is_file():
        raise FileNotFoundError(f"VideoDataset requires the video {str(path)!r}, which does not exist")
    if decoder == "decord":
        decord = require("decord", extra="video", purpose="VideoDataset(decoder='decord')")
        reader = decord.VideoReader(str(path), num_threads=1)
        frames = reader.get_batch(list(range(len(reader))))
        return np.asarray(frames.asnumpy() if hasattr(frames, "asnumpy") else frames.numpy())  # decord's torch bridge
    av = require("av", extra="video", purpose="VideoDataset")
    with av.open(str(path)) as container:
        return np.stack([f.to_ndarray(format="rgb24") for f in container.decode(video=0)])


class VideoDataset(FolderDataset):
    """Windows of a video dataset; arguments as 0.0.3 (``video_keys`` are the media columns,
    default: every sub-folder holding ``ep_*.mp4``) plus those of :class:`FolderDataset`
    by keyword, and ``decoder`` (``"av"``, ``"decord"`` or None for whichever is installed)."""

    media_kind = "video"
    meta_kind = "video"

    def __init__(
        self,
        name: str | os.PathLike | None = None,
        video_keys: Sequence[str] | None = None,
        *,
        decoder: str | None = None,
        **kwargs: Any,
    ):
        if decoder is None:
            decoder = "decord" if not is_available("av") and is_available("decord") else "av"
        if decoder not in DECODERS:
            raise ConfigError(f"VideoDataset requires decoder 'av' or 'decord' (or None), got {decoder!r}")
        require(decoder, extra="video", purpose="VideoDataset")
        self.decoder = decoder
        self._decoded: OrderedDict = OrderedDict()
        super().__init__(name, folder_keys=video_keys, **kwargs)

    def __getstate__(self) -> dict:
        state = self.__dict__.copy()
        state["_decoded"] = OrderedDict()
        return state

    def _episode(self, col: str, ep: int) -> np.ndarray:
        """Decoded frames ``(L, H, W, C)`` of episode ``ep`` of ``col`` (cropped to the recorded size)."""
        key = (col, ep)
        frames = self._decoded.get(key)
        if frames is not None:
            self._decoded.move_to_end(key)
            return frames
        frames = decode_video(self.layout.video_file(col, ep), self.decoder)
        shape = self.layout.shapes.get(col)
        if shape is not None:
            h, w, c = shape
            frames = frames[:, :h, :w, :1] if c == 1 else frames[:, :h, :w, :3]
        self._decoded[key] = frames
        if len(self._decoded) > EPISODES_IN_MEMORY:
            self._decoded.popitem(last=False)
        return frames

    def _frames(self, col: str, ep: int, steps: np.ndarray) -> np.ndarray:
        frames = self._episode(col, ep)
        if len(steps) and int(steps.max()) >= len(frames):
            raise DatasetFormatError(
                f"VideoDataset requires a frame per row in {self.layout.video_file(col, ep)}, got {len(frames)} frames "
                f"for an episode of {int(self.lengths[ep])} rows"
            )
        return frames[steps]


class VideoWriter(FolderWriter):
    """:class:`FolderWriter` that stores each media column of an episode as ``<key>/ep_{e}.mp4``
    (``codec``, default H.264, at ``fps``; odd frame sizes are padded and ``<key>/frames.json``
    records the true one). Upstream 0.1.1's signature: ``VideoWriter(path, fps=25, codec="libx264",
    *, mode="append")``; ``quality`` (0-10) is ours."""

    def __init__(
        self,
        path: str | os.PathLike,
        fps: int = 25,
        codec: str = "libx264",
        *,
        mode: str = "append",
        quality: int = 10,
    ):
        if isinstance(fps, bool) or not isinstance(fps, (int, float)) or fps <= 0:
            raise ConfigError(f"VideoWriter requires fps > 0, got {fps!r}")
        if not 0 <= quality <= 10:
            raise ConfigError(f"VideoWriter requires 0 <= quality <= 10, got {quality!r}")
        if not isinstance(codec, str) or not codec:
            raise ConfigError(
                f"VideoWriter requires codec to be an ffmpeg encoder name such as 'libx264', got {codec!r}"
            )
        super().__init__(path, mode=mode)
        self.fps, self.codec, self.video_quality = fps, codec, quality

    def _write_media(self, col: str, ep: int, frames: np.ndarray) -> None:
        path = self.path / col / f"ep_{ep}.mp4"
        write_mp4(path, frames, fps=self.fps, quality=self.video_quality, codec=self.codec)
        h, w, c = frames.shape[1:]
        sidecar = self.path / col / FRAMES_FILE
        if h % 2 or w % 2 or c == 1:  # what the decoded frames do not say
            sidecar.write_text(json.dumps({"shape": [h, w, c]}))


def write_video_dataset(dataset: Dataset, path: str | os.PathLike, fps: int = 30, mode: str = "error") -> Path:
    """Convert ``dataset`` (e.g. an :class:`HDF5Dataset`) to a video dataset at ``path``."""
    with VideoWriter(path, mode=mode, fps=fps) as writer:
        writer.write_episodes(episodes_of(dataset))
    return Path(path)

"""``video``: ``ep_len.npz`` + one ``.npz`` per column + one MP4 per episode (see :mod:`.._layout`)."""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

from ..._lazy import lazy_getattr
from .._layout import EP_LEN_FILE, has_videos
from ..format import Format, register_format

# the reader and writer, as 0.1.1 placed them here (imported on first use)
__getattr__ = lazy_getattr(
    __name__,
    {"VideoDataset": "stable_worldmodel.data.video_dataset", "VideoWriter": "stable_worldmodel.data.video_dataset"},
)


@register_format
class Video(Format):
    name = "video"

    @classmethod
    def detect(cls, path: str | os.PathLike) -> bool:
        p = Path(path)
        return (p / EP_LEN_FILE).is_file() and has_videos(p)

    @classmethod
    def open_reader(cls, path: str | os.PathLike, **kwargs: Any) -> Any:
        from ..video_dataset import VideoDataset

        return VideoDataset(path=path, **kwargs)

    @classmethod
    def open_writer(cls, path: str | os.PathLike, **kwargs: Any) -> Any:
        from ..video_dataset import VideoWriter

        return VideoWriter(path, **kwargs)

"""``lance_video``: a Lance frames table ``<name>.lance`` beside its videos table
``<name>_videos.lance`` (upstream main's format; see :mod:`stable_worldmodel.data.lance_video`).
Reading and writing need the ``lance`` and ``video`` extras (pylance, PyAV)."""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

from ..._lazy import lazy_getattr
from ..format import Format, register_format

# the reader and writer, where upstream placed them (imported on first use)
__getattr__ = lazy_getattr(
    __name__,
    {
        "LanceVideoDataset": "stable_worldmodel.data.lance_video",
        "LanceVideoWriter": "stable_worldmodel.data.lance_video",
    },
)

SUFFIX = "_videos"  # the videos table of x.lance is x_videos.lance


def _has_videos(frames: Path) -> bool:
    return frames.is_dir() and (frames.parent / f"{frames.stem}{SUFFIX}.lance").is_dir()


@register_format
class LanceVideo(Format):
    name = "lance_video"

    @classmethod
    def detect(cls, path: str | os.PathLike) -> bool:
        """A frames table ``x.lance`` whose ``x_videos.lance`` is beside it, or a folder holding one such
        pair and no other table (a videos table alone is not a dataset)."""
        p = Path(path)
        if p.suffix.lower() == ".lance":
            return _has_videos(p)
        if not p.is_dir():
            return False
        tables = sorted(p.glob("*.lance"))
        frames = [t for t in tables if _has_videos(t)]
        return len(frames) == 1 and len(tables) == 2

    @classmethod
    def open_reader(cls, path: str | os.PathLike, **kwargs: Any) -> Any:
        from ..lance_video import LanceVideoDataset

        return LanceVideoDataset(path, **kwargs)

    @classmethod
    def open_writer(cls, path: str | os.PathLike, **kwargs: Any) -> Any:
        from ..lance_video import LanceVideoWriter

        return LanceVideoWriter(path, **kwargs)

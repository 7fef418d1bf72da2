"""``folder-meta`` / ``video-meta``: our earlier folder layouts (``meta.json`` + ``columns.npz``),
read only (see :mod:`.._layout`); convert them with ``write_folder_dataset`` / ``write_video_dataset``."""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

from .._layout import meta_kind
from ..format import Format, register_format


@register_format
class VideoMeta(Format):
    name = "video-meta"

    @classmethod
    def detect(cls, path: str | os.PathLike) -> bool:
        return meta_kind(Path(path)) == "video"

    @classmethod
    def open_reader(cls, path: str | os.PathLike, **kwargs: Any) -> Any:
        from ..video_dataset import VideoDataset

        return VideoDataset(path=path, **kwargs)


@register_format
class FolderMeta(Format):
    name = "folder-meta"

    @classmethod
    def detect(cls, path: str | os.PathLike) -> bool:
        return meta_kind(Path(path)) == "folder"

    @classmethod
    def open_reader(cls, path: str | os.PathLike, **kwargs: Any) -> Any:
        from ..folder import FolderDataset

        return FolderDataset(path=path, **kwargs)

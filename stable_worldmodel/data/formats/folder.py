"""``folder``: ``ep_len.npz`` + one ``.npz`` per column + one JPEG per step (see :mod:`.._layout`)."""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

from ..._lazy import lazy_getattr
from .._layout import EP_LEN_FILE
from ..format import Format, register_format

# the reader and writer, as 0.1.1 placed them here (imported on first use)
__getattr__ = lazy_getattr(
    __name__,
    {
        "FolderDataset": "stable_worldmodel.data.folder",
        "ImageDataset": "stable_worldmodel.data.folder",
        "FolderWriter": "stable_worldmodel.data.folder",
    },
)


@register_format
class Folder(Format):
    name = "folder"

    @classmethod
    def detect(cls, path: str | os.PathLike) -> bool:
        return (Path(path) / EP_LEN_FILE).is_file()

    @classmethod
    def open_reader(cls, path: str | os.PathLike, **kwargs: Any) -> Any:
        from ..folder import FolderDataset

        return FolderDataset(path=path, **kwargs)

    @classmethod
    def open_writer(cls, path: str | os.PathLike, **kwargs: Any) -> Any:
        from ..folder import FolderWriter

        return FolderWriter(path, **kwargs)

"""``lance``: a Lance directory ``<name>.lance`` (upstream 0.1.1's default collect format; see
:mod:`stable_worldmodel.data.lance`). Reading and writing need the ``lance`` extra (pylance)."""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

from ..._lazy import lazy_getattr
from ..format import Format, register_format

# the reader and writer, where upstream placed them (imported on first use)
__getattr__ = lazy_getattr(
    __name__, {"LanceDataset": "stable_worldmodel.data.lance", "LanceWriter": "stable_worldmodel.data.lance"}
)


@register_format
class Lance(Format):
    name = "lance"

    @classmethod
    def detect(cls, path: str | os.PathLike) -> bool:
        p = Path(path)
        if p.suffix.lower() == ".lance":
            if p.stem.endswith("_videos") and p.with_name(p.stem[: -len("_videos")] + ".lance").is_dir():
                return False  # the videos table of a lance_video dataset, not a dataset of its own
            return p.is_dir() or not p.exists()
        return p.is_dir() and len(list(p.glob("*.lance"))) == 1

    @classmethod
    def open_reader(cls, path: str | os.PathLike, **kwargs: Any) -> Any:
        from ..lance import LanceDataset

        return LanceDataset(path, **kwargs)

    @classmethod
    def open_writer(cls, path: str | os.PathLike, **kwargs: Any) -> Any:
        from ..lance import LanceWriter

        return LanceWriter(path, **kwargs)

"""``hdf5``: one ``.h5`` file, one dataset per column (layout in :mod:`..writer`), or a folder of
``shard_*.h5`` files read as one dataset (what ``swm collect --ray`` records)."""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

from ..._lazy import lazy_getattr
from ..format import Format, register_format

# the reader and writer, as 0.1.1 placed them here (imported on first use)
__getattr__ = lazy_getattr(
    __name__, {"HDF5Dataset": "stable_worldmodel.data.hdf5", "HDF5Writer": "stable_worldmodel.data.writer"}
)

SUFFIXES = (".h5", ".hdf5")


@register_format
class HDF5(Format):
    name = "hdf5"
    summary_options = {"preload": False}  # a summary reads a few rows: no need to decode it all

    @classmethod
    def detect(cls, path: str | os.PathLike) -> bool:
        p = Path(path)
        return (p.suffix in SUFFIXES and p.is_file()) or (p.is_dir() and any(p.glob("shard_*.h5")))

    @classmethod
    def open_reader(cls, path: str | os.PathLike, **kwargs: Any) -> Any:
        from ..hdf5 import HDF5Dataset

        return HDF5Dataset(path, **kwargs)

    @classmethod
    def open_writer(cls, path: str | os.PathLike, **kwargs: Any) -> Any:
        from ..writer import HDF5Writer

        return HDF5Writer(path, **kwargs)

"""``FolderDataset`` / ``ImageDataset``: numeric columns in one ``.npz``, one JPEG per image row.

Layout::

    <root>/
      meta.json            {"format": "folder", "images": {"pixels": [H, W, C], ...}}
      columns.npz          every numeric column (N, ...) plus ep_len (E,) and ep_offset (E,)
      pixels/000000123.jpg one JPEG per row of each image column (row = global row number)

JPEG is lossy: images read back differ slightly from the recorded ones.
"""

from __future__ import annotations

import json
import os
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from .. import keys
from ..errors import DatasetFormatError
from .dataset import Dataset, image_like
from .utils import get_cache_dir

META = "meta.json"
COLUMNS = "columns.npz"


def resolve_dir(name: str | os.PathLike, cache_dir: str | os.PathLike | None) -> Path:
    """``name`` as a directory path when it exists or has a directory part, else ``<cache_dir>/<name>``."""
    path = Path(name).expanduser()
    if path.is_dir() or len(path.parts) > 1:
        return path
    return (Path(cache_dir).expanduser() if cache_dir is not None else get_cache_dir()) / str(name)


class _DirectoryDataset(Dataset):
    """Shared by the folder and video kinds: ``meta.json`` + ``columns.npz`` in a directory."""

    kind = "folder"

    def __init__(
        self,
        name: str | os.PathLike,
        frameskip: int = 1,
        num_steps: int = 1,
        transform: Callable[[dict], dict] | None = None,
        keys_to_load: Sequence[str] | None = None,
        cache_dir: str | os.PathLike | None = None,
    ):
        super().__init__(frameskip=frameskip, num_steps=num_steps, transform=transform, keys_to_load=keys_to_load)
        self.path = resolve_dir(name, cache_dir)
        meta_path = self.path / META
        if not meta_path.is_file():
            raise FileNotFoundError(f"{type(self).__name__} requires {str(meta_path)!r} (not found)")
        self.meta = json.loads(meta_path.read_text())
        if self.meta.get("format") != self.kind:
            raise DatasetFormatError(
                f"{type(self).__name__} requires a {self.kind!r} dataset, got format {self.meta.get('format')!r} in {self.path}"
            )
        with np.load(self.path / COLUMNS) as npz:
            self._arrays = {k: npz[k] for k in npz.files}
        self._lengths = self._arrays.pop(keys.EP_LEN).astype(np.int64)
        self._offsets = self._arrays.pop(keys.EP_OFFSET).astype(np.int64)
        self._images = {k: tuple(v) for k, v in self.meta.get("images", {}).items()}
        if keys_to_load is not None:
            self.check_keys(keys_to_load)

    @property
    def column_names(self) -> list[str]:
        return sorted([*self._arrays, *self._images])

    def _read(self, col: str, start: int, stop: int) -> np.ndarray:
        if col in self._arrays:
            return self._arrays[col][start:stop]
        return self._read_images(col, start, stop)

    def _read_images(self, col: str, start: int, stop: int) -> np.ndarray:
        raise NotImplementedError("_read_images(col, start, stop) -> (stop - start, H, W, C) uint8")


class FolderDataset(_DirectoryDataset):
    """Windows of a folder dataset (see the module docstring); arguments as :class:`HDF5Dataset`."""

    kind = "folder"

    def _read_images(self, col: str, start: int, stop: int) -> np.ndarray:
        from PIL import Image

        h, w, c = self._images[col]
        out = np.empty((max(stop - start, 0), h, w, c), np.uint8)
        for i, row in enumerate(range(start, stop)):
            with Image.open(self.path / col / f"{row:09d}.jpg") as img:
                arr = np.asarray(img.convert("L" if c == 1 else "RGB"))
            out[i] = arr.reshape(h, w, c)
        return out


ImageDataset = FolderDataset


def split_columns(dataset: Dataset) -> tuple[dict[str, np.ndarray], dict[str, np.ndarray]]:
    """``(numeric, images)`` columns of every committed row of ``dataset`` (plus ep_len/ep_offset)."""
    numeric: dict[str, np.ndarray] = {}
    images: dict[str, np.ndarray] = {}
    for col in dataset.column_names:
        data = dataset.get_col_data(col)
        (images if image_like(data) else numeric)[col] = data
    lengths = np.asarray(dataset.lengths, np.int32)
    numeric[keys.EP_LEN] = lengths
    numeric[keys.EP_OFFSET] = np.concatenate([[0], np.cumsum(lengths, dtype=np.int64)[:-1]]).astype(np.int64)
    return numeric, images


def write_meta(path: Path, kind: str, numeric: dict[str, np.ndarray], images: dict[str, np.ndarray], **extra: Any) -> None:
    path.mkdir(parents=True, exist_ok=True)
    np.savez(path / COLUMNS, **numeric)
    meta = {"format": kind, "images": {k: list(v.shape[1:]) for k, v in images.items()}, **extra}
    (path / META).write_text(json.dumps(meta, indent=1))


def write_folder_dataset(dataset: Dataset, path: str | os.PathLike, quality: int = 95) -> Path:
    """Convert ``dataset`` (e.g. an :class:`HDF5Dataset`) to a folder dataset at ``path``."""
    from PIL import Image

    path = Path(path)
    numeric, images = split_columns(dataset)
    for col, data in images.items():
        (path / col).mkdir(parents=True, exist_ok=True)
        for row, frame in enumerate(data):
            img = Image.fromarray(frame[..., 0] if frame.shape[-1] == 1 else frame[..., :3])
            img.save(path / col / f"{row:09d}.jpg", quality=quality)
    write_meta(path, "folder", numeric, images)
    return path

"""``FolderDataset`` / ``ImageDataset``: numeric columns in ``.npz`` files, one JPEG per step.

The folder layouts (the released one, written here, and our earlier ``meta.json`` one, read
only) are drawn in :mod:`._layout`. Media columns are the sub-folders (``folder_keys`` /
``image_keys``; by default every sub-folder holding ``ep_*`` images). JPEG is lossy: images
read back differ slightly from the recorded ones.
"""

from __future__ import annotations

import os
import shutil
from collections.abc import Callable, Iterable, Iterator, Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import ConfigError, DatasetFormatError
from ._layout import EP_LEN_FILE, EP_OFFSET_FILE, META, Layout, MetaLayout, ReleasedLayout, open_layout
from .dataset import Dataset
from .format import per_step_columns, validate_write_mode
from .utils import resolve_dataset_dir


def is_media(arr: np.ndarray) -> bool:
    """Rows ``(L, H, W, C)`` uint8 with C in 1, 3: stored as image files / videos, not in a ``.npz``."""
    return arr.dtype == np.uint8 and arr.ndim == 4 and arr.shape[-1] in (1, 3)


def _load_image(path: Path) -> np.ndarray:
    from PIL import Image

    if not path.is_file():
        raise FileNotFoundError(f"FolderDataset requires the image {str(path)!r}, which does not exist")
    with Image.open(path) as img:
        if img.mode not in ("L", "RGB", "RGBA"):
            img = img.convert("RGB")
        arr = np.asarray(img)
    return arr[..., None] if arr.ndim == 2 else arr


class FolderDataset(Dataset):
    """Windows of a dataset folder (see :mod:`._layout`); arguments as 0.0.3.

    Args:
        name: folder name in ``cache_dir`` (default :func:`get_cache_dir`, or its ``datasets/``
            sub-folder) or a path to the folder.
        frameskip, num_steps, transform, keys_to_load: as :class:`HDF5Dataset`.
        folder_keys: media columns (sub-folders); default: every sub-folder holding media.
        cache_dir: folder holding ``name``.
        path: the dataset folder itself (0.1.1), instead of ``name``.
        keys_to_cache: accepted for symmetry with :class:`HDF5Dataset`: numeric columns are
            always in memory, images never are.
    """

    media_kind = "image"  # what a sub-folder holds: "image" files per step, or "video" files per episode
    meta_kind = "folder"  # the meta.json "format" this class reads (our earlier layout)

    def __init__(
        self,
        name: str | os.PathLike | None = None,
        frameskip: int = 1,
        num_steps: int = 1,
        transform: Callable[[dict], dict] | None = None,
        keys_to_load: Sequence[str] | None = None,
        folder_keys: Sequence[str] | None = None,
        cache_dir: str | os.PathLike | None = None,
        *,
        path: str | os.PathLike | None = None,
        keys_to_cache: Sequence[str] | None = None,
    ):
        owner = type(self).__name__
        super().__init__(frameskip=frameskip, num_steps=num_steps, transform=transform, keys_to_load=keys_to_load)
        if (name is None) == (path is None):
            raise ConfigError(f"{owner} requires a dataset name or path=, got {'neither' if name is None else 'both'}")
        self.path = Path(path).expanduser() if path is not None else resolve_dataset_dir(name, cache_dir)
        self.layout: Layout = open_layout(self.path, owner)
        if isinstance(self.layout, MetaLayout) and self.layout.kind != self.meta_kind:
            raise DatasetFormatError(
                f"{owner} requires a {self.meta_kind!r} dataset, got format {self.layout.kind!r} in {self.path}"
            )
        self.lengths, self.offsets = self.layout.lengths, self.layout.offsets
        self.folder_keys = self._media_keys(folder_keys)
        self._arrays: dict[str, np.ndarray] = {}
        if keys_to_load is not None:
            self.check_keys(keys_to_load)
        self.check_keys(list(keys_to_cache or []))
        for col in self.keys_to_load:
            if col not in self.folder_keys:
                self._array(col)
        self.check_span()

    def _holds_media(self, col: str, kind: str) -> bool:
        pattern = "ep_*.mp4" if kind == "video" else "ep_*_step_*"
        return next((self.path / col).glob(pattern), None) is not None

    def _media_keys(self, given: Sequence[str] | None) -> list[str]:
        owner = type(self).__name__
        if given is None:
            if isinstance(self.layout, MetaLayout):
                return list(self.layout.media)
            found = [col for col in self.layout.media if self._holds_media(col, self.media_kind)]
            other = "image" if self.media_kind == "video" else "video"
            wrong = [col for col in self.layout.media if col not in found and self._holds_media(col, other)]
            if wrong:
                reader = "FolderDataset" if other == "image" else "VideoDataset"
                raise DatasetFormatError(
                    f"{owner} requires {self.media_kind} folders, got {other} files in {wrong} of {self.path}: "
                    f"open it with {reader}"
                )
            return found
        if isinstance(given, (str, bytes)):
            raise ConfigError(f"{owner} requires a list of media keys, got the string {given!r}; write [{given!r}]")
        for col in given:
            if col not in self.layout.media:
                raise ConfigError(
                    f"{owner} media key {col!r} not found: {str(self.path / str(col))!r} does not exist; "
                    f"sub-folders: {self.layout.media}"
                )
        return list(given)

    @property
    def stored_columns(self) -> list[str]:
        return sorted({*self.layout.numeric, *self.folder_keys})

    def _array(self, col: str) -> np.ndarray:
        arr = self._arrays.get(col)
        if arr is None:
            arr = self._arrays[col] = self.layout.load(col)
        return arr

    # -- rows ---------------------------------------------------------------------------------
    def _read(self, col: str, start: int, stop: int) -> np.ndarray:
        return self._read_strided(col, start, stop, 1)

    def _read_strided(self, col: str, start: int, stop: int, step: int) -> np.ndarray:
        if col not in self.folder_keys:
            return self._array(col)[start:stop:step]
        rows = np.arange(start, stop, step)
        if not rows.size:
            return np.zeros((0, *self.frame_shape(col)), np.uint8)
        eps = np.searchsorted(self.offsets, rows, side="right") - 1
        parts = []
        for ep in np.unique(eps):
            steps = rows[eps == ep] - int(self.offsets[ep])
            parts.append(self._frames(col, int(ep), steps))
        return parts[0] if len(parts) == 1 else np.concatenate(parts)

    def _frames(self, col: str, ep: int, steps: np.ndarray) -> np.ndarray:
        """Frames ``(len(steps), H, W, C)`` of episode ``ep`` of media column ``col``."""
        first = int(self.offsets[ep])
        return np.stack([_load_image(self.layout.image_file(col, ep, int(s), first + int(s))) for s in steps])

    def frame_shape(self, col: str) -> tuple[int, int, int]:
        """``(H, W, C)`` of the frames of media column ``col``."""
        shape = self.layout.shapes.get(col)
        if shape is None:
            if not self.num_rows:
                return (0, 0, 3)
            ep = int(np.argmax(np.asarray(self.lengths) > 0))
            shape = self.layout.shapes[col] = tuple(self._frames(col, ep, np.array([0])).shape[1:])
        return tuple(shape)

    def row_shape(self, col: str) -> tuple[int, ...]:
        self.check_keys([col])
        return self.frame_shape(col) if col in self.folder_keys else tuple(self._array(col).shape[1:])


class ImageDataset(FolderDataset):
    """A :class:`FolderDataset` whose media columns are ``image_keys`` (default: every sub-folder
    holding images, which covers 0.0.3's default ``["pixels"]``)."""

    def __init__(self, name: str | os.PathLike | None = None, image_keys: Sequence[str] | None = None, **kwargs: Any):
        super().__init__(name, folder_keys=image_keys, **kwargs)


# -- writing -----------------------------------------------------------------------------------
def _save_npz(path: Path, arr: np.ndarray) -> None:
    """``np.savez(path, arr)`` written aside and renamed into place."""
    tmp = path.with_name(f".{path.name}.tmp")
    with open(tmp, "wb") as fh:
        np.savez(fh, arr)
    os.replace(tmp, path)


class FolderWriter:
    """Append episodes to a dataset folder in the released layout (:mod:`._layout`).

    ``mode``: ``"append"`` (default: extend a dataset already there), ``"overwrite"`` (remove
    it first) or ``"error"`` (FileExistsError if there is one). Each episode maps a column to
    ``(L, ...)`` rows; uint8 ``(L, H, W, C)`` columns (C in 1, 3) become media files, the
    others ``.npz`` columns, written by :meth:`close` (the context manager calls it).
    """

    def __init__(self, path: str | os.PathLike, *, mode: str = "append", quality: int = 95):
        owner = type(self).__name__
        validate_write_mode(mode, owner)
        if not 1 <= int(quality) <= 100:
            raise ConfigError(f"{owner} requires 1 <= quality <= 100, got {quality!r}")
        self.path, self.mode, self.quality = Path(path), mode, int(quality)
        if (self.path / META).is_file():
            raise DatasetFormatError(
                f"{owner} requires a folder in the released layout, got {self.path}, "
                f"which holds our earlier {META} layout"
            )
        self._lengths: list[int] = []
        self._numeric: dict[str, list[np.ndarray]] = {}
        self._schema: dict[str, tuple[bool, tuple[int, ...], np.dtype]] = {}
        self._closed = False
        if (self.path / EP_LEN_FILE).is_file():
            if mode == "error":
                raise FileExistsError(
                    f"{owner} requires a new folder with mode='error', got {str(self.path)!r}, "
                    "which already holds a dataset; pass mode='append' or 'overwrite'"
                )
            if mode == "overwrite":
                self._clear()
            else:
                self._resume()
        self.path.mkdir(parents=True, exist_ok=True)

    @property
    def num_episodes(self) -> int:
        return len(self._lengths)

    def _clear(self) -> None:
        layout = ReleasedLayout(self.path)
        for col in layout.numeric + ["ep_len", "ep_offset"]:
            (self.path / f"{col}.npz").unlink(missing_ok=True)
        for col in layout.media:
            if next((self.path / col).glob("ep_*"), None) is not None:
                shutil.rmtree(self.path / col)

    def _resume(self) -> None:
        layout = ReleasedLayout(self.path)
        self._lengths = [int(n) for n in layout.lengths]
        for col in layout.numeric:
            arr = layout.load(col)
            self._numeric[col] = [arr]
            self._schema[col] = (False, arr.shape[1:], arr.dtype)
        for col in layout.media:
            self._schema[col] = (True, (), np.dtype(np.uint8))  # frame shape checked by the files themselves

    def _check(self, episode: Mapping[str, Any]) -> tuple[int, dict[str, np.ndarray]]:
        owner = type(self).__name__
        cols = {str(k): np.asarray(v) for k, v in episode.items()}
        sizes = {k: len(v) if v.ndim else 0 for k, v in cols.items()}
        if not cols or len(set(sizes.values())) != 1 or 0 in sizes.values():
            raise ConfigError(
                f"{owner} requires an episode of columns with the same number of rows (at least 1), got {sizes}"
            )
        for k, v in cols.items():
            if v.dtype.kind in "OUSV":
                raise ConfigError(f"{owner} requires numeric or bool columns, got {k!r} of dtype {v.dtype}")
        if not self._schema:
            self._schema = {k: (is_media(v), v.shape[1:], v.dtype) for k, v in cols.items()}
        elif set(cols) != set(self._schema):
            raise DatasetFormatError(
                f"{owner} requires the columns of the dataset {sorted(self._schema)}, got {sorted(cols)}"
            )
        for k, v in cols.items():
            media, shape, dtype = self._schema[k]
            known = shape if not media or shape else v.shape[1:]  # a resumed media column: any frame size
            if media != is_media(v) or v.shape[1:] != known or v.dtype != dtype:
                raise DatasetFormatError(
                    f"{owner} requires column {k!r} rows of shape {shape} and dtype {dtype}, "
                    f"got {v.shape[1:]} {v.dtype}"
                )
        return next(iter(sizes.values())), cols

    def write_episode(self, episode: Mapping[str, Any]) -> None:
        """Write one episode: media files now, numeric rows at :meth:`close`."""
        if self._closed:
            raise ConfigError(f"{type(self).__name__} requires an open writer, got one already closed")
        length, cols = self._check(per_step_columns(episode, type(self).__name__))
        ep = len(self._lengths)
        for col, arr in cols.items():
            if is_media(arr):
                (self.path / col).mkdir(exist_ok=True)
                self._write_media(col, ep, arr)
            else:
                self._numeric.setdefault(col, []).append(arr)
        self._lengths.append(length)

    def write_episodes(self, episodes: Iterable[Mapping[str, Any]], next_seed: int | None = None) -> None:
        """Write each episode (``next_seed`` is accepted for symmetry with :class:`HDF5Writer`)."""
        for episode in episodes:
            self.write_episode(episode)

    def _write_media(self, col: str, ep: int, frames: np.ndarray) -> None:
        from PIL import Image

        for step, frame in enumerate(frames):
            img = Image.fromarray(frame[..., 0] if frame.shape[-1] == 1 else frame)
            img.save(self.path / col / f"ep_{ep}_step_{step}.jpeg", quality=self.quality)

    def close(self) -> None:
        """Write the numeric columns, then ``ep_offset`` and ``ep_len`` (the commit)."""
        if self._closed:
            return
        self._closed = True
        if not self._lengths:
            return
        for col, parts in self._numeric.items():
            _save_npz(self.path / f"{col}.npz", np.concatenate(parts))
        lengths = np.asarray(self._lengths, np.int32)
        _save_npz(
            self.path / EP_OFFSET_FILE, np.concatenate([[0], np.cumsum(lengths, dtype=np.int64)[:-1]]).astype(np.int64)
        )
        _save_npz(self.path / EP_LEN_FILE, lengths)

    def __enter__(self) -> FolderWriter:
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()


def episodes_of(dataset: Dataset) -> Iterator[dict[str, np.ndarray]]:
    """Every episode of ``dataset`` (one of our datasets) as raw rows ``{col: (L, ...)}``."""
    for offset, length in zip(dataset.offsets, dataset.lengths, strict=False):
        start, stop = int(offset), int(offset) + int(length)
        yield {col: dataset._read(col, start, stop) for col in dataset.stored_columns}


def write_folder_dataset(dataset: Dataset, path: str | os.PathLike, quality: int = 95, mode: str = "error") -> Path:
    """Convert ``dataset`` (e.g. an :class:`HDF5Dataset`) to a folder dataset at ``path``."""
    with FolderWriter(path, mode=mode, quality=quality) as writer:
        writer.write_episodes(episodes_of(dataset))
    return Path(path)

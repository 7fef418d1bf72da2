"""Crash-safe, append-only writer of the released (0.0.3) HDF5 dataset layout.

Layout (N = total rows over all episodes, E = episodes)::

    <column>    (N, ...)        one flat dataset per info column, episodes concatenated
    pixels      (N, H, W, 3)    uint8 images (gzip, chunked along rows)
    action      (N, A)          row t holds the action taken at step t (NaN on an episode's last row)
    ep_len      (E,)  int32     rows of each episode
    ep_offset   (E,)  int64     first row of each episode
    attrs       next_seed       seed of the next episode to record (resuming continues from it)

Crash safety: rows are appended (resizable chunked datasets) and flushed *before* ``ep_len``
/ ``ep_offset`` grow, so those two columns are the commit record; readers trust only them
and ignore rows past the last committed episode. The file is written in SWMR mode
(``libver='latest'``) so HDF5 orders its metadata writes and SWMR readers may open it
while it is written; after every commit the superblock is sealed (see ``_superblock``) so
a plain ``h5py.File(path)`` also opens it, including after a ``kill -9`` between two
commits. A kill *during* a commit leaves every earlier episode intact; such a file opens
with ``h5py.File(path, swmr=True)`` and :func:`~._superblock.repair` (run by this writer
and by :class:`~.hdf5.HDF5Dataset`) makes it plain-openable again.
"""

from __future__ import annotations

import logging
import os
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from .. import keys
from ..errors import DatasetFormatError
from . import _superblock

logger = logging.getLogger(__name__)

NEXT_SEED_ATTR = "next_seed"
IMAGE_CHUNK_BYTES = 256 * 1024
NUMERIC_CHUNK_BYTES = 64 * 1024
GZIP_LEVEL = 4
INDEX_COLUMNS = (keys.EP_LEN, keys.EP_OFFSET)


def is_image_column(shape: tuple[int, ...], dtype: np.dtype) -> bool:
    """Per-row ``shape`` (H, W, C) uint8 with C in 1, 3, 4."""
    return np.dtype(dtype) == np.uint8 and len(shape) == 3 and shape[-1] in (1, 3, 4)


def is_recordable(value: Any) -> bool:
    """Numeric or bool arrays are written; strings and objects are skipped."""
    dtype = np.asarray(value).dtype
    return dtype == np.bool_ or np.issubdtype(dtype, np.number)


def _chunk_rows(row_shape: tuple[int, ...], dtype: np.dtype, image: bool) -> int:
    row_bytes = max(int(np.prod(row_shape, dtype=np.int64)) * np.dtype(dtype).itemsize, 1)
    target = IMAGE_CHUNK_BYTES if image else NUMERIC_CHUNK_BYTES
    rows = max(1, target // row_bytes)
    rows = 1 << (rows.bit_length() - 1)  # power of two
    return min(rows, 64) if image else min(max(rows, 256), 65536)


class HDF5Writer:
    """Append whole episodes to ``path`` (created on the first episode, resumed if it exists).

    Use as a context manager or call :meth:`close`. ``write_episodes`` takes a list of
    episodes, each a mapping column -> array ``(L, ...)`` with the same columns, per-row
    shapes and dtypes as the episodes already in the file.
    """

    def __init__(self, path: str | os.PathLike):
        import h5py

        self.path = Path(path)
        self._h5py = h5py
        self._file = None
        self._schema: dict[str, tuple[tuple[int, ...], np.dtype]] = {}
        self.num_rows = 0
        self.num_episodes = 0
        self.next_seed: int | None = None
        if self.path.exists():
            self._resume()

    # -- opening ------------------------------------------------------------------------------
    def _resume(self) -> None:
        if _superblock.repair(self.path):
            logger.warning("%s was left open by a killed writer; cleared its write flags", self.path)
        try:
            f = self._h5py.File(self.path, "a", libver="latest", locking=False)
        except OSError as exc:
            raise DatasetFormatError(f"HDF5Writer requires a readable HDF5 file, got {self.path}: {exc}") from exc
        missing = [k for k in INDEX_COLUMNS if k not in f]
        if missing:
            f.close()
            raise DatasetFormatError(f"HDF5Writer requires columns {missing} to append to {self.path}, got {sorted(f)}")
        lengths = f[keys.EP_LEN][:].astype(np.int64)
        self.num_episodes = len(lengths)
        self.num_rows = int(lengths.sum())
        for name, dset in f.items():
            if name in INDEX_COLUMNS or not isinstance(dset, self._h5py.Dataset):
                continue
            self._schema[name] = (tuple(dset.shape[1:]), dset.dtype)
            if dset.shape[0] != self.num_rows:  # rows of an uncommitted episode: drop them
                dset.resize(self.num_rows, axis=0)
        if len(f[keys.EP_OFFSET]) != self.num_episodes:
            f[keys.EP_OFFSET].resize(self.num_episodes, axis=0)
        seed = f.attrs.get(NEXT_SEED_ATTR)
        self.next_seed = None if seed is None or int(seed) < 0 else int(seed)
        if NEXT_SEED_ATTR not in f.attrs:
            f.attrs[NEXT_SEED_ATTR] = np.int64(-1)
        self._file = f
        self._start_swmr()

    def _create(self, episode: Mapping[str, np.ndarray]) -> None:
        self.path.parent.mkdir(parents=True, exist_ok=True)
        f = self._h5py.File(self.path, "w", libver="latest", locking=False)
        try:
            for name, value in episode.items():
                arr = np.asarray(value)
                row_shape, dtype = tuple(arr.shape[1:]), arr.dtype
                image = is_image_column(row_shape, dtype)
                f.create_dataset(
                    name,
                    shape=(0, *row_shape),
                    maxshape=(None, *row_shape),
                    dtype=dtype,
                    chunks=(_chunk_rows(row_shape, dtype, image), *row_shape),
                    compression="gzip",
                    compression_opts=GZIP_LEVEL,
                    shuffle=not image and dtype.itemsize > 1,
                )
                self._schema[name] = (row_shape, dtype)
            f.create_dataset(keys.EP_LEN, shape=(0,), maxshape=(None,), dtype=np.int32, chunks=(4096,))
            f.create_dataset(keys.EP_OFFSET, shape=(0,), maxshape=(None,), dtype=np.int64, chunks=(4096,))
            f.attrs[NEXT_SEED_ATTR] = np.int64(-1)
        except Exception:
            f.close()
            self.path.unlink(missing_ok=True)
            raise
        self._file = f
        self._start_swmr()

    def _start_swmr(self) -> None:
        self._file.swmr_mode = True
        self._file.flush()
        _superblock.seal(self.path)

    # -- writing ------------------------------------------------------------------------------
    def _check(self, episode: Mapping[str, np.ndarray]) -> int:
        names = set(episode)
        expected = set(self._schema)
        if names != expected:
            extra, missing = sorted(names - expected), sorted(expected - names)
            raise DatasetFormatError(
                f"HDF5Writer requires the columns of {self.path.name} in every episode, "
                f"got extra columns {extra} and missing columns {missing}"
            )
        length = None
        for name, value in episode.items():
            arr = np.asarray(value)
            row_shape, dtype = self._schema[name]
            if tuple(arr.shape[1:]) != row_shape:
                raise DatasetFormatError(
                    f"HDF5Writer requires column {name!r} rows of shape {row_shape}, got {tuple(arr.shape[1:])}"
                )
            if not np.can_cast(arr.dtype, dtype, casting="same_kind"):
                raise DatasetFormatError(f"HDF5Writer requires column {name!r} of dtype {dtype}, got {arr.dtype}")
            if length is None:
                length = len(arr)
            elif len(arr) != length:
                raise DatasetFormatError(
                    f"HDF5Writer requires every column of an episode to have the same length, "
                    f"got {len(arr)} rows in {name!r} and {length} in others"
                )
        if not length:
            raise DatasetFormatError("HDF5Writer requires episodes of at least one row, got an empty episode")
        return length

    def write_episodes(self, episodes: Sequence[Mapping[str, np.ndarray]], next_seed: int | None = None) -> None:
        """Append ``episodes`` and commit them (one flush); ``next_seed`` is stored for resuming."""
        if not episodes:
            return
        if self._file is None:
            self._create(episodes[0])
        lengths = [self._check(ep) for ep in episodes]
        total = int(sum(lengths))
        start = self.num_rows
        f = self._file
        for name in self._schema:
            try:
                data = np.concatenate([np.asarray(ep[name]) for ep in episodes])
                dset = f[name]
                dset.resize(start + total, axis=0)
                dset[start:] = data
                dset.flush()
            except (OSError, TypeError, ValueError) as exc:
                raise DatasetFormatError(
                    f"HDF5Writer could not write column {name!r} of {self.path} ({total} rows); "
                    f"the {self.num_episodes} episodes committed before are intact: {exc}"
                ) from exc
        offsets = start + np.concatenate([[0], np.cumsum(lengths)[:-1]])
        try:
            for name, values in ((keys.EP_OFFSET, offsets), (keys.EP_LEN, lengths)):  # ep_len last: the commit
                dset = f[name]
                dset.resize(self.num_episodes + len(lengths), axis=0)
                dset[self.num_episodes :] = values
                dset.flush()
            if next_seed is not None:
                f.attrs.modify(NEXT_SEED_ATTR, np.int64(next_seed))
                self.next_seed = int(next_seed)
            f.flush()
        except OSError as exc:
            raise DatasetFormatError(f"HDF5Writer could not commit episodes to {self.path}: {exc}") from exc
        _superblock.seal(self.path)
        self.num_rows += total
        self.num_episodes += len(lengths)

    def close(self) -> None:
        if self._file is not None:
            self._file.close()
            self._file = None

    def __enter__(self) -> HDF5Writer:
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()

    def __del__(self) -> None:  # pragma: no cover - best effort
        try:
            self.close()
        except Exception:  # noqa: BLE001
            pass

"""``HDF5Dataset``: windows of a recorded ``.h5`` file (layout in :mod:`.writer`).

Reads are contiguous row slices. Each column is read in blocks aligned to its HDF5 chunks
and the last few decoded blocks are kept (a small per-column LRU), so consecutive or nearby
windows cost a numpy slice instead of an HDF5 call and a decompression. The file is opened
lazily, once per process (DataLoader workers each open their own handle); a file that is
still being recorded can be read: only committed episodes (``ep_len`` / ``ep_offset``)
are visible.

Rows of a raw column that carry checksums (:mod:`._rowsum`) are checked the first time this
reader reads them, whatever the path (items, windows, whole columns, preloading); a damaged
row raises :class:`DatasetFormatError` naming the file, column and row. Compressed chunks
are checked by their filter (zlib's Adler-32), a failure raising the same error.
"""

from __future__ import annotations

import contextlib
import functools
import logging
import os
import re
import sys
import time
from collections import OrderedDict
from collections.abc import Callable, Collection, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from .. import keys
from ..errors import ConfigError, DatasetFormatError
from . import _redo, _rowsum, _superblock
from ._index import H5_READ_ERRORS, check_file, damaged, read_index
from .dataset import Dataset
from .utils import resolve_dataset_path
from .writer import is_image_column

logger = logging.getLogger(__name__)

BLOCK_BYTES = 1 << 20  # decoded bytes per cached block of a small-row column
CACHE_BYTES = 64 << 20  # decoded bytes kept per column and process
PRELOAD_BYTES = 256 << 20  # datasets whose loaded columns decode to at most this are read at construction


SWMR_READ_ATTEMPTS = 28  # HDF5 re-reads a metadata block whose checksum fails this often (~0.3 s of back-off)


@functools.cache
def _set_read_attempts():
    """``H5Pset_metadata_read_attempts`` of the HDF5 library h5py runs on, or None where it cannot be found.

    A SWMR reader re-reads metadata whose checksum fails, in case a writer was half-way through
    it; HDF5's default (100 attempts with a doubling back-off) turns a damaged file into a
    hang of hours. h5py does not wrap the setting, so it is called through ctypes.
    """
    import ctypes
    import ctypes.util
    import glob

    import h5py

    candidates = []
    if sys.platform.startswith("linux"):  # the library this process loaded for h5py
        with contextlib.suppress(OSError), open("/proc/self/maps") as fh:
            candidates += sorted({line.split()[-1] for line in fh if re.search(r"/libhdf5[-.][^/]*$", line.strip())})
    package = Path(h5py.__file__).parent
    candidates += glob.glob(str(package.parent / "h5py.libs" / "libhdf5-*")) + glob.glob(
        str(package / ".dylibs" / "libhdf5*")
    )
    candidates += [ctypes.util.find_library("hdf5")]
    for candidate in filter(None, candidates):
        try:
            fn = ctypes.CDLL(candidate).H5Pset_metadata_read_attempts
        except (OSError, AttributeError):
            continue
        fn.argtypes, fn.restype = [ctypes.c_int64, ctypes.c_uint], ctypes.c_int
        return fn
    logger.debug("H5Pset_metadata_read_attempts not found: damaged files may take long to be reported")
    return None


def _open_swmr(path: str | os.PathLike, locking: bool | None):
    """``h5py.File(path, 'r', libver='latest', swmr=True)`` that gives up on a bad checksum within a second."""
    import h5py
    from h5py._hl.files import make_fapl

    fapl = make_fapl(None, libver="latest", locking=locking)
    setter = _set_read_attempts()
    if setter is not None and setter(fapl.id, SWMR_READ_ATTEMPTS) < 0:  # pragma: no cover - another HDF5 build
        logger.debug("H5Pset_metadata_read_attempts refused h5py's property list")
    fid = h5py.h5f.open(os.fsencode(path), h5py.h5f.ACC_RDONLY | h5py.h5f.ACC_SWMR_READ, fapl=fapl)
    return h5py.File(fid)


TORN_RETRIES = 6  # reads of a chunk that fails its checksum, a few ms apart (see _retry_torn)


def _is_filter_failure(exc: BaseException) -> bool:
    """``exc`` is HDF5 refusing a chunk: a checksum that fails (Fletcher-32, zlib's Adler-32...)."""
    return isinstance(exc, OSError) and "filter returned failure" in str(exc)


def _retry_torn(read: Callable[[], Any]) -> Any:
    """``read()``, tried again while a chunk fails its checksum (up to :data:`TORN_RETRIES` times).

    A writer appending to a file whose raw chunks carry Fletcher-32 checksums (as an earlier version
    could write them) rewrites the partly filled chunk of each column whole, in place (see
    :mod:`._checksum`); a read that
    overlaps that write can see the first pages of one version and the checksum of the other. Read
    again once the write is over, it holds; a damaged chunk still fails, some 60 ms later.
    """
    for attempt in range(TORN_RETRIES + 1):
        try:
            return read()
        except OSError as exc:
            if attempt == TORN_RETRIES or not _is_filter_failure(exc):
                raise
            time.sleep(0.001 * 2**attempt)
    raise AssertionError("unreachable")  # pragma: no cover


@functools.cache
def _register_filters() -> bool:
    """Import ``hdf5plugin`` where it is installed: it registers the compression filters (Blosc,
    LZ4, Zstd...) that 0.0.3 recordings use, so their image columns open with no extra step."""
    from .._optional import is_available

    if not is_available("hdf5plugin"):
        logger.debug("hdf5plugin is not installed: Blosc-compressed columns cannot be read")
        return False
    import hdf5plugin  # noqa: F401

    return True


def open_h5(path: str | os.PathLike):
    """Open ``path`` read-only: as a SWMR reader first, plainly as a fallback.

    A SWMR reader can keep reading a file that a writer is still appending to (a plain reader
    of a live file may fail once the writer has grown it past its slack, see :mod:`.writer`);
    files in older layouts, or already open plainly in this process, fall back to plain opens;
    file systems without locks to opens without locking. A damaged file fails within a second
    or two (:data:`SWMR_READ_ATTEMPTS`) with :class:`DatasetFormatError`.
    A file left flagged by a killed writer of an older version is repaired first.
    """
    import h5py

    _register_filters()
    if _superblock.cut_in_superblock(path):  # nothing can read it: skip HDF5's read attempts
        raise damaged("HDF5Dataset", Path(path), "no complete superblock")
    if _superblock.needs_repair(path) or _redo.record_path(path).exists():
        try:
            _superblock.repair(path)
        except OSError as exc:  # read-only file: a SWMR read of a flagged file still works
            logger.warning(
                "%s was left by a killed writer and could not be repaired (%s); open it once with write access",
                path,
                exc,
            )
    # HDF5 shares a file opened twice in one process only with compatible flags: a later plain
    # h5py.File(path) joins a SWMR reader opened with default locking, not the other way round
    attempts = (
        lambda: _open_swmr(path, None),
        lambda: h5py.File(path, "r"),
        lambda: _open_swmr(path, False),  # file systems without locks, or a locking writer
        lambda: h5py.File(path, "r", locking=False),
    )
    for i, attempt in enumerate(attempts):
        try:
            return attempt()
        except OSError as exc:
            if i == len(attempts) - 1:
                if _superblock.truncation(path):
                    raise damaged("HDF5Dataset", Path(path), exc) from exc
                raise DatasetFormatError(
                    f"HDF5Dataset requires a readable HDF5 file, got {str(path)!r}: {exc}"
                ) from exc
    raise AssertionError("unreachable")  # pragma: no cover


class HDF5Dataset(Dataset):
    """Samples of ``num_steps`` frames spaced by ``frameskip`` from ``<cache_dir>/<name>.h5``.

    A *sharded* dataset (``<cache_dir>/<name>/shard_*.h5``, as ``swm collect --ray`` records)
    reads as one: the shards' episodes one after the other, in shard-name order, with the
    episode numbers (``ep_idx``, ``id``) counted across shards.

    Args:
        name: dataset name in ``cache_dir`` (default :func:`get_cache_dir`), a path to an ``.h5``
            file, or a folder of ``shard_*.h5`` files.
        path: the ``.h5`` file itself (0.1.1), instead of ``name``.
        frameskip: rows between two sampled frames; ``action`` groups the ``frameskip`` actions.
        num_steps: frames per sample (T).
        transform: callable applied to each item dict.
        keys_to_load: columns in items (default: every column).
        keys_to_cache: columns loaded into memory at construction (fast for small columns).
        cache_dir: directory holding ``<name>.h5``.
        preload: read every loaded column into memory at construction. The default (None) does
            it when they decode to at most ``PRELOAD_BYTES`` (256 MiB): batches are then gathered
            with one numpy indexing per column, and DataLoader workers forked afterwards share
            the decoded arrays instead of each decompressing the file again, epoch after epoch.
            Larger datasets are read on demand through a per-process cache of decoded blocks.

    Items: ``{col: tensor (T, ...)}``; images ``(T, C, H, W)`` uint8; ``action`` ``(T, frameskip * A)``.
    """

    def __init__(
        self,
        name: str | os.PathLike | None = None,
        frameskip: int = 1,
        num_steps: int = 1,
        transform: Callable[[dict], dict] | None = None,
        keys_to_load: Sequence[str] | None = None,
        keys_to_cache: Sequence[str] | None = None,
        cache_dir: str | os.PathLike | None = None,
        *,
        preload: bool | None = None,
        path: str | os.PathLike | None = None,
        dense_columns: Collection[str] | str | None = None,
    ):
        super().__init__(
            frameskip=frameskip,
            num_steps=num_steps,
            transform=transform,
            keys_to_load=keys_to_load,
            dense_columns=dense_columns,
        )
        if (name is None) == (path is None):
            raise ConfigError(
                f"HDF5Dataset requires a dataset name or path=, got {'neither' if name is None else 'both'}"
            )
        self.path = Path(path).expanduser() if path is not None else resolve_dataset_path(name, cache_dir)
        sharded = self.path.is_dir() and self.path.suffix != ".h5"  # a folder named x.h5 is a mistake, not shards
        self._shards = shard_files(self.path, "HDF5Dataset") if sharded else [self.path]
        if not sharded:
            check_file(self.path, "HDF5Dataset")
        self.name = self.path.stem
        self._file = None
        self._pid = None
        self._blocks: dict[str, OrderedDict] = {}
        self._verified: list[dict[str, _rowsum.Verified]] = []  # per shard: the columns with checksums
        try:
            _retry_torn(self._read_indexes)
        except H5_READ_ERRORS as exc:  # h5py: damaged metadata
            self.close()
            raise damaged("HDF5Dataset", self.path, exc) from exc
        except DatasetFormatError:
            self.close()
            raise
        if keys_to_load is not None:
            self.check_keys(keys_to_load)
        self.check_span()
        self._cache: dict[str, np.ndarray] = {}
        end = self._end
        to_cache = self.check_keys(list(keys_to_cache or []))
        if preload is None:
            decoded = sum(end * self._row_bytes(c) for c in self.keys_to_load)
            preload = decoded <= PRELOAD_BYTES
        if preload:
            to_cache += [c for c in self.keys_to_load if c not in to_cache]
        for col in to_cache:
            rows = self._rows(col, 0, end)
            # images are kept (N, C, H, W) so that items need no transposing copy; _read
            # hands out (N, H, W, C) views of them like every other reader
            self._cache[col] = np.ascontiguousarray(np.moveaxis(rows, -1, -3)) if col in self._images else rows

    def _read_indexes(self) -> None:
        """The episode index over every shard: offsets shifted by the rows of the shards before."""
        lengths, offsets, self._bases, self._episode_bases, self._verified = [], [], [], [], []
        base = 0
        for i, f in enumerate(self._handles()):
            sums: dict[str, Any] = {}
            ls, os_, columns = read_index(f, self._shards[i], checksums=sums)
            if i == 0:
                self._columns = columns
                self._describe_columns(f)
            elif sorted(columns) != sorted(self._columns) or any(
                tuple(f[k].shape[1:]) != self._shapes[k][0] for k in columns
            ):
                raise DatasetFormatError(
                    f"HDF5Dataset requires every shard to have the columns and shapes of {self._shards[0].name}, "
                    f"got {self._shards[i].name} with columns {sorted(columns)}"
                )
            self._verified.append(self._checksummed(self._shards[i], sums, int(os_[-1] + ls[-1]) if len(ls) else 0))
            self._bases.append(base)
            self._episode_bases.append(sum(len(x) for x in lengths))
            lengths.append(ls)
            offsets.append(os_ + base)
            base += int(os_[-1] + ls[-1]) if len(ls) else 0
        self._bases.append(base)
        self._lengths, self._offsets = np.concatenate(lengths), np.concatenate(offsets)

    def _checksummed(self, path: Path, sums: dict[str, Any], end: int) -> dict[str, _rowsum.Verified]:
        """What to check in a file (``path``): its columns with checksums (``sums``: their
        datasets, as :func:`read_index` found them), each up to the committed rows (``end``)
        that have one, by the HDF5 chunks of the first shard's column."""
        return {
            col: _rowsum.Verified(path, col, self._chunk_rows[col], min(end, dset.shape[0]))
            for col, dset in sums.items()
            if col in self._shapes and _rowsum.is_checksum_dataset(dset, *self._shapes[col])
        }

    def _describe_columns(self, f) -> None:
        dsets = {k: f[k] for k in self._columns}
        self._shapes = {k: (tuple(d.shape[1:]), d.dtype) for k, d in dsets.items()}
        self._chunk_rows = {k: d.chunks[0] if d.chunks else 1 for k, d in dsets.items()}
        self._images = {k for k, (shape, dtype) in self._shapes.items() if is_image_column(shape, dtype)}
        self._block_rows = {k: self._choose_block(d, k in self._images) for k, d in dsets.items()}
        self._max_blocks = {
            k: max(8, CACHE_BYTES // max(self._block_rows[k] * self._row_bytes(k), 1)) for k in self._columns
        }

    # -- file handle --------------------------------------------------------------------------
    def _handles(self) -> list:
        """One open file per shard (one for a plain dataset)."""
        pid = os.getpid()
        if self._file is None or self._pid != pid:  # first use in this process (e.g. a DataLoader worker)
            # a forked worker must not share the parent's HDF5 handle; the decoded blocks are
            # plain arrays and stay valid (copy-on-write), so a warm cache is kept
            self._file = [open_h5(p) for p in self._shards]
            self._pid = pid
        return self._file

    def _handle(self):
        """The open file of a plain (one-file) dataset; the first shard of a sharded one."""
        return self._handles()[0]

    @property
    def attrs(self) -> dict[str, Any]:
        """The file's string attributes (``env_id``: the env it was recorded from, when the recorder
        wrote it); of the first shard for a sharded dataset."""
        return {k: str(v) for k, v in self._handle().attrs.items() if isinstance(v, (str, bytes))}

    def __getstate__(self) -> dict[str, Any]:
        state = self.__dict__.copy()
        state["_file"] = None
        state["_pid"] = None
        state["_blocks"] = {}
        return state

    def close(self) -> None:
        if self._file is not None:
            for f in self._file:
                f.close()
            self._file = None

    @staticmethod
    def _choose_block(dset, image: bool = False) -> int:
        """Rows per cached block: one HDF5 chunk for images and other big rows, about 1 MiB
        otherwise. (A 64x64 frame is 12 KiB: a 1-MiB block of them decoded 85 frames for each
        window a random sample reads.)"""
        chunk = dset.chunks[0] if dset.chunks else 1
        row_bytes = max(int(np.prod(dset.shape[1:], dtype=np.int64)) * dset.dtype.itemsize, 1)
        if image or row_bytes * chunk >= BLOCK_BYTES // 16:
            return chunk
        return max(chunk, (BLOCK_BYTES // row_bytes) // chunk * chunk)

    # -- Dataset interface --------------------------------------------------------------------
    @property
    def h5_path(self) -> Path:
        """The ``.h5`` file (0.0.3's name of :attr:`path`)."""
        return self.path

    def row_shape(self, col: str) -> tuple[int, ...]:
        return self.column_shape(col)[0]

    def column_shape(self, col: str) -> tuple[tuple[int, ...], np.dtype]:
        """Per-row shape and dtype of ``col``."""
        self.check_keys([col])
        return self._shapes[col]

    def _row_bytes(self, col: str) -> int:
        """Decoded bytes of one row of ``col``."""
        shape, dtype = self._shapes[col]
        return int(np.prod(shape, dtype=np.int64)) * dtype.itemsize

    def _cached(self, col: str) -> np.ndarray | None:
        """The in-memory rows of ``col`` as ``(N, ...)`` (images as ``(N, H, W, C)`` views), or None."""
        cached = self._cache.get(col)
        if cached is not None and col in self._images:
            return np.moveaxis(cached, -3, -1)
        return cached

    def _read(self, col: str, start: int, stop: int) -> np.ndarray:
        cached = self._cached(col)
        if cached is not None:
            return cached[start:stop]
        size = self._block_rows[col]
        if stop <= start:
            return self._rows(col, start, stop)
        b0, b1 = start // size, (stop - 1) // size
        if b1 - b0 > 2:  # a long range: one direct read
            return self._rows(col, start, stop)
        parts = [self._block(col, b, size) for b in range(b0, b1 + 1)]
        rows = parts[0] if len(parts) == 1 else np.concatenate(parts)
        return rows[start - b0 * size : stop - b0 * size]

    def _read_strided(self, col: str, start: int, stop: int, step: int) -> np.ndarray:
        """Rows ``start:stop:step``; a column stored one row per chunk (images) reads only the
        rows kept (a window of 4 frames at frameskip 5 decodes 4 chunks, not 16)."""
        if step > 1 and self._block_rows[col] == 1 and self._cached(col) is None and stop - start > step:
            return np.concatenate([self._block(col, r, 1) for r in range(start, stop, step)])
        return self._read(col, start, stop)[::step]

    def _rows(self, col: str, start: int, stop: int) -> np.ndarray:
        """Rows ``start:stop`` of ``col`` from the file (the shards); a damaged file raises
        :class:`DatasetFormatError`."""
        try:
            return _retry_torn(lambda: self._read_rows(col, start, stop))
        except (OSError, RuntimeError) as exc:
            if any(
                t in str(exc).lower() for t in ("plugin", "not registered", "required filter")
            ):  # an unknown compression filter
                raise DatasetFormatError(
                    f"HDF5Dataset requires the compression filter of column {col!r} of {self.path}, got: {exc}; "
                    "install it with: pip install hdf5plugin"
                ) from exc
            if _is_filter_failure(exc):
                raise DatasetFormatError(
                    f"HDF5Dataset requires chunks whose checksums hold, got a damaged chunk in rows {start}:{stop} "
                    f"of column {col!r} of {self.path}: {exc}; restore the file from a copy (a recording killed "
                    "in the middle of a commit is repaired by resuming it: open an HDF5Writer on it)"
                ) from exc
            raise DatasetFormatError(
                f"HDF5Dataset could not read rows {start}:{stop} of column {col!r} of {self.path} (damaged?): {exc}"
            ) from exc

    def _read_rows(self, col: str, start: int, stop: int) -> np.ndarray:
        """Rows ``start:stop`` of ``col`` as h5py reads them (its errors unchanged), checked
        against their checksums (a mismatch raises :class:`DatasetFormatError`)."""
        files = self._handles()
        if len(files) == 1:
            return self._checked(0, col, start, stop)
        renumber = col in (keys.EP_IDX, keys.EPISODE_ID)  # episode numbers count across shards
        spans = zip(self._bases[:-1], self._bases[1:], self._episode_bases, strict=True)
        parts = [
            self._checked(i, col, max(start, lo) - lo, min(stop, hi) - lo) + (eb if renumber else 0)
            for i, (lo, hi, eb) in enumerate(spans)
            if max(start, lo) < min(stop, hi)
        ]
        if not parts:
            return files[0][col][0:0]
        return parts[0] if len(parts) == 1 else np.concatenate(parts)

    def _checked(self, shard: int, col: str, start: int, stop: int) -> np.ndarray:
        """Rows ``start:stop`` of ``col`` in shard ``shard`` (its own row numbers), checked."""
        f = self._handles()[shard]  # datasets are opened per read: one kept open breaks another reader's refresh()
        rows = f[col][start:stop]
        verified = self._verified[shard].get(col)
        if verified is not None:
            verified.check(lambda: f[_rowsum.companion(col)], rows, start)
        return rows

    @property
    def _end(self) -> int:
        """One past the last row of the last episode."""
        return int(self._offsets[-1] + self._lengths[-1]) if len(self._lengths) else 0

    def _block(self, col: str, b: int, size: int) -> np.ndarray:
        lru = self._blocks.setdefault(col, OrderedDict())
        block = lru.get(b)
        if block is None:
            block = self._rows(col, b * size, (b + 1) * size)
            lru[b] = block
            if len(lru) > self._max_blocks[col]:
                lru.popitem(last=False)
        else:
            lru.move_to_end(b)
        return block

    def _read_windows(self, col: str, starts: np.ndarray) -> np.ndarray:
        cached = self._cached(col)
        if cached is None:
            return super()._read_windows(col, starts)
        return cached[starts[:, None] + self._row_offsets(col)]  # one gather for the whole batch

    def get_col_data(self, col: str) -> np.ndarray:
        self.check_keys([col])
        if col in self._cache:
            return self._cached(col)[: self._end]
        return self._rows(col, 0, self._end)

    def __repr__(self) -> str:
        return f"HDF5Dataset({str(self.path)!r}, " + super().__repr__().split("(", 1)[1]


SHARD_PATTERN = "shard_*.h5"


def shard_files(folder: Path, owner: str) -> list[Path]:
    """The ``shard_*.h5`` files of a sharded dataset folder, in name order (FileNotFoundError when none)."""
    shards = sorted(p for p in folder.glob(SHARD_PATTERN) if p.is_file())
    if not shards:
        raise FileNotFoundError(
            f"{owner} requires an .h5 file or a folder of {SHARD_PATTERN} files, got {str(folder)!r}, "
            "a folder without shards"
        )
    return shards


def dataset_path(name: str | os.PathLike, cache_dir: str | os.PathLike | None = None) -> Path:
    """Path of HDF5 dataset ``name`` (see :class:`HDF5Dataset`)."""
    return resolve_dataset_path(name, cache_dir)

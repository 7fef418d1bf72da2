"""Crash-safe, append-only writer of the released (0.0.3) HDF5 dataset layout.

Layout (N = total rows over all episodes, E = episodes)::

    <column>    (N, ...)        one flat dataset per info column, episodes concatenated
    pixels      (N, H, W, 3)    uint8 images (gzip, one row per chunk; see column_storage)
    action      (N, A)          row t holds the action taken at step t (NaN on an episode's last row)
    checksum:<column>  (N,)     checksum of each row of each raw (uncompressed) column (see _rowsum)
    ep_len      (E,)  int32     rows of each episode
    ep_offset   (E,)  int64     first row of each episode
    attrs       next_seed       seed of the next episode to record (resuming continues from it)
                env_id          the env the episodes were recorded from (World.record_dataset)

Commit record: rows (and their checksums) are appended (resizable chunked datasets) and flushed *before*
``ep_len`` / ``ep_offset`` grow; readers trust only those two columns and ignore rows past
the last committed episode (a resuming writer writes over them). ``next_seed`` is stored
before the ``ep_len`` entries it follows, so a kill between the two skips seeds but never
makes a resumed recording repeat one.

Committed rows are immutable: no later write touches their bytes (see :func:`column_storage`),
so a kill can only lose the commit under way.

Crash safety. A ``kill -9`` (or power-preserving crash of the process) at any moment leaves
a file that plain ``h5py.File(path)`` opens, with default arguments, and in which every episode
whose :meth:`HDF5Writer.write_episodes` returned reads back exactly; the episodes of the call
under way are committed entirely or not at all. The one exception: a kill that cuts one of
HDF5's in-place metadata writes at a page boundary (see :mod:`._redo`) leaves the file for
:func:`~._superblock.repair` to complete from its redo record, which the next
:class:`~.hdf5.HDF5Dataset` or :class:`HDF5Writer` to open it does first. How:

* HDF5 writes in SWMR mode (``libver='latest'``), which orders its metadata writes so that
  nothing on disk points at data not yet written;
* it writes through :class:`~._superblock.SealedFile` (h5py's file-object driver), which puts
  each write straight into the page cache and keeps the superblock free of "open for write"
  flags and its end-of-file address equal to the file's size, so the file is valid between
  any two system calls. A killed writer leaves up to ``SLACK`` (1 MiB) of unused space at the
  end, which a resuming writer does not reclaim; :meth:`HDF5Writer.close` (or interpreter
  exit) trims it;
* a new file is written as ``.<name>.partial`` and renamed once valid, so ``path`` never
  holds a half-created file;
* a write over bytes already written that crosses a page boundary is first kept, with the
  bytes it replaces, in ``.<name>.redo`` (:mod:`._redo`): the kernel may cut it there when a
  kill arrives. Closing the writer removes the record.

Not covered: the operating system crashing or losing power (nothing is fsync'ed).

Readers may open the file while it is written and see the episodes committed when they
opened it: :class:`~.hdf5.HDF5Dataset` does, and so does h5py's SWMR reader
(``h5py.File(path, 'r', libver='latest', swmr=True)``). A plain ``h5py.File(path)`` assumes
the file does not change under it: opened in the middle of a commit it can read half-written
metadata (``incorrect metadata checksum``; HDF5 retries those reads only in SWMR mode), and
it fails with ``addr overflow`` once the writer has appended more than ``SLACK`` bytes since
it opened. Open it again, or use one of the two readers above.

Failures: an I/O error inside HDF5's writes (``ENOSPC``...) raises :class:`DatasetFormatError`
and a ``KeyboardInterrupt`` raised there propagates; in both cases nothing more is written, the
file is as a kill at that moment would leave it, and the writer is closed.
"""

from __future__ import annotations

import logging
import os
import weakref
import zlib
from collections.abc import Iterable, Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from .. import keys
from ..errors import ConfigError, DatasetFormatError
from . import _checksum, _redo, _rowsum, _superblock
from ._index import H5_READ_ERRORS, damaged, not_a_file, read_index
from ._lock import WriterLock
from .format import per_step_columns, validate_write_mode

logger = logging.getLogger(__name__)

NEXT_SEED_ATTR = "next_seed"
#: episodes per commit when :meth:`HDF5Writer.write_episodes` is given a generator
COMMIT_EPISODES = 32
#: file attribute naming the env a dataset was recorded from (``World.record_dataset`` writes it)
ENV_ID_ATTR = "env_id"
COMPRESS_ROW_BYTES = 1024  # rows this big are compressed (one per chunk); smaller ones are stored raw
NUMERIC_CHUNK_BYTES = 16 * 1024
GZIP_LEVEL = 4
INDEX_COLUMNS = (keys.EP_LEN, keys.EP_OFFSET)


def is_image_column(shape: tuple[int, ...], dtype: Any) -> bool:
    """The one image rule of the package: per-row ``shape`` (H, W, C) of uint8 (a numpy or torch
    dtype) with C in 1, 3, 4. :func:`.info.is_image`, :func:`.dataset.image_like` and
    :func:`stable_worldmodel.planning.io.is_image` apply it to an array, rows and a batch."""
    name = str(dtype).removeprefix("torch.") if type(dtype).__module__ == "torch" else np.dtype(dtype).name
    return name == "uint8" and len(shape) == 3 and shape[-1] in (1, 3, 4)


def is_recordable(value: Any) -> bool:
    """Numeric or bool arrays are written; strings and objects are skipped."""
    dtype = np.asarray(value).dtype
    return dtype == np.bool_ or np.issubdtype(dtype, np.number)


def column_storage(row_shape: tuple[int, ...], dtype: np.dtype) -> dict[str, Any]:
    """``create_dataset`` arguments of a column: no HDF5 chunk ever holds rows of two commits' making.

    An HDF5 chunk that is written twice is rewritten whole (a compressed one moves, and its old
    space can be handed to the next allocation before the index that points at it is on disk),
    so a kill at the wrong moment could damage rows committed long before. Hence:

    * rows of at least :data:`COMPRESS_ROW_BYTES` (images...) are compressed, one row per chunk:
      each chunk is written once, when its row is appended. The price is compression across
      frames: a 64x64 PushT recording takes about 2.3x the bytes of 16-row chunks (bench_data);
    * smaller rows are stored uncompressed in chunks of about :data:`NUMERIC_CHUNK_BYTES`, with
      no fill value and no chunk cache (see :meth:`HDF5Writer._open`), so HDF5 writes exactly
      the bytes of the appended rows into the chunk and never touches the rows before them.
      Hence no HDF5 filter on them (Fletcher-32 would make HDF5 rewrite the chunk whole, its
      committed rows included, at every append): their checksums are rows of their own
      (:mod:`._rowsum`), appended like any raw column's.
    """
    dtype = np.dtype(dtype)
    row_bytes = max(int(np.prod(row_shape, dtype=np.int64)) * dtype.itemsize, 1)
    if row_bytes >= COMPRESS_ROW_BYTES:
        return dict(
            chunks=(1, *row_shape),
            compression="gzip",
            compression_opts=GZIP_LEVEL,
            shuffle=not is_image_column(row_shape, dtype) and dtype.itemsize > 1,
        )
    rows = 1 << ((NUMERIC_CHUNK_BYTES // row_bytes).bit_length() - 1)  # a power of two
    return dict(chunks=(max(rows, 1), *row_shape), fillvalue=None, fill_time="never")


def _write_rows(dset, start: int, rows: np.ndarray) -> None:
    """Write ``rows`` (already of ``dset``'s dtype, or castable by HDF5) at ``start``, growing
    ``dset`` if needed, through h5py's low-level calls (a fraction of the Python cost of
    ``dset[start:end] = rows``, paid per column per commit). The caller flushes.

    A dataset is never shrunk: HDF5 would rewrite the chunk that holds its last committed rows.
    Rows past ``start`` left by a killed commit are written over instead (readers ignore them).
    """
    import h5py

    rows = np.ascontiguousarray(rows)
    end = start + len(rows)
    did = dset.id
    shape = did.shape
    if shape[0] < end:
        did.set_extent((end, *shape[1:]))
    space = did.get_space()
    space.select_hyperslab((start,) + (0,) * (len(shape) - 1), (len(rows), *shape[1:]))
    did.write(h5py.h5s.create_simple(rows.shape), space, rows)


def deflate_level(dset) -> int | None:
    """The gzip level of a column stored one row per chunk with deflate as its only filter (the
    images :func:`column_storage` makes), whose chunks :func:`_write_deflated` can write; else None."""
    import h5py

    if dset.chunks != (1, *dset.shape[1:]):
        return None
    plist = dset.id.get_create_plist()
    if plist.get_nfilters() != 1:
        return None
    code, _, opts, _ = plist.get_filter(0)
    return int(opts[0]) if code == h5py.h5z.FILTER_DEFLATE and opts else None


PARALLEL_DEFLATE_BYTES = 1 << 20  # rows of a commit worth compressing on two threads


class _Helper:
    """One worker thread of this process (made again in a forked child, which has no threads)."""

    pool = None
    pid = None

    @classmethod
    def submit(cls, fn, *args):
        if cls.pid != os.getpid():
            from concurrent.futures import ThreadPoolExecutor

            cls.pool, cls.pid = ThreadPoolExecutor(1, thread_name_prefix="swm-deflate"), os.getpid()
        return cls.pool.submit(fn, *args)


def _compress(rows: list, level: int) -> list[bytes]:
    return [zlib.compress(row, level) for row in rows]


def _deflate(rows: np.ndarray, level: int) -> list[bytes]:
    """One zlib stream per row (the format of HDF5's deflate filter); a row equal to the row
    before it (an episode's goal image) shares that row's bytes instead of being compressed again.
    A commit of at least :data:`PARALLEL_DEFLATE_BYTES` is compressed half here, half on a helper
    thread (zlib releases the GIL): the same bytes, in about half the time on two cores."""
    flat = rows.reshape(len(rows), -1)
    repeats = [i > 0 and np.array_equal(row, flat[i - 1]) for i, row in enumerate(flat)]
    todo = [row for row, repeat in zip(flat, repeats, strict=True) if not repeat]
    if len(todo) > 1 and len(todo) * flat.shape[1] * flat.itemsize >= PARALLEL_DEFLATE_BYTES:
        half = len(todo) // 2
        later = _Helper.submit(_compress, todo[half:], level)
        packed = _compress(todo[:half], level) + later.result()
    else:
        packed = _compress(todo, level)
    out: list[bytes] = []
    stream = iter(packed)
    for repeat in repeats:
        out.append(out[-1] if repeat else next(stream))
    return out


def _write_deflated(dset, start: int, rows: np.ndarray, level: int) -> None:
    """:func:`_write_rows` for a :func:`deflate_level` column: the rows are compressed here and
    their chunks handed to HDF5 as they are (``write_direct_chunk``), the bytes HDF5's own filter
    would store, without its per-chunk overhead (see :func:`_deflate` for repeated rows)."""
    rows = np.ascontiguousarray(rows)
    chunks = _deflate(rows, level)
    end = start + len(rows)
    did = dset.id
    shape = did.shape
    if shape[0] < end:
        did.set_extent((end, *shape[1:]))
    zeros = (0,) * (len(shape) - 1)
    for i, chunk in enumerate(chunks):
        did.write_direct_chunk((start + i, *zeros), chunk)


def _close(f, fileobj: _superblock.SealedFile) -> None:
    """HDF5 writes through ``fileobj`` while it closes, so the descriptor goes last."""
    if os.getpid() != fileobj.pid:  # a forked child exiting: the writer and its file are the parent's
        fileobj.detach()
    try:
        f.close()
    finally:
        fileobj.close()


class HDF5Writer:
    """Append whole episodes to ``path`` (created on the first episode, resumed if it exists).

    One writer per dataset: another writer of ``path`` (in any process) makes this one raise
    :class:`~stable_worldmodel.errors.DatasetBusyError` naming it, or wait for it with
    ``wait=True`` (or ``wait=seconds``). Use as a context manager or call :meth:`close`.
    ``write_episodes`` takes a list of
    episodes, each a mapping column -> array ``(L, ...)`` with the same columns, per-row
    shapes and dtypes as the episodes already in the file.

    ``mode`` (upstream's :data:`~.format.WRITE_MODES`): ``"append"`` (the default: resume the
    file), ``"overwrite"`` (remove it first) or ``"error"`` (``FileExistsError`` if it exists).

    ``checksum`` (default True): a new file stores a checksum per row of each raw column, which
    :class:`~.hdf5.HDF5Dataset` checks on read (see :mod:`._rowsum`). A file keeps what it was
    created with: one without checksums is appended to without, one with them gets them for
    every row appended, whatever ``checksum`` says.
    """

    def __init__(
        self,
        path: str | os.PathLike,
        wait: bool | float = False,
        *,
        checksum: bool = True,
        attrs: Mapping[str, str] | None = None,
        mode: str = "append",
    ):
        import h5py

        self.mode = validate_write_mode(mode, "HDF5Writer")
        if not isinstance(checksum, (bool, np.bool_)):
            raise ConfigError(f"HDF5Writer requires checksum to be True or False, got {checksum!r}")
        attrs = dict(attrs or {})
        bad = {k: v for k, v in attrs.items() if not (isinstance(k, str) and isinstance(v, str)) or k == NEXT_SEED_ATTR}
        if bad:
            raise ConfigError(
                f"HDF5Writer requires attrs to map names to strings (not {NEXT_SEED_ATTR!r}), got {bad!r}"
            )
        self.attrs = attrs  # file attributes (e.g. the env id), written when missing

        self.path = Path(path)
        self._h5py = h5py
        self._file = None
        self._io: _superblock.SealedFile | None = None
        self._closer: weakref.finalize | None = None
        self._closed = False
        self._schema: dict[str, tuple[tuple[int, ...], np.dtype]] = {}
        self.checksum = bool(checksum)
        self._summed: set[str] = set()  # columns whose rows get a checksum
        self._dsets: dict[str, Any] = {}  # the file's datasets by name, opened once SWMR writing started
        self._levels: dict[str, int | None] = {}  # gzip level of the columns written chunk by chunk (deflate_level)
        self.num_rows = 0
        self.num_episodes = 0
        self.next_seed: int | None = None
        what = not_a_file(self.path)
        if what is not None:
            raise DatasetFormatError(f"HDF5Writer requires an .h5 file path, got {str(self.path)!r}, which is {what}")
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self._lock = WriterLock(self.path, wait).acquire()
        self._unlock = weakref.finalize(self, self._lock.release)
        try:
            if self.path.exists() and mode == "error":
                raise FileExistsError(
                    f"HDF5Writer(mode='error') requires a new dataset, got {self.path}, which exists; "
                    "pass mode='append' to extend it or mode='overwrite' to replace it"
                )
            if self.path.exists() and mode == "overwrite":  # under the lock: no writer of it is running
                self.path.unlink()
                _redo.record_path(self.path).unlink(missing_ok=True)
            if self.path.exists():
                self._resume()
            else:  # a first recording killed before its file was valid left this: it holds nothing
                self.path.with_name(f".{self.path.name}.partial").unlink(missing_ok=True)
        except BaseException:
            self.close()
            raise

    @property
    def columns(self) -> list[str]:
        """Names of the columns every episode must have (empty before the first episode of a new file)."""
        return list(self._schema)

    # -- opening ------------------------------------------------------------------------------
    def _resume(self) -> None:
        if _redo.complete(self.path):  # this writer holds the lock: no other has the file open
            logger.warning("%s: completed the write a killed writer left cut in two", self.path)
        if _superblock.repair(self.path):
            logger.warning("%s was left open by a killed writer; cleared its write flags", self.path)
        try:
            f = self._open(_superblock.SealedFile(self.path), "r+")
        except OSError as exc:
            if _superblock.truncation(self.path):
                raise damaged("HDF5Writer", self.path, exc) from exc
            raise DatasetFormatError(f"HDF5Writer requires a readable HDF5 file, got {self.path}: {exc}") from exc
        try:
            episodes = f[keys.EP_LEN].shape[0] if isinstance(f.get(keys.EP_LEN), self._h5py.Dataset) else 0
            self._reseal(f, [n for n in INDEX_COLUMNS if isinstance(f.get(n), self._h5py.Dataset)], episodes)
            lengths, offsets, columns = read_index(f, self.path, "HDF5Writer")
            self._schema = {name: (tuple(f[name].shape[1:]), f[name].dtype) for name in columns}
            self.num_episodes = len(lengths)
            self.num_rows = (
                int(offsets[-1] + lengths[-1]) if len(lengths) else 0
            )  # later rows (a killed commit): written over
            self._reseal(f, columns, self.num_rows)
            self._summed = self._checksummed(f, columns)
        except (*H5_READ_ERRORS, DatasetFormatError) as exc:
            self.close()
            if isinstance(exc, DatasetFormatError):
                raise
            raise damaged("HDF5Writer", self.path, exc) from exc
        seed = f.attrs.get(NEXT_SEED_ATTR)
        self.next_seed = None if seed is None or int(seed) < 0 else int(seed)
        if NEXT_SEED_ATTR not in f.attrs:
            f.attrs[NEXT_SEED_ATTR] = np.int64(-1)
        for key, value in self.attrs.items():
            if key not in f.attrs:  # a file keeps what it was created with
                f.attrs[key] = value
        self._start_swmr()
        self._raise_io_error("resume")

    def _reseal(self, f, names: Sequence[str], end: int) -> None:
        """Fresh checksums on the chunks of ``names`` past row ``end`` that a killed commit tore
        (see :mod:`._checksum`)."""
        for name in names:
            fixed = _checksum.reseal(f[name], end)
            if fixed:
                logger.warning(
                    "%s: re-sealed %d chunk(s) of column %r from row %d, torn by a killed commit",
                    self.path,
                    len(fixed),
                    name,
                    fixed[0],
                )

    def _checksummed(self, f, columns: Sequence[str]) -> set[str]:
        """The columns of open file ``f`` whose checksums this writer keeps appending.

        A checksum dataset shorter than the committed rows means another program appended rows
        without checksums: rows past its end are read unchecked, and appending after a gap is
        impossible, so that column gets no more.
        """
        summed = set()
        for name in columns:
            sums = f.get(_rowsum.companion(name))
            if not _rowsum.is_checksum_dataset(sums, *self._schema[name]):
                continue
            if sums.shape[0] < self.num_rows:
                logger.warning(
                    "%s: rows %d:%d of column %r have no checksum (appended by another program); "
                    "the rows appended now get none either",
                    self.path,
                    sums.shape[0],
                    self.num_rows,
                    name,
                )
                continue
            summed.add(name)
        return summed

    def _create(self, episode: Mapping[str, np.ndarray]) -> None:
        partial = self.path.with_name(f".{self.path.name}.partial")  # renamed once it is a valid file
        f = self._open(_superblock.SealedFile(partial, create=True, name=self.path), "w")
        try:
            for name, value in episode.items():
                arr = np.asarray(value)
                row_shape, dtype = tuple(arr.shape[1:]), arr.dtype
                storage = column_storage(row_shape, dtype)
                f.create_dataset(name, shape=(0, *row_shape), maxshape=(None, *row_shape), dtype=dtype, **storage)
                self._schema[name] = (row_shape, dtype)
                if self.checksum and storage.get("compression") is None:  # compressed: zlib checks them
                    sums = _rowsum.checksum_dtype(row_shape, dtype)
                    storage = column_storage((), sums)
                    f.create_dataset(_rowsum.companion(name), shape=(0,), maxshape=(None,), dtype=sums, **storage)
                    self._summed.add(name)
            for name, dtype in ((keys.EP_LEN, np.int32), (keys.EP_OFFSET, np.int64)):
                f.create_dataset(name, shape=(0,), maxshape=(None,), dtype=dtype, **column_storage((), dtype))
            f.attrs[NEXT_SEED_ATTR] = np.int64(-1)
            for key, value in self.attrs.items():
                f.attrs[key] = value
            self._start_swmr()
            self._raise_io_error("create")
        except BaseException:
            self._release()
            self._schema, self._summed = {}, set()
            partial.unlink(missing_ok=True)
            raise
        _redo.record_path(self.path).unlink(missing_ok=True)  # a record of a file once at this path
        os.replace(partial, self.path)
        self._io.publish()

    def _open(self, fileobj: _superblock.SealedFile, mode: str):
        """Open HDF5 on ``fileobj``; closed (HDF5 first, then the descriptor) by :meth:`close` or at exit."""
        try:
            # no chunk cache: a partly filled raw chunk gets only the appended rows' bytes written
            f = self._h5py.File(fileobj, mode, libver="latest", rdcc_nbytes=0)
        except BaseException:
            fileobj.close()
            raise
        self._file, self._io = f, fileobj
        self._closer = weakref.finalize(self, _close, f, fileobj)
        return f

    def _raise_io_error(self, doing: str) -> None:
        """Raise the failure the file object kept during HDF5's last calls, if any; closes the writer.

        Nothing was written after it, so the file is as a kill at that moment would leave it.
        """
        exc = self._io.error if self._io is not None else None
        if exc is None:
            return
        self._io = None  # reported here, not again by close()
        self.close()
        if not isinstance(exc, Exception):  # KeyboardInterrupt, SystemExit
            raise exc
        raise DatasetFormatError(
            f"HDF5Writer could not {doing} {self.path}: {exc}; the {self.num_episodes} episodes committed before "
            f"are intact, open a new HDF5Writer to append after them"
        ) from exc

    def _start_swmr(self) -> None:
        self._file.swmr_mode = True
        self._file.flush()

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

    def write_episode(self, episode: Mapping[str, Any]) -> None:
        """Append one episode and commit it (upstream's ``Writer`` protocol); see :meth:`write_episodes`."""
        self.write_episodes([episode])

    def write_episodes(self, episodes: Iterable[Mapping[str, Any]], next_seed: int | None = None) -> None:
        """Append ``episodes`` and commit them (rows, then ``ep_offset``, then ``ep_len``, each
        flushed): a list is committed whole, another iterable (a generator) every
        :data:`COMMIT_EPISODES` episodes. ``next_seed`` is stored for resuming. An episode maps
        each column to its rows ``(L, ...)`` (an array, or a list of per-step values)."""
        if not isinstance(episodes, Sequence):
            batch: list = []
            for episode in episodes:
                batch.append(episode)
                if len(batch) == COMMIT_EPISODES:
                    self._commit(batch, None)
                    batch = []
            self._commit(batch, next_seed)
            return
        self._commit(episodes, next_seed)

    def _commit(self, episodes: Sequence[Mapping[str, Any]], next_seed: int | None) -> None:
        episodes = [per_step_columns(ep, "HDF5Writer") for ep in episodes]
        if self._closed:
            raise DatasetFormatError(
                f"HDF5Writer requires an open writer, got a closed one for {self.path}; open a new HDF5Writer to append"
            )
        if not episodes:
            return
        if self._file is None:
            self._create(episodes[0])
        lengths = [self._check(ep) for ep in episodes]
        total = int(sum(lengths))
        start = self.num_rows
        f = self._file
        dsets = self._dsets
        if not dsets:  # opened once, after SWMR writing started
            dsets.update((name, f[name]) for name in [*self._schema, keys.EP_LEN, keys.EP_OFFSET])
            dsets.update((_rowsum.companion(name), f[_rowsum.companion(name)]) for name in self._summed)
            self._levels = {name: deflate_level(dsets[name]) for name in self._schema}
        for name, (_, dtype) in self._schema.items():
            try:
                data = np.concatenate([np.asarray(ep[name]) for ep in episodes])
                level = self._levels[name]
                if level is not None and data.dtype == dtype:
                    _write_deflated(dsets[name], start, data, level)
                else:
                    _write_rows(dsets[name], start, data)
                if name in self._summed:  # the checksums are of the rows as stored (HDF5 casts, saturating)
                    stored = data if data.dtype == dtype else dsets[name][start : start + total]
                    _write_rows(dsets[_rowsum.companion(name)], start, _rowsum.row_checksums(stored, start))
            except (OSError, TypeError, ValueError) as exc:
                self._raise_io_error(f"write column {name!r} to")
                raise DatasetFormatError(
                    f"HDF5Writer could not write column {name!r} of {self.path} ({total} rows); "
                    f"the {self.num_episodes} episodes committed before are intact: {exc}"
                ) from exc
            self._raise_io_error(f"write column {name!r} to")
        offsets = start + np.concatenate([[0], np.cumsum(lengths)[:-1]])
        try:
            if next_seed is not None:  # on disk before the commit: a kill after it skips seeds, never repeats
                f.attrs.modify(NEXT_SEED_ATTR, np.int64(next_seed))
            f.flush()  # the rows, their checksums and next_seed, before ep_len grows
            if next_seed is not None:
                self.next_seed = int(next_seed)
            _write_rows(dsets[keys.EP_OFFSET], self.num_episodes, offsets)
            dsets[keys.EP_OFFSET].flush()  # before ep_len, whose new entries are the commit
            _write_rows(dsets[keys.EP_LEN], self.num_episodes, np.asarray(lengths))
            f.flush()
        except OSError as exc:
            self._raise_io_error("commit episodes to")
            raise DatasetFormatError(f"HDF5Writer could not commit episodes to {self.path}: {exc}") from exc
        self._raise_io_error("commit episodes to")
        self.num_rows += total
        self.num_episodes += len(lengths)

    def close(self) -> None:
        """Close the file (every committed episode was already flushed) and let other writers in; idempotent."""
        self._closed = True
        try:
            self._release()
        finally:
            self._unlock()

    def _release(self) -> None:
        io, closer = self._io, self._closer
        self._file = self._io = self._closer = None
        self._dsets = {}
        if closer is None:
            return
        try:
            closer()
        except Exception as exc:  # noqa: BLE001 - every commit is on disk already
            logger.warning("%s: closing failed (%s); the committed episodes are intact", self.path, exc)
        if io is not None and io.error is not None:
            if not isinstance(io.error, Exception):  # Ctrl-C while HDF5 closed the file
                raise io.error
            logger.warning("%s: closing failed (%s); the committed episodes are intact", self.path, io.error)

    def __enter__(self) -> HDF5Writer:
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()

"""Per-row checksums of the raw (uncompressed) columns of an HDF5 dataset.

Layout (next to the columns of :mod:`.writer`)::

    state             (N, 2) float64   a raw column (rows under COMPRESS_ROW_BYTES)
    checksum:state    (N,)   int64     checksum of row i of ``state``: row_checksums(state[i:i+1], i)
    reward            (N,)   float32   a 4-byte row ...
    checksum:reward   (N,)   int32     ... has a 4-byte checksum (1-byte rows a 1-byte one, 2-byte a 2-byte)
    pixels            (N, 64, 64, 3)   a compressed column: none (zlib's Adler-32 catches a flip)

The writer appends a column's checksums in the same commit as its rows, before ``ep_len`` /
``ep_offset`` grow, so they are append-only and covered by the commit protocol like any row.
The companion is a flat dataset at the top level (0.0.3 / 0.1.1 readers list every top-level
name as a column and read ``f[name][start:stop]``: a 1-D integer dataset reads as one more
column there, where a group would fail). Its name has no leading ``_`` (private info keys, never written)
and a ``:``, which no flattened info key has. Files without them (older files, or written with
``HDF5Writer(..., checksum=False)``) read and append as before; rows past a companion's end
(appended by another program) are read unchecked.

The hash, vectorized over a block of rows: a row's bytes (zero-padded to a multiple of 4) are
read as little-endian 32-bit words ``w_j``; its checksum is::

    sum_j M_j * w_j + (i + 1) * R    (mod 2**64, stored as int64; narrow rows keep fewer bytes)

with odd 64-bit constants ``M_j`` (splitmix64, fixed: part of the file format) and ``i`` the
row's index in the file. Why this one:

* any damage confined to one word changes the sum (``M_j`` is odd, so invertible mod 2**64, and
  a 32-bit word's change is non-zero and below 2**32 in size): every single flipped bit is caught;
* two flipped bits of one row are always caught too: in one word it is a one-word change; in
  words j, k, ``±2**a M_j ± 2**b M_k`` vanishes mod 2**64 only if ``a == b`` and
  ``M_j ≡ ∓M_k (mod 2**33)``, which no two of the constants are (checked by the tests). 64-bit
  words would be half as much arithmetic but blind to flips of the top bit of two words (two
  sign flips of a float64 row), since ``2**63 * M ≡ 2**63`` for every odd ``M``;
* rows of at most 4 bytes (one word) keep the low bytes of the sum, as many as the row has
  (rounded up to 1, 2 or 4): ``M_0 * w`` is then a bijection of the row, so any damage to the row
  alone is caught, and a one-byte flag costs one byte, not eight;
* the row term catches rows read from the wrong place (a chunk index pointing at another
  chunk) and zeroed pages (rows and checksums both zero);
* it is one integer matrix-vector product per block (numpy, several GB/s on one core), where
  a CRC per row would be a Python loop over rows. It is a checksum against damage, not a
  defence against someone forging rows.

The reader verifies a block of rows the first time it reads it and remembers it (per reader,
per column, at the granularity of the column's HDF5 chunks): see :class:`Verified`.
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import DatasetFormatError

PREFIX = "checksum:"
_STORED = {1: (np.uint8, np.int8), 2: (np.uint16, np.int16), 4: (np.uint32, np.int32), 8: (np.uint64, np.int64)}
_MASK = (1 << 64) - 1
_SEED = 0x53574D5F524F5753  # "SWM_ROWS": never change it, files store what it makes
ROW_MULTIPLIER = np.uint64(0x9FB21C651E98DF25)
NARROW_WORDS = 8  # rows of up to this many words are summed column by column


def companion(column: str) -> str:
    """Name of the dataset that holds the checksums of ``column``'s rows."""
    return PREFIX + column


def is_companion(name: str) -> bool:
    """``name`` is a checksum dataset, not a column."""
    return name.startswith(PREFIX)


def column_of(name: str) -> str:
    """The column whose checksums dataset ``name`` holds."""
    return name[len(PREFIX) :]


@functools.lru_cache(maxsize=64)
def multipliers(words: int) -> np.ndarray:
    """The odd constants ``M_0 .. M_{words-1}`` (splitmix64 of :data:`_SEED`, low bit set)."""
    out, x = [], _SEED
    for _ in range(words):
        x = (x + 0x9E3779B97F4A7C15) & _MASK
        z = ((x ^ (x >> 30)) * 0xBF58476D1CE4E5B9) & _MASK
        z = ((z ^ (z >> 27)) * 0x94D049BB133111EB) & _MASK
        out.append((z ^ (z >> 31)) | 1)
    return np.array(out, dtype=np.uint64)


@functools.lru_cache(maxsize=256)
def _checksum_dtype(row_shape: tuple[int, ...], dtype: np.dtype) -> np.dtype:
    row_bytes = int(np.prod(row_shape, dtype=np.int64)) * np.dtype(dtype).itemsize
    size = next(s for s in (1, 2, 4, 8) if s >= min(row_bytes, 8))
    return np.dtype(_STORED[size][1])


def checksum_dtype(row_shape: tuple[int, ...], dtype: np.dtype) -> np.dtype:
    """The dtype of the checksums of rows of ``row_shape`` and ``dtype``: signed (torch, which
    0.1.1's reader hands them to, has no uint64), 1, 2, 4 or 8 bytes (see the module docstring)."""
    return _checksum_dtype(tuple(row_shape), np.dtype(dtype))


def row_checksums(rows: np.ndarray, start: int) -> np.ndarray:
    """Checksums ``(n,)`` of ``rows`` ``(n, ...)`` (C order, as stored), the first being row ``start``,
    in :func:`checksum_dtype` (the low bytes of the 64-bit sum)."""
    n = len(rows)
    unsigned, signed = _STORED[checksum_dtype(rows.shape[1:], rows.dtype).itemsize]
    if n == 0:
        return np.zeros(0, signed)
    raw = np.ascontiguousarray(rows).reshape(n, -1).view(np.uint8)
    width = raw.shape[1]
    if width % 4:
        padded = np.zeros((n, width + (-width % 4)), np.uint8)
        padded[:, :width] = raw
        raw = padded
    sums = _word_sums(raw.view("<u4"))
    rows_term = np.arange(start + 1, start + n + 1, dtype=np.uint64)
    rows_term *= ROW_MULTIPLIER
    sums += rows_term
    return (sums if unsigned is np.uint64 else sums.astype(unsigned)).view(signed)


def _word_sums(words: np.ndarray) -> np.ndarray:
    """``words @ multipliers`` (uint64, mod 2**64) of ``words`` ``(n, m)`` uint32; a few
    column products beat numpy's integer matmul on narrow rows."""
    n, m = words.shape
    mult = multipliers(m)
    if m == 0:
        return np.zeros(n, np.uint64)
    if m > NARROW_WORDS:
        return np.matmul(words, mult)
    sums = np.multiply(words[:, 0], mult[0], dtype=np.uint64)
    term = np.empty(n, np.uint64) if m > 1 else None
    for j in range(1, m):
        np.multiply(words[:, j], mult[j], out=term, dtype=np.uint64)
        sums += term
    return sums


def mismatch(path: Path, column: str, rows: np.ndarray) -> DatasetFormatError:
    """The error for rows ``rows`` (indexes in file ``path``) of ``column`` that fail their checksums."""
    more = ""
    if len(rows) > 1:
        listed = ", ".join(str(int(r)) for r in rows[1:6]) + (", ..." if len(rows) > 6 else "")
        more = f" (nor do {len(rows) - 1} more: {listed})"
    return DatasetFormatError(
        f"HDF5Dataset requires rows that match their checksums: row {int(rows[0])} of column {column!r} in {path} "
        f"does not match its checksum{more}; the file was damaged after it was written: restore it from a copy "
        "or record it again"
    )


class Verified:
    """Which rows of one column of one file a reader has checked, by HDF5 chunk of that column.

    ``limit``: rows that have a checksum and belong to the reader's committed episodes (the
    rows past it are not checked). A read checks the rows it returns that lie in chunks not yet
    checked, and marks the chunks it covered whole, so each chunk is hashed once per reader
    (a read that covers a chunk in part checks that part again next time).
    """

    def __init__(self, path: Path, column: str, chunk_rows: int, limit: int):
        self.path, self.column = path, column
        self.chunk = max(int(chunk_rows), 1)
        self.limit = int(limit)
        self.done = np.zeros(-(-self.limit // self.chunk), bool)

    def check(self, sums: Callable[[], Any], rows: np.ndarray, start: int) -> None:
        """Compare ``rows`` (rows ``start:start + len(rows)`` of the column) with their checksums
        (``sums()``: the checksum dataset, opened only when something is left to check)."""
        stop = min(start + len(rows), self.limit)
        if stop <= start:
            return
        c = self.chunk
        first, last = start // c, (stop - 1) // c
        todo = np.flatnonzero(~self.done[first : last + 1])
        if not len(todo):
            return
        lo, hi = max(start, (first + int(todo[0])) * c), min(stop, (first + int(todo[-1]) + 1) * c)
        bad = np.flatnonzero(row_checksums(rows[lo - start : hi - start], lo) != sums()[lo:hi])
        if len(bad):
            raise mismatch(self.path, self.column, lo + bad)
        whole_to = last if stop == self.limit else stop // c - 1  # the chunk holding limit - 1 ends there
        whole_from = -(-start // c)
        if whole_to >= whole_from:
            self.done[whole_from : whole_to + 1] = True


def is_checksum_dataset(obj, row_shape: tuple[int, ...], dtype: np.dtype) -> bool:
    """``obj`` (what ``f.get(companion(name))`` returned) can hold the checksums of rows of
    ``row_shape`` and ``dtype``: a 1-D dataset of their :func:`checksum_dtype`."""
    import h5py

    return isinstance(obj, h5py.Dataset) and obj.ndim == 1 and obj.dtype == checksum_dtype(row_shape, dtype)

"""Complete an in-place write that a kill cut at a page boundary (a redo record beside the file).

A ``kill -9`` that arrives while the kernel copies a ``pwrite`` into the page cache stops the
copy at the next page boundary: the file keeps the new bytes of the first pages and the old
bytes of the rest. For data appended past the file's committed end that is harmless (nothing
points at it yet), but HDF5 also rewrites metadata in place (object headers, chunk-index
blocks of a few kB, each with a checksum at its end): cut in two, such a block fails its
checksum and the file no longer opens. A write that fits in one page is never cut.

So :class:`RedoLog` keeps, in ``.<name>.redo`` beside the file, the last in-place write that
spans a page boundary, written (one ``pwrite``, with its own checksum) *before* the file is
touched: the new bytes and the old ones. :func:`complete` puts the new bytes back when the
file holds a cut of that write (new up to a page boundary, old after it), and only then, so a
record never changes a file it does not belong to (a copy, a file made anew under the name).
Record layout (little endian)::

    MAGIC (8) | pos (8) | length (8) | CRC-32 of the rest (4) | new bytes | old bytes
"""

from __future__ import annotations

import os
import struct
import zlib
from pathlib import Path

from ._superblock import pwrite_all

MAGIC = b"SWMREDO1"
PAGE = 4096  # the kernel cuts a write at page boundaries (folios are whole pages, or more)
_HEAD = struct.Struct("<8sQQI")


def record_path(path: str | os.PathLike) -> Path:
    """The redo record of data file ``path``."""
    path = Path(path)
    return path.with_name(f".{path.name}.redo")


def spans_pages(pos: int, size: int) -> bool:
    """A write of ``size`` bytes at ``pos`` crosses a page boundary (a kill can cut it)."""
    return size > 0 and pos // PAGE != (pos + size - 1) // PAGE


def _cuts(pos: int, size: int) -> list[int]:
    """Offsets (within a write) at which a kill can leave it: its start, each page boundary, its end."""
    first = (pos // PAGE + 1) * PAGE - pos
    return [0, *range(first, size, PAGE), size]


def _parse(raw: bytes) -> tuple[int, bytes, bytes] | None:
    """``(pos, new, old)`` of a whole, valid record; None for a cleared or cut-off one."""
    if len(raw) < _HEAD.size:
        return None
    magic, pos, size, check = _HEAD.unpack_from(raw)
    end = _HEAD.size + 2 * size
    if magic != MAGIC or len(raw) < end or zlib.crc32(raw[8:24] + raw[_HEAD.size : end]) != check:
        return None
    return pos, raw[_HEAD.size : _HEAD.size + size], raw[_HEAD.size + size : end]


class RedoLog:
    """The redo record of the file open on descriptor ``fd`` (see the module doc).

    :meth:`before` is called with every write to that file that may land on bytes already
    written (``pos`` below the file's written end), before it is made.
    """

    def __init__(self, path: str | os.PathLike, fd: int):
        self.path = record_path(path)
        self._file_fd = fd
        self._fd: int | None = None
        self._region: tuple[int, int] | None = None  # the region the current valid record covers

    def before(self, view: memoryview, pos: int) -> None:
        end = pos + len(view)
        if spans_pages(pos, len(view)):
            self._log(view, pos)
        elif self._region is not None and pos < self._region[1] and end > self._region[0]:
            self._clear()  # replaying the record now would undo this write

    def _log(self, view: memoryview, pos: int) -> None:
        old = os.pread(self._file_fd, len(view), pos)
        old += bytes(len(view) - len(old))
        body = struct.pack("<QQ", pos, len(view)) + bytes(view) + old
        record = MAGIC + body[:16] + struct.pack("<I", zlib.crc32(body)) + body[16:]
        if self._fd is None:
            self._fd = os.open(self.path, os.O_RDWR | os.O_CREAT | os.O_CLOEXEC, 0o644)
        self._region = None
        pwrite_all(self._fd, record, 0)
        self._region = (pos, pos + len(view))

    def _clear(self) -> None:
        os.pwrite(self._fd, bytes(len(MAGIC)), 0)
        self._region = None

    def close(self, remove: bool) -> None:
        """Close the record; ``remove`` it too (the file is complete: HDF5 closed it)."""
        fd, self._fd = self._fd, None
        if fd is None:
            return
        try:
            if remove:
                self.path.unlink(missing_ok=True)
        finally:
            os.close(fd)


def complete(path: str | os.PathLike) -> bool:
    """Finish the write recorded beside ``path`` if the file holds a cut of it, and remove the
    record; True when bytes changed. The caller makes sure no writer has the file open."""
    record = record_path(path)
    try:
        raw = record.read_bytes()
    except FileNotFoundError:
        return False
    parsed = _parse(raw)
    changed = False
    if parsed is not None:
        pos, new, old = parsed
        with open(path, "r+b", buffering=0) as fh:
            now = os.pread(fh.fileno(), len(new), pos)
            cut = any(now == new[:c] + old[c:] for c in _cuts(pos, len(new))) if len(now) == len(new) else False
            if cut and now != new:
                pwrite_all(fh.fileno(), new, pos)
                changed = True
    record.unlink(missing_ok=True)
    return changed


def complete_unless_written(path: str | os.PathLike) -> bool:
    """:func:`complete` under ``path``'s writer lock; False without a record, or when a writer
    holds the file (its record describes a write it has under way)."""
    if not record_path(path).exists():
        return False
    from ..errors import DatasetBusyError
    from ._lock import WriterLock

    try:
        lock = WriterLock(path).acquire()
    except DatasetBusyError:
        return False
    try:
        return complete(path)
    finally:
        lock.release()

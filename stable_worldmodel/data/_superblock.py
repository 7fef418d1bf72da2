"""Keep an HDF5 file that is being written in SWMR mode openable by plain ``h5py``.

While a file is open for (SWMR) writing, HDF5 marks its superblock (version 3) with
"open for write" flags and keeps its end-of-allocation address (EOA) loosely up to date.
A reader that does not use SWMR refuses such a file (``file is already open for write``)
and, after the writer was killed, would keep refusing it (``h5clear`` clears the flags).

:class:`SealedFile` is the file the writer hands to HDF5 (h5py's file-object driver): every
write passes through it, and the superblock reaches the disk without the flags and with an
EOA equal to the file's size, so the file is a valid, closed-looking HDF5 file between any
two of its system calls (a write a kill cuts inside is kept in a redo record first, see
:mod:`._redo`). :func:`repair` completes such a write, and clears the flags of a file left by
a killed writer of an earlier version (which sealed the file after each commit instead). Superblock
version 2/3 layout (all little endian)::

    offset  size  field
    0       8     signature  \\x89HDF\\r\\n\\x1a\\n
    8       1     superblock version (2 or 3)
    9       1     size of offsets (O, 8)
    10      1     size of lengths
    11      1     file consistency flags  <- cleared
    12      O     base address
    12+O    O     superblock extension address
    12+2O   O     end-of-file address     <- the file size
    12+3O   O     root group object header address
    12+4O   4     Jenkins lookup3 checksum of the bytes before it
"""

from __future__ import annotations

import os
import struct

SIGNATURE = b"\x89HDF\r\n\x1a\n"
_M = 0xFFFFFFFF
SLACK = 1 << 20  # bytes the file is grown ahead of HDF5's writes (see SealedFile)


def _rot(x: int, k: int) -> int:
    return ((x << k) | (x >> (32 - k))) & _M


def lookup3(data: bytes, initval: int = 0) -> int:
    """Bob Jenkins' lookup3 ``hashlittle`` (the checksum HDF5 puts on its metadata)."""
    n = len(data)
    a = b = c = (0xDEADBEEF + n + initval) & _M
    i = 0
    while n > 12:
        a = (a + int.from_bytes(data[i : i + 4], "little")) & _M
        b = (b + int.from_bytes(data[i + 4 : i + 8], "little")) & _M
        c = (c + int.from_bytes(data[i + 8 : i + 12], "little")) & _M
        a = (a - c) & _M ^ _rot(c, 4)
        c = (c + b) & _M
        b = (b - a) & _M ^ _rot(a, 6)
        a = (a + c) & _M
        c = (c - b) & _M ^ _rot(b, 8)
        b = (b + a) & _M
        a = (a - c) & _M ^ _rot(c, 16)
        c = (c + b) & _M
        b = (b - a) & _M ^ _rot(a, 19)
        a = (a + c) & _M
        c = (c - b) & _M ^ _rot(b, 4)
        b = (b + a) & _M
        n -= 12
        i += 12
    if n == 0:
        return c
    tail = data[i : i + n] + bytes(12 - n)
    a = (a + int.from_bytes(tail[0:4], "little")) & _M
    b = (b + int.from_bytes(tail[4:8], "little")) & _M
    c = (c + int.from_bytes(tail[8:12], "little")) & _M
    c = (c ^ b) - _rot(b, 14) & _M
    a = (a ^ c) - _rot(c, 11) & _M
    b = (b ^ a) - _rot(a, 25) & _M
    c = (c ^ b) - _rot(b, 16) & _M
    a = (a ^ c) - _rot(c, 4) & _M
    b = (b ^ a) - _rot(a, 14) & _M
    c = (c ^ b) - _rot(b, 24) & _M
    return c


def _known(head: bytes) -> bool:
    """``head`` starts with a v2/v3 superblock whose checksum holds (a layout we can rewrite)."""
    if len(head) < 12 or head[:8] != SIGNATURE or head[8] not in (2, 3):
        return False
    end = 12 + 4 * head[9]
    return len(head) >= end + 4 and lookup3(bytes(head[:end])) == int.from_bytes(head[end : end + 4], "little")


def _stamp(head: bytes, eoa: int) -> bytes:
    """Superblock ``head`` with no write flags, end-of-file address ``eoa`` and its checksum."""
    size = head[9]
    end = 12 + 4 * size
    out = bytearray(head[:end])
    out[11] = 0
    out[12 + 2 * size : 12 + 3 * size] = eoa.to_bytes(size, "little")
    return bytes(out) + struct.pack("<I", lookup3(bytes(out)))


def _eoa(head: bytes) -> int:
    size = head[9]
    return int.from_bytes(head[12 + 2 * size : 12 + 3 * size], "little")


def needs_repair(path: str | os.PathLike) -> bool:
    """True when the superblock still carries "open for write" flags."""
    with open(path, "rb") as fh:
        head = fh.read(12)
    return len(head) == 12 and head[:8] == SIGNATURE and head[8] >= 2 and head[11] != 0  # a cut-off file has no flags


def _head_and_size(path: str | os.PathLike) -> tuple[bytes, int]:
    try:
        with open(path, "rb") as fh:
            return fh.read(64), os.fstat(fh.fileno()).st_size
    except OSError:
        return b"", 0


def _cut(head: bytes) -> bool:
    """``head`` (a whole file) starts with the signature and ends before its v2/v3 superblock does."""
    return head[:8] == SIGNATURE and (len(head) < 12 or (head[8] in (2, 3) and len(head) < 16 + 4 * head[9]))


def cut_in_superblock(path: str | os.PathLike) -> bool:
    """``path`` is an HDF5 file that ends inside its superblock: no HDF5 library can open it."""
    return _cut(_head_and_size(path)[0])


def truncation(path: str | os.PathLike) -> str | None:
    """How HDF5 file ``path`` is cut short ("4096 bytes of the 361544 its superblock declares"), or None
    when it is not (or is not an HDF5 file, or its superblock is not a v2/v3 one we can read)."""
    head, size = _head_and_size(path)
    if _cut(head):
        return f"{size} bytes, cut off inside its superblock"
    if _known(head) and size < _eoa(head):
        return f"{size} bytes of the {_eoa(head)} its superblock declares"
    return None


def seal(path: str | os.PathLike) -> bool:
    """Clear the write flags and raise the EOA to the file size; False for other superblocks."""
    with open(path, "r+b") as fh:
        head = fh.read(64)
        if not _known(head):
            return False  # not a superblock layout we know: leave it alone
        eoa = _eoa(head)
        file_size = os.fstat(fh.fileno()).st_size
        if file_size < eoa:  # HDF5 refuses files shorter than their EOA
            fh.truncate(eoa)
        fh.seek(0)
        fh.write(_stamp(head, max(eoa, file_size)))
        fh.flush()
    return True


def repair(path: str | os.PathLike) -> bool:
    """Make a file left by a killed writer openable by plain h5py; True if it changed it.

    Completes the in-place write a kill cut at a page boundary (see :mod:`._redo`; not while a
    writer has the file open: the record is then that writer's), and clears the write flags an
    older version left. Readers (:class:`~.hdf5.HDF5Dataset`) and writers do it on open.
    """
    from ._redo import complete_unless_written

    completed = complete_unless_written(path)
    return (needs_repair(path) and seal(path)) or completed


def pwrite_all(fd: int, data, pos: int) -> None:
    """Write all of ``data`` (bytes-like) at ``pos`` of descriptor ``fd``, however many ``pwrite`` calls it takes."""
    view = memoryview(data).cast("B")
    while view:
        done = os.pwrite(fd, view, pos)
        view, pos = view[done:], pos + done


def _redo_log(path: str | os.PathLike, fd: int):
    from ._redo import RedoLog

    return RedoLog(path, fd)


class SealedFile:
    """The file HDF5 writes through (h5py's file-object driver); its superblock stays sealed.

    Writes go straight to the descriptor (``pwrite``: unbuffered, in HDF5's order, which SWMR
    mode makes safe for readers). Two rules keep every state between two system calls a file
    that plain HDF5 opens, so a ``kill -9`` anywhere leaves one:

    * the superblock HDF5 writes reaches the disk without its write flags, with a fresh checksum;
    * its end-of-file address (EOA) is the file's size: a write past the end first grows the
      file (by :data:`SLACK` more) and then stamps the new size into the superblock, and HDF5's
      truncations only grow the file while it is open (:meth:`close` trims it). A reader checks
      the size against an EOA it reads a moment later, and trusts no address past that EOA;
      the slack keeps both true while the writer appends.

    A kill can also land *inside* a system call: the kernel stops copying a write at a page
    boundary. A write over bytes already written that spans pages (HDF5 rewrites metadata in
    place) is therefore recorded first (:class:`._redo.RedoLog`, once the file has its name:
    :meth:`publish`), and :func:`repair` completes it.

    h5py's driver does not recover from an exception raised here (later calls fail and the
    process may crash), so no method raises: the first failure (``ENOSPC``, ``KeyboardInterrupt``
    ...) is kept in :attr:`error` for the caller to raise, and every later change is dropped,
    which leaves the file as a kill at that moment would.
    """

    def __init__(self, path: str | os.PathLike, create: bool = False, name: str | os.PathLike | None = None):
        self.name = str(path if name is None else name)
        self.error: BaseException | None = None
        self.pid = os.getpid()
        self._live = True  # False once writes are dropped (a failure, or detach())
        self._fh = open(path, "w+b" if create else "r+b", buffering=0)  # noqa: SIM115 - closed by close()
        self._fd = self._fh.fileno()
        self._size = os.fstat(self._fd).st_size
        self._pos = 0
        self._head: bytearray | None = None  # the superblock as HDF5 last wrote it
        self._eoa = 0  # HDF5's end of allocation, as it last told us
        self._trim: int | None = None  # the size HDF5 last truncated to (applied by close)
        self._written = 0 if create else self._size  # bytes below this may be in use: writes there are in place
        self._redo = None if create else _redo_log(path, self._fd)  # a new file gets one once published
        head = os.pread(self._fd, 64, 0)
        if _known(head):
            self._head = bytearray(head[: 16 + 4 * head[9]])
            self._eoa = _eoa(head)

    def __repr__(self) -> str:
        return self.name  # h5py names the HDF5 file after it (File.filename, error messages)

    # -- what h5py's driver calls (never raising, see the class doc) -------------------------------
    def seek(self, pos: int, whence: int = 0) -> int:
        try:
            self._pos = pos if whence == 0 else (self._pos + pos if whence == 1 else self._size + pos)
        except BaseException as exc:  # noqa: BLE001
            self._fail(exc)
        return self._pos

    def tell(self) -> int:
        return self._pos

    def readinto(self, buf) -> int:
        try:
            n = os.preadv(self._fd, [buf], self._pos)
            head = self._head
            if head is not None and self._pos < len(head):  # HDF5 reads back what it wrote
                k = min(len(head) - self._pos, n)
                memoryview(buf).cast("B")[:k] = head[self._pos : self._pos + k]
            self._pos += n
            return n
        except BaseException as exc:  # noqa: BLE001
            self._fail(exc)
            return 0

    def read(self, size: int = -1) -> bytes:
        buf = bytearray(max(self._size - self._pos, 0) if size < 0 else size)
        return bytes(buf[: self.readinto(buf)])

    def write(self, buf) -> int:
        try:
            view = memoryview(buf).cast("B")
            pos, n = self._pos, len(view)
            self._pos = pos + n
            if not self._live:
                return n
            if self._head is not None and pos < len(self._head):
                self._write_head(pos, view)
            elif pos == 0 and _known(view[:64]):  # the first superblock of a new file
                self._head = bytearray(16 + 4 * view[9])
                self._write_head(pos, view)
            else:
                if pos + n > self._size:
                    self._grow(pos + n)
                self._put(view, pos)
            return n
        except BaseException as exc:  # noqa: BLE001
            self._fail(exc)
            return len(buf)

    def truncate(self, size: int | None = None) -> int:
        try:
            size = self._pos if size is None else size
            self._eoa = self._trim = size
            if size > self._size and self._live:
                self._grow(size)
        except BaseException as exc:  # noqa: BLE001
            self._fail(exc)
        return size

    def flush(self) -> None:
        """Nothing to do: writes are not buffered (the page cache survives ``kill -9``)."""

    # -- for the owner ---------------------------------------------------------------------------
    @property
    def closed(self) -> bool:
        return self._fh.closed

    def close(self) -> None:
        """Close the descriptor, once HDF5 closed the file; trims it to HDF5's last EOA."""
        if self._fh.closed:
            return
        try:
            if self._redo is not None:  # HDF5 finished every write (unless one failed: then it may be needed)
                self._redo.close(remove=self._live)
            trim = self._trim
            if self._live and self._head is not None and trim is not None and self._eoa <= trim < self._size:
                self._pwrite(memoryview(_stamp(self._head, trim)), 0)  # the EOA never passes the end
                self._ftruncate(trim)
        finally:
            self._fh.close()

    def publish(self) -> None:
        """The file now has its name (a new file is renamed once valid): keep a redo record of its
        in-place writes from here on (see :mod:`._redo`)."""
        if self._redo is None:
            self._redo = _redo_log(self.name, self._fd)

    def detach(self) -> None:
        """Drop every later change: the file belongs to another process (this one is a fork)."""
        self._live = False

    # -- helpers ---------------------------------------------------------------------------------
    def _fail(self, exc: BaseException) -> None:
        if self.error is None:
            self.error = exc
        self._live = False

    def _pwrite(self, view: memoryview, pos: int) -> None:
        pwrite_all(self._fd, view, pos)

    def _put(self, view: memoryview, pos: int) -> None:
        """Write HDF5's bytes; one landing on bytes already written is recorded first, in case a
        kill cuts it (see :mod:`._redo`)."""
        if self._redo is not None and pos < self._written:
            self._redo.before(view, pos)
        self._pwrite(view, pos)
        self._written = max(self._written, pos + len(view))

    def _ftruncate(self, size: int) -> None:
        os.ftruncate(self._fd, size)
        self._size = size

    def _write_head(self, pos: int, view: memoryview) -> None:
        head = self._head
        k = min(len(head) - pos, len(view))
        head[pos : pos + k] = view[:k]
        self._eoa = _eoa(head)
        if len(view) > k:  # metadata written along with the superblock goes first
            if pos + len(view) > self._size:
                self._ftruncate(pos + len(view) + SLACK)
            self._put(view[k:], pos + k)
        self._restamp()

    def _grow(self, end: int) -> None:
        """Extend the file to ``end`` plus :data:`SLACK`, then point the EOA at its end."""
        self._ftruncate(end + SLACK)
        if self._head is not None:
            self._restamp()

    def _restamp(self) -> None:
        if self._eoa > self._size:  # the EOA never passes the end
            self._ftruncate(self._eoa + SLACK)
        self._pwrite(memoryview(_stamp(self._head, self._size)), 0)

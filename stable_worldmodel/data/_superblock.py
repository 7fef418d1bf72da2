"""Keep an HDF5 file that is being written in SWMR mode openable by plain ``h5py``.

While a file is open for (SWMR) writing, HDF5 marks its superblock (version 3) with
"open for write" flags and keeps its end-of-allocation address (EOA) loosely up to date.
A reader that does not use SWMR refuses such a file (``file is already open for write``)
and, after the writer was killed, would keep refusing it (``h5clear`` clears the flags).

The writer calls :func:`seal` after every flush: the flags are cleared and the EOA is set
to the file's size, so at any moment between two writes the file on disk is a valid,
closed-looking HDF5 file. :func:`repair` does the same for a file whose writer was killed
during a write. Superblock version 2/3 layout (all little endian)::

    offset  size  field
    0       8     signature  \\x89HDF\\r\\n\\x1a\\n
    8       1     superblock version (2 or 3)
    9       1     size of offsets (O, 8)
    10      1     size of lengths
    11      1     file consistency flags  <- cleared
    12      O     base address
    12+O    O     superblock extension address
    12+2O   O     end-of-file address     <- raised to the file size
    12+3O   O     root group object header address
    12+4O   4     Jenkins lookup3 checksum of the bytes before it
"""

from __future__ import annotations

import os
import struct
from pathlib import Path

SIGNATURE = b"\x89HDF\r\n\x1a\n"
_M = 0xFFFFFFFF


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


def needs_repair(path: str | os.PathLike) -> bool:
    """True when the superblock still carries "open for write" flags."""
    with open(path, "rb") as fh:
        head = fh.read(12)
    return head[:8] == SIGNATURE and head[8] >= 2 and head[11] != 0


def seal(path: str | os.PathLike) -> bool:
    """Clear the write flags and raise the EOA to the file size; False for other superblocks."""
    path = Path(path)
    with open(path, "r+b") as fh:
        head = bytearray(fh.read(64))
        if head[:8] != SIGNATURE or head[8] not in (2, 3):
            return False
        size = head[9]
        end = 12 + 4 * size
        stored = int.from_bytes(head[end : end + 4], "little")
        if lookup3(bytes(head[:end])) != stored:
            return False  # not a superblock layout we know: leave it alone
        eoa_at = 12 + 2 * size
        eoa = int.from_bytes(head[eoa_at : eoa_at + size], "little")
        file_size = os.fstat(fh.fileno()).st_size
        if file_size < eoa:  # HDF5 refuses files shorter than their EOA
            fh.truncate(eoa)
        head[11] = 0
        head[eoa_at : eoa_at + size] = max(eoa, file_size).to_bytes(size, "little")
        fh.seek(0)
        fh.write(bytes(head[:end]) + struct.pack("<I", lookup3(bytes(head[:end]))))
        fh.flush()
    return True


def repair(path: str | os.PathLike) -> bool:
    """Make a file left by a killed writer openable by plain h5py; True if it changed it."""
    return needs_repair(path) and seal(path)

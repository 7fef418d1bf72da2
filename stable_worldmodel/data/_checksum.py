"""HDF5's Fletcher-32 chunk checksum, and re-sealing the raw chunks a killed commit may have torn.

Kept for files of an earlier version, written with its ``writer.CHECKSUM_RAW`` flag: their raw
(uncompressed) columns have HDF5's Fletcher-32 filter, each chunk stored as its bytes followed
by a 4-byte checksum, which HDF5 checks on every read. New files never get it (their raw rows
carry checksums of their own, see :mod:`._rowsum`): an append to a partly filled Fletcher-32
chunk rewrites it whole, in place, its committed rows with the bytes they already hold. A
``kill -9`` in the middle of that write (one ``pwrite`` of several pages) can leave the chunk's
first pages new and its last ones (the checksum) old: its committed rows are intact, but HDF5
refuses the chunk, for reading and for appending. :func:`reseal` stamps a fresh checksum on such
chunks; the writer calls it when it resumes a file (the only time one can be torn is past the
committed rows' end, where that writer's commit was under way).
"""

from __future__ import annotations

import numpy as np

CHECKSUM_BYTES = 4


def fletcher32(data: bytes) -> int:
    """``H5_checksum_fletcher32``: 16-bit big-endian words, sums folded every 360 words."""
    words = np.frombuffer(data, ">u2", count=len(data) // 2).tolist()
    s1 = s2 = 0
    for i in range(0, len(words), 360):
        for w in words[i : i + 360]:
            s1 += w
            s2 += s1
        s1 = (s1 & 0xFFFF) + (s1 >> 16)
        s2 = (s2 & 0xFFFF) + (s2 >> 16)
    if len(data) % 2:
        s1 += data[-1] << 8
        s2 += s1
        s1 = (s1 & 0xFFFF) + (s1 >> 16)
        s2 = (s2 & 0xFFFF) + (s2 >> 16)
    s1 = (s1 & 0xFFFF) + (s1 >> 16)
    s2 = (s2 & 0xFFFF) + (s2 >> 16)
    return (s2 << 16) | s1


def only_fletcher32(dset) -> bool:
    """``dset`` is chunked and its only filter is Fletcher-32 (a raw column of a checksummed file)."""
    import h5py

    if dset.chunks is None or not dset.fletcher32:
        return False
    plist = dset.id.get_create_plist()
    return plist.get_nfilters() == 1 and plist.get_filter(0)[0] == h5py.h5z.FILTER_FLETCHER32


def holds(raw: bytes) -> bool:
    """The stored checksum of chunk ``raw`` (as ``read_direct_chunk`` returns it) matches its bytes;
    HDF5 also accepts the byte-swapped value that some old versions wrote."""
    stored = raw[-CHECKSUM_BYTES:]
    expected = fletcher32(raw[:-CHECKSUM_BYTES])
    return stored in (expected.to_bytes(4, "little"), expected.to_bytes(4, "big"))


def reseal(dset, end: int) -> list[int]:
    """Give a fresh checksum to the chunks of ``dset`` from the one holding row ``end`` (the end of
    the committed rows) on whose checksum fails; returns their first rows."""
    if not only_fletcher32(dset):
        return []
    rows = dset.chunks[0]
    fixed = []
    for start in range(end // rows * rows, dset.shape[0], rows):
        try:
            dset[start : start + rows]  # HDF5 checks the checksum (in C, the common case)
            continue
        except OSError:
            pass
        coord = (start,) + (0,) * (dset.ndim - 1)
        try:
            mask, raw = dset.id.read_direct_chunk(coord)
        except (OSError, RuntimeError, ValueError):  # no chunk stored there: nothing to fix
            continue
        if mask or holds(raw):  # unreadable for another reason: the writes that follow report it
            continue
        data = raw[:-CHECKSUM_BYTES]
        dset.id.write_direct_chunk(coord, data + fletcher32(data).to_bytes(4, "little"))
        fixed.append(start)
    return fixed

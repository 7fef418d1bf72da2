"""The episode index of an HDF5 dataset (``ep_len`` / ``ep_offset``), checked before anything trusts it."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from .. import keys
from ..errors import DatasetFormatError


def not_a_file(path: Path) -> str | None:
    """What ``path`` is when it exists but is not a regular file ("a folder", "a FIFO"...), else None."""
    import stat

    try:
        mode = path.stat().st_mode
    except FileNotFoundError:
        return None
    if stat.S_ISREG(mode):
        return None
    return "a folder" if stat.S_ISDIR(mode) else "a FIFO" if stat.S_ISFIFO(mode) else "not a regular file"


def check_file(path: Path, owner: str) -> None:
    """Raise unless ``path`` is a regular file: FileNotFoundError, or DatasetFormatError saying what it is."""
    what = not_a_file(path)
    if what is not None:
        raise DatasetFormatError(f"{owner} requires an .h5 file, got {str(path)!r}, which is {what}")
    if not path.exists():
        raise FileNotFoundError(f"{owner} requires an existing .h5 file, got {str(path)!r} (not found)")


# what h5py raises for metadata HDF5 cannot read (RuntimeError: "Link iteration failed",
# "Unable to get group info"...; KeyError when an object cannot be opened)
H5_READ_ERRORS = (OSError, RuntimeError, KeyError)


def damaged(owner: str, path: Path, exc: BaseException) -> DatasetFormatError:
    """The error for HDF5 file ``path`` that HDF5 fails to read: it names the file and, when the
    file is shorter than its superblock says, how much of it is left."""
    from ._superblock import truncation

    cut = truncation(path)
    state = f"truncated ({cut})" if cut else "damaged or truncated"
    return DatasetFormatError(
        f"{owner} requires an intact HDF5 file, got {path}, which is {state}: {exc}; "
        "restore it from a copy or record it again"
    )


def _names(f) -> str:
    """The names in open file ``f`` for an error message; a damaged group cannot always list them."""
    try:
        return str(sorted(f))
    except H5_READ_ERRORS:
        return "(unreadable)"


def _fresh(dset):
    """``dset`` as it is on disk now: a file opened twice in one process shares HDF5's cached metadata."""
    if dset.file.swmr_mode:
        dset.refresh()
    return dset


def read_index(
    f, path: Path, owner: str = "HDF5Dataset", checksums: dict[str, Any] | None = None
) -> tuple[np.ndarray, np.ndarray, list[str]]:
    """``(lengths, offsets, columns)`` of open file ``f``, checked: a damaged index raises DatasetFormatError.

    ``ep_len`` / ``ep_offset`` must be 1-D integer datasets (``ep_offset`` may hold one more
    entry, from a killed commit), lengths positive, episodes in order and not overlapping,
    and every column a numeric dataset with rows for every episode. In a file whose rows carry
    checksums (written by :class:`~.writer.HDF5Writer`, which stores episodes one after the
    other), a gap between episodes is damage to the index. The checksum datasets
    (:mod:`._rowsum`) are not columns: ``checksums``, if given, gets each one (refreshed after
    the index, so that it covers every committed row), by the name of its column.
    """
    import h5py

    from ._rowsum import column_of, is_companion
    from ._superblock import truncation

    def bad(what: str) -> DatasetFormatError:
        cut = truncation(path)  # the likely cause of a missing or unreadable object
        return DatasetFormatError(
            f"{owner} requires {what} in {path}" + (f", which is truncated ({cut})" if cut else "")
        )

    index = {}
    for name in (keys.EP_LEN, keys.EP_OFFSET):
        dset = f.get(name)
        if not isinstance(dset, h5py.Dataset):
            got = "missing" if dset is None else type(dset).__name__
            listing = "" if truncation(path) else f"; columns: {_names(f)}"  # a cut file: HDF5 would retry in vain
            raise bad(f"a 1-D integer dataset {name!r} (the episode index), got {got}{listing}")
        if dset.ndim != 1 or not np.issubdtype(dset.dtype, np.integer):
            raise bad(f"a 1-D integer dataset {name!r}, got shape {dset.shape} of {dset.dtype}")
        index[name] = _fresh(dset)
    lengths = index[keys.EP_LEN][:].astype(np.int64)
    offsets = index[keys.EP_OFFSET][: len(lengths)].astype(np.int64)
    if len(offsets) != len(lengths):
        raise bad(f"one ep_offset per ep_len, got {len(offsets)} offsets for {len(lengths)} episodes")
    if len(lengths):
        if lengths.min() < 1:
            ep = int(np.argmin(lengths))
            raise bad(f"positive episode lengths, got ep_len[{ep}] = {lengths[ep]}")
        if offsets[0] < 0:
            raise bad(f"non-negative offsets, got ep_offset[0] = {offsets[0]}")
        ends = offsets + lengths
        clash = np.flatnonzero(offsets[1:] < ends[:-1])
        if len(clash):
            e = int(clash[0])
            raise bad(
                f"episodes in order and not overlapping, got episode {e + 1} at row {offsets[e + 1]} "
                f"inside episode {e} (rows {offsets[e]}:{ends[e]})"
            )
    end = int(offsets[-1] + lengths[-1]) if len(lengths) else 0
    columns, summed = [], False
    for name in f:
        if name in index:
            continue
        dset = f[name]  # not f.items(): it silently skips objects that cannot be opened
        if isinstance(dset, h5py.Group):
            continue  # not a column
        _fresh(dset)  # after the index: a checksum dataset then covers every committed row
        if is_companion(name):
            summed = True
            if checksums is not None:
                checksums[column_of(name)] = dset
            continue
        if dset.ndim < 1 or not (np.issubdtype(dset.dtype, np.number) or dset.dtype == np.bool_):
            raise bad(f"numeric columns of one row per step, got {name!r} of shape {dset.shape} and dtype {dset.dtype}")
        if dset.shape[0] < end:
            raise bad(f"{end} rows in every column (the episodes need them), got {dset.shape[0]} in {name!r}")
        columns.append(name)
    if summed and len(lengths):
        starts = np.concatenate([[0], np.cumsum(lengths)[:-1]])
        gap = np.flatnonzero(offsets != starts)
        if len(gap):
            e = int(gap[0])
            raise DatasetFormatError(
                f"{owner} requires the episodes of {path} one after the other (its rows carry checksums), got "
                f"ep_offset[{e}] = {offsets[e]} where the episodes before it end at row {starts[e]}: ep_len or "
                "ep_offset was damaged after it was written; restore the file from a copy or record it again"
            )
    return lengths, offsets, columns

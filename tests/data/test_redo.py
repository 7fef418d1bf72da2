"""The redo record that completes an in-place write a kill cut at a page boundary (data/_redo.py)."""

from __future__ import annotations

import os

import h5py
import numpy as np
import pytest

from stable_worldmodel import keys
from stable_worldmodel.data import HDF5Dataset, _redo, repair
from stable_worldmodel.data._lock import WriterLock
from stable_worldmodel.data.writer import HDF5Writer

PAGE = _redo.PAGE


def _file(tmp_path, size=3 * PAGE):
    path = tmp_path / "data.bin"
    path.write_bytes(bytes(range(256)) * (size // 256))
    return path


@pytest.fixture
def fds():
    opened = []
    yield opened
    for fd in opened:
        os.close(fd)


def _log(path, data: bytes, pos: int, fds: list) -> _redo.RedoLog:
    """Record the write of ``data`` at ``pos`` (not made yet), as the writer does before making it."""
    fds.append(os.open(path, os.O_RDWR))
    log = _redo.RedoLog(path, fds[-1])
    log.before(memoryview(data), pos)
    if log._fd is not None:
        fds.append(log._fd)
    return log


def _write(path, data: bytes, pos: int) -> None:
    with open(path, "r+b") as fh:
        fh.seek(pos)
        fh.write(data)


@pytest.mark.parametrize("cut", [0, PAGE - 100, 2 * PAGE - 100])
def test_a_cut_write_is_completed_and_its_record_removed(tmp_path, cut, fds):
    path = _file(tmp_path)
    new = b"\xab" * (2 * PAGE + 200)
    pos = 100  # spans pages 0, 1 and 2: the kernel may stop after PAGE - 100 or 2 * PAGE - 100 bytes
    _log(path, new, pos, fds)
    _write(path, new[:cut], pos)  # what a kill at that boundary leaves
    assert _redo.complete(path) is True
    assert path.read_bytes()[pos : pos + len(new)] == new
    assert not _redo.record_path(path).exists()


def test_a_finished_write_is_left_as_it_is(tmp_path, fds):
    path = _file(tmp_path)
    new = b"\xab" * (PAGE + 200)
    _log(path, new, 100, fds)
    _write(path, new, 100)
    before = path.read_bytes()
    assert _redo.complete(path) is False and path.read_bytes() == before
    assert not _redo.record_path(path).exists()


@pytest.mark.parametrize(
    "change",
    [
        lambda path: _write(path, b"\xcd" * 10, 200),  # the region holds bytes the record does not know
        lambda path: _write(path, b"\xab" * 50, 100),  # new bytes up to a place that is no page boundary
    ],
)
def test_a_record_that_does_not_describe_the_file_changes_nothing(tmp_path, change, fds):
    """A copy of the file changed since, or a file made anew under the name: its bytes are no cut of the write."""
    path = _file(tmp_path)
    _log(path, b"\xab" * (PAGE + 200), 100, fds)
    change(path)
    before = path.read_bytes()
    assert _redo.complete(path) is False and path.read_bytes() == before
    assert not _redo.record_path(path).exists()


@pytest.mark.parametrize(
    "spoil",
    [
        lambda rec: rec.write_bytes(rec.read_bytes()[:-1]),  # the record's own write was cut
        lambda rec: rec.write_bytes(rec.read_bytes()[:-1] + b"\x00"),  # a flipped byte
        lambda rec: rec.write_bytes(b""),
    ],
)
def test_a_cut_or_damaged_record_is_ignored(tmp_path, spoil, fds):
    """The record is written before the file: if the kill cut the record, the file was not touched."""
    path = _file(tmp_path)
    _log(path, b"\xab" * (PAGE + 200), 100, fds)
    spoil(_redo.record_path(path))
    before = path.read_bytes()
    assert _redo.complete(path) is False and path.read_bytes() == before


def test_a_later_write_over_the_recorded_bytes_clears_the_record(tmp_path, fds):
    """Replaying the record after a one-page write over its bytes would undo that write."""
    path = _file(tmp_path)
    log = _log(path, b"\xab" * (PAGE + 200), 100, fds)
    _write(path, b"\xab" * (PAGE + 200), 100)
    log.before(memoryview(b"\x01" * 8), 120)  # within one page: never cut, not recorded, but over the record
    _write(path, b"\x01" * 8, 120)
    assert _redo._parse(_redo.record_path(path).read_bytes()) is None
    log.before(memoryview(b"\x02" * 8), 3 * PAGE - 8)  # elsewhere: nothing to clear
    assert _redo.complete(path) is False and path.read_bytes()[120:128] == b"\x01" * 8


def test_one_page_writes_are_not_recorded(tmp_path, fds):
    path = _file(tmp_path)
    _log(path, b"\xab" * 100, PAGE, fds)
    assert not _redo.record_path(path).exists()
    assert _redo.spans_pages(PAGE - 1, 2) and not _redo.spans_pages(PAGE, PAGE) and not _redo.spans_pages(5, 0)


def _cut_dataset(tmp_path, synth, cut_writes) -> tuple:
    """A dataset of 3 episodes plus the state a kill leaves when it cuts the writer's next in-place
    write of several pages (the file's bytes, its redo record); the file holds the cut state."""
    path = tmp_path / "cut.h5"
    with HDF5Writer(path) as w:
        for ep in range(3):
            w.write_episodes([synth(ep, 3, (24, 24))], next_seed=ep + 1)
    cut = cut_writes(path, first_only=True)
    with HDF5Writer(path) as w:
        ep = 3
        while not cut:
            w.write_episodes([synth(ep, 3, (24, 24))], next_seed=ep + 1)
            ep += 1
    raw, record = cut[0]
    path.write_bytes(raw)
    _redo.record_path(path).write_bytes(record)
    return path, raw, record


def test_the_dataset_reader_completes_a_cut_write_on_open(tmp_path, synth, cut_writes):
    path, _, _ = _cut_dataset(tmp_path, synth, cut_writes)
    ds = HDF5Dataset(path)
    assert ds.num_episodes >= 3
    np.testing.assert_array_equal(ds.get_col_data(keys.STATE)[:3], synth(0, 3, (24, 24))[keys.STATE])
    ds.close()
    assert not _redo.record_path(path).exists()
    with h5py.File(path) as f:  # and plain h5py opens it from then on
        assert f[keys.EP_LEN][:3].tolist() == [3, 3, 3]


def test_a_resuming_writer_completes_a_cut_write(tmp_path, synth, cut_writes):
    path, _, _ = _cut_dataset(tmp_path, synth, cut_writes)
    with HDF5Writer(path) as w:
        n = w.num_episodes
        w.write_episodes([synth(n, 2, (24, 24))])
    with h5py.File(path) as f:
        assert f[keys.EP_LEN][:].tolist() == [3] * n + [2]


def test_a_reader_leaves_the_record_of_a_live_writer_alone(tmp_path, synth, cut_writes):
    """While a writer holds the file, its record describes a write it may still be making."""
    path, raw, record = _cut_dataset(tmp_path, synth, cut_writes)
    with WriterLock(path):
        assert repair(path) is False
    assert path.read_bytes() == raw and _redo.record_path(path).read_bytes() == record
    assert repair(path) is True


def test_a_new_file_drops_the_record_of_a_file_once_at_its_path(tmp_path, synth, cut_writes):
    path, _, _ = _cut_dataset(tmp_path, synth, cut_writes)
    with HDF5Writer(path, mode="overwrite") as w:
        assert not _redo.record_path(path).exists()
        w.write_episodes([synth(0, 2, (24, 24))])
    path.unlink()
    stale = _redo.record_path(path)
    stale.write_bytes(b"stale")
    with HDF5Writer(path) as w:
        w.write_episodes([synth(0, 2, (24, 24))])
        assert not stale.exists() or stale.read_bytes() != b"stale"
    assert not stale.exists()

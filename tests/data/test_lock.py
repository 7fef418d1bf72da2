"""One writer per dataset: a second writer fails at once naming the holder, or waits; kills free the lock."""

from __future__ import annotations

import multiprocessing
import os
import signal
import time

import h5py
import pytest

from stable_worldmodel import keys
from stable_worldmodel.data._lock import WriterLock, lock_path
from stable_worldmodel.data.writer import HDF5Writer
from stable_worldmodel.errors import ConfigError, DatasetBusyError, DatasetFormatError


def _hold(path, ready, seconds, synth):  # pragma: no cover - runs in a forked child
    try:
        with HDF5Writer(path) as w:
            w.write_episodes([synth(9, 2)])
            ready.set()
            time.sleep(seconds)
    finally:
        os._exit(0)


@pytest.fixture
def holder(tmp_path, synth):
    """``holder(seconds)`` starts a process that writes ``tmp_path/d.h5`` and holds it that long."""
    procs = []

    def start(seconds):
        ready = multiprocessing.get_context("fork").Event()
        proc = multiprocessing.get_context("fork").Process(
            target=_hold, args=(tmp_path / "d.h5", ready, seconds, synth)
        )
        proc.start()
        assert ready.wait(60)  # a slow start on a loaded machine is not what these tests check
        procs.append(proc)
        return proc

    yield start
    for proc in procs:
        if proc.is_alive():
            proc.kill()
        proc.join()


def test_second_writer_in_another_process_fails_at_once_naming_the_holder(tmp_path, holder, synth):
    proc = holder(30)
    t0 = time.monotonic()
    with pytest.raises(DatasetBusyError, match=rf"d\.h5 requires a single writer.*pid {proc.pid} on ") as err:
        HDF5Writer(tmp_path / "d.h5")
    assert time.monotonic() - t0 < 1
    assert isinstance(err.value, BlockingIOError) and "wait=True" in str(err.value)


def test_second_writer_waits_when_asked_and_appends_after_the_first(tmp_path, holder, synth):
    holder(0.5)
    with pytest.raises(DatasetBusyError, match="waited 0.1 s"):
        HDF5Writer(tmp_path / "d.h5", wait=0.1)
    with HDF5Writer(tmp_path / "d.h5", wait=True) as w:
        assert w.num_episodes == 1
        w.write_episodes([synth(1, 3)])
    with h5py.File(tmp_path / "d.h5") as f:
        assert f[keys.EP_LEN][:].tolist() == [2, 3]
    assert not lock_path(tmp_path / "d.h5").exists()  # removed by the last holder


def test_lock_of_a_killed_holder_is_free_at_once(tmp_path, holder, synth):
    proc = holder(30)
    os.kill(proc.pid, signal.SIGKILL)
    proc.join()
    with HDF5Writer(tmp_path / "d.h5") as w:  # no wait needed: the kernel dropped the lock
        w.write_episodes([synth(1, 3)])
        assert w.num_episodes == 2


def test_same_name_twice_in_one_process(tmp_path, synth):
    first = HDF5Writer(tmp_path / "new.h5")  # not created yet: the name is still taken
    with pytest.raises(DatasetBusyError, match="this process"):
        HDF5Writer(tmp_path / "new.h5")
    first.write_episodes([synth(0, 2)])
    first.close()
    with HDF5Writer(tmp_path / "new.h5") as w:
        assert w.num_episodes == 1


def test_forked_child_does_not_hold_or_release_the_parent_lock(tmp_path):
    lock = WriterLock(tmp_path / "x.h5").acquire()
    ctx = multiprocessing.get_context("fork")

    def child():  # pragma: no cover - forked
        lock.release()  # a no-op in the child: the lock file stays the parent's
        os._exit(0 if lock_path(tmp_path / "x.h5").exists() else 1)

    proc = ctx.Process(target=child)
    proc.start()
    proc.join()
    assert proc.exitcode == 0
    with pytest.raises(DatasetBusyError):
        WriterLock(tmp_path / "x.h5").acquire()
    lock.release()
    WriterLock(tmp_path / "x.h5").acquire().release()


def test_garbage_collected_writer_releases_its_lock(tmp_path, synth):
    w = HDF5Writer(tmp_path / "gc.h5")
    w.write_episodes([synth(0, 2)])
    del w
    with HDF5Writer(tmp_path / "gc.h5") as w:
        assert w.num_episodes == 1


@pytest.mark.parametrize("wait", ["yes", -1, None])
def test_bad_wait(tmp_path, wait):
    with pytest.raises(ConfigError, match="wait"):
        WriterLock(tmp_path / "x.h5", wait=wait)


def test_folder_or_fifo_at_the_path(tmp_path):
    (tmp_path / "dir.h5").mkdir()
    with pytest.raises(DatasetFormatError, match="dir.h5.*a folder"):
        HDF5Writer(tmp_path / "dir.h5")
    os.mkfifo(tmp_path / "pipe.h5")
    with pytest.raises(DatasetFormatError, match="pipe.h5.*a FIFO"):
        HDF5Writer(tmp_path / "pipe.h5")


def test_leftover_partial_files_are_listed_and_cleaned(tmp_path, monkeypatch, synth):
    from stable_worldmodel.data.info import leftover_partials

    monkeypatch.setenv("STABLEWM_HOME", str(tmp_path))
    partial = tmp_path / "sub" / ".killed.h5.partial"  # a first recording killed before its file was valid
    partial.parent.mkdir()
    partial.write_bytes(b"half an HDF5 file")
    assert leftover_partials() == [partial]
    lock = WriterLock(tmp_path / "sub" / "killed.h5").acquire()  # being created right now: not leftover
    assert leftover_partials() == []
    lock.release()
    with HDF5Writer(tmp_path / "sub" / "killed.h5") as w:  # the next recording of that name removes it
        assert not partial.exists()
        w.write_episodes([synth(0, 2)])
    assert leftover_partials() == []

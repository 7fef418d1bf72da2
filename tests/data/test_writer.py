"""HDF5Writer: layout, validation, resume, loud failures, and a file that survives ``kill -9``."""

from __future__ import annotations

import multiprocessing
import os
import random
import signal
import subprocess
import sys
import textwrap
import time

import h5py
import numpy as np
import pytest

from stable_worldmodel import keys
from stable_worldmodel.data import HDF5Dataset, _redo, _superblock, repair
from stable_worldmodel.data import writer as writer_module
from stable_worldmodel.data.writer import NEXT_SEED_ATTR, HDF5Writer
from stable_worldmodel.errors import DatasetFormatError

IMAGE = (24, 24)  # rows of 1.7 kB: compressed, one row per chunk (smaller rows are stored raw)


def _length(ep: int) -> int:
    return 2 + ep % 5


def _episode(synth, ep: int) -> dict[str, np.ndarray]:
    """Episode ``ep`` as the recording children write it: a compressed image column and raw ones."""
    return synth(ep, _length(ep), IMAGE)


def _record_forever(path, synth, pause=0.0):  # pragma: no cover - runs in a forked child
    """Append episodes 0, 1, ... (content derived from the index) until killed."""
    try:
        writer = HDF5Writer(path)
        ep = writer.num_episodes
        while True:
            writer.write_episodes([_episode(synth, ep)], next_seed=ep + 1)
            ep += 1
            time.sleep(pause)
    finally:
        os._exit(1)


def _check_committed(f, synth) -> int:
    """Every committed episode of ``f`` (by ep_len / ep_offset) holds what was written; their count."""
    lengths, offsets = f[keys.EP_LEN][:], f[keys.EP_OFFSET][: len(f[keys.EP_LEN])]
    assert lengths.tolist() == [_length(e) for e in range(len(lengths))]
    end = int(offsets[-1] + lengths[-1]) if len(lengths) else 0
    columns = {name: f[name][:end] for name in f if name not in (keys.EP_LEN, keys.EP_OFFSET)}
    for ep, (off, n) in enumerate(zip(offsets, lengths, strict=False)):
        for name, value in synth(ep, int(n), columns[keys.PIXELS].shape[1:3]).items():
            np.testing.assert_array_equal(columns[name][off : off + n], value, err_msg=f"{name} of episode {ep}")
    return len(lengths)


def _fork(target, *args):
    proc = multiprocessing.get_context("fork").Process(target=target, args=args, daemon=True)
    proc.start()
    return proc


def test_layout(make_h5):
    path = make_h5((5, 7, 4))
    with h5py.File(path, "r") as f:
        assert f[keys.EP_LEN][:].tolist() == [5, 7, 4]
        assert f[keys.EP_LEN].dtype == np.int32
        assert f[keys.EP_OFFSET][:].tolist() == [0, 5, 12]
        assert f[keys.EP_OFFSET].dtype == np.int64
        assert f[keys.PIXELS].shape == (16, 8, 8, 3) and f[keys.PIXELS].dtype == np.uint8
        assert f[keys.STATE][5:12, 0].tolist() == [1.0] * 7
        assert f.attrs[NEXT_SEED_ATTR] == 3
        assert f[keys.PIXELS].compression is None  # 192-byte rows are stored raw
        assert f[keys.STATE].chunks == (1024, 2)  # 16 KiB of raw rows


def test_big_rows_are_compressed_one_row_per_chunk(make_h5):
    path = make_h5((3, 2), image=IMAGE)
    with h5py.File(path, "r") as f:
        assert f[keys.PIXELS].compression == "gzip" and f[keys.PIXELS].chunks == (1, *IMAGE, 3)
        assert f[keys.PIXELS].id.get_num_chunks() == 5
        assert f[keys.STATE].compression is None


def _committed_bytes(f) -> list[tuple[str, int, int]]:
    """(column, start, end) file byte ranges that hold the rows of ``f``'s committed episodes."""
    ranges = []
    for name, dset in f.items():
        rows = len(f[keys.EP_LEN]) if name in (keys.EP_LEN, keys.EP_OFFSET) else int(f[keys.EP_LEN][:].sum())
        row_bytes = int(np.prod(dset.shape[1:], dtype=np.int64)) * dset.dtype.itemsize
        for i in range(dset.id.get_num_chunks()):
            chunk = dset.id.get_chunk_info(i)
            first = chunk.chunk_offset[0]
            if first >= rows:
                continue
            used = chunk.size if dset.compression else min(dset.chunks[0], rows - first) * row_bytes
            ranges.append((name, chunk.byte_offset, chunk.byte_offset + used))
    return ranges


def test_appending_and_resuming_never_write_over_committed_rows(tmp_path, monkeypatch, synth):
    """Committed rows are immutable: no write of a later commit (or of a resume) touches their bytes."""
    path = tmp_path / "immutable.h5"
    writes = []

    class Logging(_superblock.SealedFile):
        def _pwrite(self, view, pos):
            writes.append((pos, pos + len(view)))
            super()._pwrite(view, pos)

    monkeypatch.setattr(_superblock, "SealedFile", Logging)
    with HDF5Writer(path) as w:
        for ep in range(4):
            w.write_episodes([_episode(synth, ep)], next_seed=ep + 1)
        committed = _committed_bytes(w._file)
        writes.clear()
        for ep in range(4, 12):
            w.write_episodes([_episode(synth, ep)], next_seed=ep + 1)
        for name in (keys.PIXELS, keys.STATE):  # rows a killed writer appended but never committed
            w._file[name].resize(w.num_rows + 3, axis=0)
            w._file[name][w.num_rows :] = w._file[name][:3]
        w._file.flush()
    assert writes and committed
    with HDF5Writer(path) as w:  # the resume drops the uncommitted rows
        assert w.num_episodes == 12
        w.write_episodes([_episode(synth, 12)], next_seed=13)
    clashes = [(c, w) for w in writes for c in committed if w[0] < c[2] and w[1] > c[1]]
    assert not clashes, f"{len(clashes)} writes over committed rows, e.g. {clashes[:3]}"
    with h5py.File(path) as f:
        assert _check_committed(f, synth) == 13


def _killed_at_write(path, synth, k):  # pragma: no cover - runs in a forked child
    """Append episodes 3 and 4 (one commit each) and SIGKILL this process at HDF5's k-th write."""
    calls = [0]
    real = _superblock.SealedFile._pwrite

    def counting(self, view, pos):
        calls[0] += 1
        if calls[0] == k:
            os.kill(os.getpid(), signal.SIGKILL)
        real(self, view, pos)

    _superblock.SealedFile._pwrite = counting
    try:
        with HDF5Writer(path) as w:
            for ep in range(3, 5):
                w.write_episodes([_episode(synth, ep)], next_seed=ep + 1)
    finally:
        os._exit(0)


def test_kill_at_every_write_keeps_committed_episodes_byte_identical(tmp_path, synth):
    base = tmp_path / "base.h5"
    with HDF5Writer(base) as w:
        for ep in range(3):
            w.write_episodes([_episode(synth, ep)], next_seed=ep + 1)
    with h5py.File(base) as f:
        before = {name: f[name][: int(f[keys.EP_LEN][:].sum())].tobytes() for name in f if f[name].ndim > 1}
    path = tmp_path / "killed.h5"
    outcomes = set()
    for k in range(1, 200):
        path.write_bytes(base.read_bytes())
        proc = _fork(_killed_at_write, path, synth, k)
        proc.join()
        with h5py.File(path) as f:  # plain h5py, no repair
            count = _check_committed(f, synth)
            assert count >= 3, f"kill at write {k}"
            for name, raw in before.items():
                assert f[name][: len(raw) // f[name][0].nbytes].tobytes() == raw, f"{name} after a kill at write {k}"
        with HDF5Writer(path) as w:  # resumes after the committed episodes: a seed may be skipped, none repeated
            assert count <= w.next_seed <= count + 1, f"kill at write {k}"
            w.write_episodes([_episode(synth, count)], next_seed=count + 1)
        with h5py.File(path) as f:
            assert _check_committed(f, synth) == count + 1
        outcomes.add(count)
        if proc.exitcode == 0:  # the child finished before its k-th write: every later k is the same
            break
    assert proc.exitcode == 0 and outcomes == {3, 4, 5}, (k, outcomes)


def test_append_resumes_and_keeps_next_seed(make_h5, synth):
    path = make_h5((3, 4))
    with HDF5Writer(path) as w:
        assert (w.num_episodes, w.num_rows, w.next_seed) == (2, 7, 2)
        w.write_episodes([synth(2, 6)], next_seed=9)
    with h5py.File(path, "r") as f:
        assert f[keys.EP_LEN][:].tolist() == [3, 4, 6]
        assert f[keys.EP_OFFSET][:].tolist() == [0, 3, 7]
        assert f[keys.STATE][7:, 0].tolist() == [2.0] * 6
        assert f.attrs[NEXT_SEED_ATTR] == 9


def test_resume_writes_over_uncommitted_rows(make_h5, synth):
    path = make_h5((3, 4))
    with h5py.File(path, "a") as f:  # rows of an episode that never got its ep_len entry
        for name in (keys.PIXELS, keys.ACTION, keys.STATE, keys.STEP_IDX, keys.TERMINATED):
            f[name].resize(f[name].shape[0] + 5, axis=0)
    with HDF5Writer(path) as w:
        w.write_episodes([synth(2, 2)])
    with h5py.File(path, "r") as f:
        assert f[keys.EP_LEN][:].tolist() == [3, 4, 2]
        assert f[keys.STATE].shape[0] == 12  # never shrunk (that would rewrite committed rows)
        assert f[keys.STATE][7:9, 0].tolist() == [2.0, 2.0]
    ds = HDF5Dataset(path)
    assert ds.num_rows == 9 and ds.get_col_data(keys.STATE)[7:, 0].tolist() == [2.0, 2.0]


@pytest.mark.parametrize(
    "change, column",
    [
        (lambda ep: ep.update({keys.STATE: ep[keys.STATE][:, :1]}), keys.STATE),
        (lambda ep: ep.update({keys.PIXELS: ep[keys.PIXELS].astype(np.float32)}), keys.PIXELS),
        (lambda ep: ep.pop(keys.ACTION), keys.ACTION),
        (lambda ep: ep.update({"extra": np.zeros(len(ep[keys.STATE]))}), "extra"),
    ],
)
def test_bad_column_fails_naming_it(make_h5, change, column, synth):
    path = make_h5((3,))
    episode = synth(1, 4)
    change(episode)
    with HDF5Writer(path) as w, pytest.raises(DatasetFormatError, match=column):
        w.write_episodes([episode])
    with h5py.File(path, "r") as f:
        assert f[keys.EP_LEN][:].tolist() == [3]


def test_disk_full_fails_loudly_and_keeps_committed(make_h5, monkeypatch, synth):
    path = make_h5((3,))
    real = writer_module._write_rows

    def full(dset, start, rows):
        if dset.name == "/" + keys.PIXELS:
            raise OSError(28, "No space left on device")
        return real(dset, start, rows)

    monkeypatch.setattr(writer_module, "_write_rows", full)
    with HDF5Writer(path) as w, pytest.raises(DatasetFormatError, match="pixels"):
        w.write_episodes([synth(1, 4)])
    monkeypatch.undo()
    with h5py.File(path, "r") as f:
        assert f[keys.EP_LEN][:].tolist() == [3]


def test_lookup3_matches_hdf5_superblock_checksum(make_h5):
    path = make_h5((2,))
    head = path.read_bytes()[:48]
    assert head[8] == 3  # superblock v3 (libver latest)
    assert _superblock.lookup3(head[:44]) == int.from_bytes(head[44:48], "little")


def test_file_is_plain_openable_while_the_writer_is_open(tmp_path, synth):
    path = tmp_path / "open.h5"
    w = HDF5Writer(path)
    w.write_episodes([synth(0, 2)])
    assert not _superblock.needs_repair(path)
    with h5py.File(path) as f:  # plain h5py, default arguments, while the writer holds the file
        assert _check_committed(f, synth) == 1
    ds = HDF5Dataset(path)
    assert ds.lengths.tolist() == [2]
    ds.close()
    w.write_episodes([synth(1, 3)])
    with h5py.File(path) as f:
        assert _check_committed(f, synth) == 2
    w.close()
    with h5py.File(path) as f:
        assert _check_committed(f, synth) == 2


def test_every_state_between_two_system_calls_opens_plainly(tmp_path, monkeypatch, synth):
    """What a ``kill -9`` can leave: the file after each write/truncate the writer makes."""
    path = tmp_path / "steps.h5"
    states = []  # (file bytes, episodes committed when the call returned, path existed)

    class Recording(_superblock.SealedFile):
        def _pwrite(self, view, pos):
            super()._pwrite(view, pos)
            states.append((os.pread(self._fd, 1 << 30, 0), committed[0], path.exists()))

        def _ftruncate(self, size):
            super()._ftruncate(size)
            states.append((os.pread(self._fd, 1 << 30, 0), committed[0], path.exists()))

    monkeypatch.setattr(_superblock, "SealedFile", Recording)
    committed = [0]
    for session in ((0, 1, 2), (3,)):  # create, then resume
        with HDF5Writer(path) as w:
            for ep in session:
                w.write_episodes([synth(ep, _length(ep))], next_seed=ep + 1)
                committed[0] += 1
    assert len(states) > 50
    copy = tmp_path / "state.h5"
    for i, (raw, done, existed) in enumerate(states):
        if not existed:  # a new file is written under another name until it is valid
            assert done == 0
            continue
        copy.write_bytes(raw)
        with h5py.File(copy) as f:
            assert _check_committed(f, synth) >= done, f"state {i}"


def _opens_with_committed(path, synth) -> int | None:
    """Committed episodes of ``path`` as plain h5py reads them; None if it cannot open it."""
    try:
        with h5py.File(path) as f:
            return _check_committed(f, synth)
    except (OSError, KeyError):  # h5py raises KeyError for an object whose header fails its checksum
        return None


def test_a_write_a_kill_cuts_at_a_page_boundary_is_completed_on_open(tmp_path, cut_writes, synth):
    """A kill during a ``pwrite`` of several pages stops the kernel's copy at a page boundary: the
    file keeps the write's first pages and its old bytes after. HDF5 rewrites metadata in place
    (object headers, chunk-index blocks), so such a state may not open; every one, once its redo
    record is applied (``repair``, as readers and writers do on open), opens with every episode."""
    path = tmp_path / "cut.h5"
    states = cut_writes(path)
    done = []  # episodes committed when each state was recorded
    for session in (range(0, 30), range(30, 60)):  # create, then resume
        with HDF5Writer(path) as w:
            for ep in session:
                w.write_episodes([synth(ep, _length(ep), IMAGE)], next_seed=ep + 1)
                done += [ep] * (len(states) - len(done))
        done += [session[-1] + 1] * (len(states) - len(done))
        assert not _redo.record_path(path).exists()  # a closed writer leaves no record
    copy = tmp_path / "state.h5"
    unopenable = 0
    for i, ((raw, record), committed) in enumerate(zip(states, done, strict=True)):
        copy.write_bytes(raw)
        unopenable += _opens_with_committed(copy, synth) is None
        _redo.record_path(copy).write_bytes(record)
        assert repair(copy), f"state {i}"
        assert (_opens_with_committed(copy, synth) or 0) >= committed, f"state {i}"
        assert not _redo.record_path(copy).exists()
    assert len(states) > 20 and unopenable > 0  # the cuts are real damage, which the record mends


def test_sigkill_at_random_moments_keeps_every_committed_episode(tmp_path, synth):
    path = tmp_path / "killed.h5"
    rng = random.Random(0)
    seen = kills = 0
    while kills < 15 or (seen <= 10 and kills < 100):  # a loaded machine records fewer episodes per child
        kills += 1
        proc = _fork(_record_forever, path, synth)
        time.sleep(rng.uniform(0.0, 0.1))
        os.kill(proc.pid, signal.SIGKILL)
        proc.join()
        assert proc.exitcode == -signal.SIGKILL
        if not path.exists():  # killed before the file was first valid
            assert seen == 0
            continue
        assert not _superblock.needs_repair(path)
        repair(path)  # completes a write the kill cut at a page boundary, as the next reader or writer does
        with h5py.File(path) as f:  # plain h5py, default arguments
            count = _check_committed(f, synth)
        assert count >= seen  # the next child resumed after the last committed episode
        seen = count
    assert seen > 10


def test_readers_see_only_committed_episodes_while_recording(tmp_path, synth):
    path = tmp_path / "live.h5"
    proc = _fork(_record_forever, path, synth, 0.002)
    try:
        deadline = time.time() + 10
        while not path.exists() and time.time() < deadline:
            time.sleep(0.005)
        counts = []
        stop = time.time() + 0.5
        while time.time() < stop or len(counts) < 5:
            with h5py.File(path, "r", libver="latest", swmr=True) as f:  # h5py's live reader, mid-commit
                counts.append(_check_committed(f, synth))
            ds = HDF5Dataset(path)
            n = ds.num_episodes
            assert ds.lengths.tolist() == [_length(e) for e in range(n)]
            expected = [synth(e, _length(e))[keys.STATE] for e in range(n)]
            np.testing.assert_array_equal(ds.get_col_data(keys.STATE), np.concatenate([np.empty((0, 2)), *expected]))
            ds.close()
            counts.append(n)
        assert proc.is_alive()
    finally:
        os.kill(proc.pid, signal.SIGKILL)
        proc.join()
    assert counts == sorted(counts) and counts[-1] > counts[0]


EXIT_SCRIPT = """
import os, sys
sys.path.insert(0, sys.argv[2])
from conftest import synthetic_episode
from stable_worldmodel.data.writer import HDF5Writer

writer = HDF5Writer(sys.argv[1])  # never closed: interpreter exit closes HDF5, then the descriptor
writer.write_episodes([synthetic_episode(0, 2), synthetic_episode(1, 3)])
writer.cycle = writer
before = open(sys.argv[1], "rb").read()
pid = os.fork()
if pid == 0:
    sys.exit(0)  # a forked child exiting normally must leave its parent's file alone
os.waitpid(pid, 0)
print("unchanged" if open(sys.argv[1], "rb").read() == before else "changed by the child")
"""


def test_interpreter_exit_without_close_leaves_a_trimmed_plain_file(tmp_path, synth):
    path = tmp_path / "exit.h5"
    script = tmp_path / "exit.py"
    script.write_text(textwrap.dedent(EXIT_SCRIPT))
    tests_dir = os.path.dirname(__file__)
    done = subprocess.run([sys.executable, str(script), str(path), tests_dir], capture_output=True, text=True)
    assert (done.returncode, done.stdout, done.stderr) == (0, "unchanged\n", "")
    with h5py.File(path) as f:
        assert _check_committed(f, synth) == 2
    assert path.stat().st_size < _superblock.SLACK  # grown ahead while open, trimmed on close


@pytest.mark.parametrize("failure", [OSError(28, "No space left on device"), KeyboardInterrupt()])
def test_io_failure_inside_hdf5_leaves_committed_episodes(tmp_path, monkeypatch, synth, failure):
    path = tmp_path / "full.h5"
    armed = [False]

    class Failing(_superblock.SealedFile):
        def _pwrite(self, view, pos):
            if armed[0]:
                raise failure
            super()._pwrite(view, pos)

    monkeypatch.setattr(_superblock, "SealedFile", Failing)
    w = HDF5Writer(path)
    w.write_episodes([synth(0, 2)])
    armed[0] = True
    if isinstance(failure, OSError):
        raised = pytest.raises(DatasetFormatError, match="No space left on device.*1 episodes committed")
    else:
        raised = pytest.raises(KeyboardInterrupt)  # Ctrl-C inside HDF5's write still stops the program
    with raised:
        w.write_episodes([synth(1, 200)])
    armed[0] = False
    with pytest.raises(DatasetFormatError, match="closed"):  # nothing more goes to that file
        w.write_episodes([synth(1, 3)])
    with h5py.File(path) as f:
        assert _check_committed(f, synth) == 1
    with HDF5Writer(path) as w:  # a new writer appends after the committed episode
        w.write_episodes([synth(1, _length(1))])
    with h5py.File(path) as f:
        assert _check_committed(f, synth) == 2


def test_write_after_close_fails_and_keeps_the_file(make_h5, synth):
    path = make_h5((3,))
    w = HDF5Writer(path)
    w.close()
    with pytest.raises(DatasetFormatError, match="closed"):
        w.write_episodes([synth(1, 2)])
    with h5py.File(path) as f:
        assert f[keys.EP_LEN][:].tolist() == [3]


def test_repair_clears_flags_left_by_an_older_writer(make_h5):
    path = make_h5((2,))
    raw = bytearray(path.read_bytes())
    raw[11] = 5  # what HDF5 leaves while a SWMR writer has the file open
    raw[44:48] = _superblock.lookup3(bytes(raw[:44])).to_bytes(4, "little")
    path.write_bytes(bytes(raw))
    with pytest.raises(OSError, match="already open for write"):
        h5py.File(path, "r")
    assert _superblock.repair(path)
    assert not _superblock.repair(path)
    with h5py.File(path, "r") as f:
        assert f[keys.EP_LEN][:].tolist() == [2]


def _episodes_with_a_goal(synth, lengths=(4, 3)) -> list[dict[str, np.ndarray]]:
    """Synthetic episodes plus a ``goal`` image column that is constant within each episode."""
    episodes = []
    for ep, n in enumerate(lengths):
        episode = synth(ep, n, IMAGE)
        episode["goal"] = np.broadcast_to(episode[keys.PIXELS][-1], episode[keys.PIXELS].shape).copy()
        episodes.append(episode)
    return episodes


def test_compressed_chunks_are_zlib_streams_of_their_rows(tmp_path, synth):
    """Image rows are compressed by the writer and handed to HDF5 chunk by chunk: each chunk is
    what HDF5's deflate filter stores (filter mask 0, a zlib stream of the row), and the file reads
    back as one written through the filter does."""
    import zlib

    episodes = _episodes_with_a_goal(synth)
    direct, filtered = tmp_path / "direct.h5", tmp_path / "filtered.h5"
    with HDF5Writer(direct) as writer:
        writer.write_episodes(episodes)
    real = writer_module.deflate_level
    writer_module.deflate_level = lambda dset: None  # HDF5's own filter writes every column
    try:
        with HDF5Writer(filtered) as writer:
            writer.write_episodes(episodes)
    finally:
        writer_module.deflate_level = real
    with h5py.File(direct, "r") as a, h5py.File(filtered, "r") as b:
        for name in ("goal", keys.PIXELS):
            dset = a[name]
            assert writer_module.deflate_level(dset) == writer_module.GZIP_LEVEL
            np.testing.assert_array_equal(dset[:], b[name][:])
            for row in range(dset.shape[0]):
                mask, chunk = dset.id.read_direct_chunk((row, 0, 0, 0))
                assert mask == 0 and zlib.decompress(chunk) == dset[row].tobytes()


def test_a_row_equal_to_the_one_before_is_compressed_once(tmp_path, synth, monkeypatch):
    import zlib

    calls, real = [], zlib.compress

    def compress(data, level):
        calls.append(level)
        return real(data, level)

    monkeypatch.setattr(writer_module.zlib, "compress", compress)
    with HDF5Writer(tmp_path / "goal.h5") as writer:
        writer.write_episodes(_episodes_with_a_goal(synth, lengths=(4, 3)))
    # pixels: 7 different rows; goal: one run of 4 equal rows, one of 3
    assert len(calls) == 7 + 2 and set(calls) == {writer_module.GZIP_LEVEL}
    with h5py.File(tmp_path / "goal.h5", "r") as f:
        assert (f["goal"][:4] == f[keys.PIXELS][3]).all() and (f["goal"][4:] == f[keys.PIXELS][6]).all()


def _deflate_in_child(rows, conn):  # pragma: no cover - runs in a forked child
    conn.send(writer_module._deflate(rows, 4))
    conn.close()


def test_a_large_commit_is_compressed_on_two_threads_to_the_same_bytes(monkeypatch):
    """Half the rows of a large commit are compressed by a helper thread: the chunks are the ones
    a single thread makes, in order, repeated rows shared; a forked child gets a helper of its own."""
    import threading
    import zlib

    rng = np.random.default_rng(0)
    rows = rng.integers(0, 4, (9, 24, 24, 3), dtype=np.uint8)
    rows[4] = rows[3]  # a repeated row, at the split
    serial = [zlib.compress(r.tobytes(), 4) for r in rows]
    serial[4] = serial[3]
    threads = []
    real = writer_module._compress

    def compress(batch, level):
        threads.append(threading.current_thread().name)
        return real(batch, level)

    monkeypatch.setattr(writer_module, "_compress", compress)
    monkeypatch.setattr(writer_module, "PARALLEL_DEFLATE_BYTES", rows[0].nbytes * 2)
    out = writer_module._deflate(rows, 4)
    assert out == serial and out[4] is out[3]
    assert sorted(name.startswith("swm-deflate") for name in threads) == [False, True]  # this thread and the helper
    parent, child = multiprocessing.get_context("fork").Pipe()
    proc = multiprocessing.get_context("fork").Process(target=_deflate_in_child, args=(rows, child))
    proc.start()
    assert parent.poll(30) and parent.recv() == serial
    proc.join()
    monkeypatch.setattr(writer_module, "PARALLEL_DEFLATE_BYTES", 1 << 60)
    threads.clear()
    assert writer_module._deflate(rows, 4) == serial and len(threads) == 1  # a small commit: one thread


@pytest.mark.parametrize(
    ("storage", "level"),
    [
        (dict(chunks=(1, 24, 24, 3), compression="gzip", compression_opts=9), 9),
        (dict(chunks=(1, 24, 24, 3), compression="gzip", shuffle=True), None),  # two filters
        (dict(chunks=(2, 24, 24, 3), compression="gzip"), None),  # two rows per chunk
        (dict(chunks=(1, 24, 24, 3), compression="lzf"), None),
        (dict(chunks=(1, 24, 24, 3)), None),
    ],
)
def test_chunks_are_written_directly_only_for_one_row_gzip_columns(tmp_path, synth, storage, level):
    """Columns of files made by other programs keep working: those that are not one deflated row
    per chunk go through HDF5's filters, and every one reads back what was appended."""
    path = tmp_path / "foreign.h5"
    first = synth(0, 3, IMAGE)
    with h5py.File(path, "w", libver="latest") as f:
        for name, value in first.items():
            opts = storage if name == keys.PIXELS else {}
            f.create_dataset(name, data=value, maxshape=(None, *value.shape[1:]), **opts)
        f.create_dataset(keys.EP_LEN, data=np.array([3], np.int32), maxshape=(None,))
        f.create_dataset(keys.EP_OFFSET, data=np.array([0], np.int64), maxshape=(None,))
    with HDF5Writer(path) as writer:
        writer.write_episodes([synth(1, 4, IMAGE)])
    with h5py.File(path, "r") as f:
        assert writer_module.deflate_level(f[keys.PIXELS]) == level
        np.testing.assert_array_equal(f[keys.PIXELS][3:], synth(1, 4, IMAGE)[keys.PIXELS])
        np.testing.assert_array_equal(f[keys.PIXELS][:3], first[keys.PIXELS])

"""The last raw errors of the dataset files: truncated and cut-off files, a full disk while taking
the writer lock, bit flips in the raw chunks of files with Fletcher-32 (as an earlier version wrote
them; row checksums, which replace it, are in test_row_checksums.py), and a dataset name ending in '/'."""

from __future__ import annotations

import errno
import os

import h5py
import numpy as np
import pytest

from stable_worldmodel import keys
from stable_worldmodel.data import (
    HDF5Dataset,
    _checksum,
    _lock,
    _superblock,
    load_dataset,
    writer,
)
from stable_worldmodel.data.utils import dataset_file, resolve_dataset_path
from stable_worldmodel.data.writer import HDF5Writer
from stable_worldmodel.errors import ConfigError, DatasetFormatError, DiskFullError


def _many_columns(synth, ep: int, length: int) -> dict[str, np.ndarray]:
    """An episode with 20 columns: the root group then keeps its links in a fractal heap."""
    episode = synth(ep, length)
    for k in range(15):
        episode[f"extra_{k}"] = np.full((length, 2), k, np.float32)
    return episode


# -- truncated files --------------------------------------------------------------------------
def test_file_truncated_at_4096_bytes_names_the_file_and_the_truncation(tmp_path, synth):
    path = tmp_path / "cut.h5"
    with HDF5Writer(path) as w:
        w.write_episodes([_many_columns(synth, e, 5) for e in range(3)])
    size = path.stat().st_size
    path.write_bytes(path.read_bytes()[:4096])  # was: RuntimeError "Link iteration failed" from sorted(f)
    for open_it in (lambda: HDF5Dataset(path), lambda: load_dataset(str(path)), lambda: HDF5Writer(path)):
        with pytest.raises(DatasetFormatError, match=rf"cut\.h5.*truncated \(4096 bytes of the {size}") as err:
            open_it()
        assert not isinstance(err.value.__cause__, DatasetFormatError)


@pytest.mark.parametrize("size", [8, 11, 30])
def test_file_cut_inside_its_superblock(tmp_path, size):
    path = tmp_path / "sig.h5"
    path.write_bytes(_superblock.SIGNATURE + bytes([3, 8, 8, 0]) + bytes(size))
    path.write_bytes(path.read_bytes()[:size])  # the 8-byte signature alone: was IndexError in needs_repair
    assert not _superblock.needs_repair(path)
    for open_it in (lambda: HDF5Dataset(path), lambda: load_dataset(str(path)), lambda: HDF5Writer(path)):
        with pytest.raises(
            DatasetFormatError, match=rf"sig\.h5.*truncated \({size} bytes, cut off inside its superblock"
        ):
            open_it()


# -- a full disk while taking the writer lock -------------------------------------------------
def _failing_pwrite(monkeypatch, code: int) -> list[int]:
    fds = []

    def pwrite(fd, data, offset):
        fds.append(fd)
        raise OSError(code, os.strerror(code))

    monkeypatch.setattr(_lock.os, "pwrite", pwrite)
    return fds


@pytest.mark.parametrize("code", [errno.ENOSPC, errno.EDQUOT, errno.EFBIG])
def test_disk_full_while_locking_raises_disk_full_and_releases(tmp_path, monkeypatch, code):
    path = tmp_path / "d.h5"
    fds = _failing_pwrite(monkeypatch, code)
    with pytest.raises(DiskFullError, match=r"WriterLock requires room to write the lock file .*\.d\.h5\.lock") as err:
        HDF5Writer(path)
    assert isinstance(err.value, OSError)
    monkeypatch.undo()
    with pytest.raises(OSError, match="Bad file descriptor"):
        os.fstat(fds[0])  # closed
    assert not _lock.lock_path(path).exists()
    assert str(_lock.lock_path(path).resolve()) not in _lock._held
    with HDF5Writer(path) as w:  # the same process takes it again
        w.write_episodes([{keys.STATE: np.zeros((2, 2))}])


def test_other_io_error_while_locking_stays_an_os_error_and_releases(tmp_path, monkeypatch):
    path = tmp_path / "d.h5"
    _failing_pwrite(monkeypatch, errno.EIO)
    with pytest.raises(OSError) as err:
        _lock.WriterLock(path).acquire()
    assert err.value.errno == errno.EIO and not isinstance(err.value, DiskFullError)
    monkeypatch.undo()
    assert not _lock.lock_path(path).exists()
    with _lock.WriterLock(path):
        pass


# -- Fletcher-32 on raw chunks (files of an earlier version) ------------------------------------
@pytest.fixture
def checksummed(monkeypatch):
    """Write files as the earlier ``writer.CHECKSUM_RAW = True`` did: Fletcher-32 on every raw
    chunk, no row checksums. Ours still read, append to and repair them."""
    real = writer.column_storage

    def storage(row_shape, dtype):
        out = real(row_shape, dtype)
        return out if out.get("compression") else {**out, "fletcher32": True}

    monkeypatch.setattr(writer, "column_storage", storage)
    defaults = {**writer.HDF5Writer.__init__.__kwdefaults__, "checksum": False}
    monkeypatch.setattr(writer.HDF5Writer.__init__, "__kwdefaults__", defaults)


def _flip(path, column: str, chunk: int = 0, at: int = 0) -> None:
    with h5py.File(path) as f:
        info = f[column].id.get_chunk_info(chunk)
    raw = bytearray(path.read_bytes())
    raw[info.byte_offset + at] ^= 0x04
    path.write_bytes(bytes(raw))


def test_fletcher32_raw_columns_catch_a_bit_flip(make_h5, checksummed):
    path = make_h5((5, 7, 4), name="flip")
    with h5py.File(path) as f:
        assert f[keys.STATE].fletcher32 and f[keys.STATE].compression is None
        assert f[keys.EP_LEN].fletcher32 and not any(name.startswith("checksum:") for name in f)
        good = f[keys.STATE][:]
    _flip(path, keys.STATE, at=8 * 2 * 6 + 3)  # row 6 (episode 1), committed
    ds = HDF5Dataset(path, preload=False)
    np.testing.assert_array_equal(
        ds.get_col_data(keys.ACTION)[:3], HDF5Dataset(path, keys_to_load=[keys.ACTION]).get_col_data(keys.ACTION)[:3]
    )
    with pytest.raises(
        DatasetFormatError, match=r"checksums hold, got a damaged chunk in rows .* of column 'state' of .*flip\.h5"
    ):
        ds.get_col_data(keys.STATE)
    with pytest.raises(DatasetFormatError, match="column 'state'"):
        HDF5Dataset(path)  # preloading reads it at construction
    assert good[6].tolist() == [1.0, 1.0]


def test_bit_flip_in_a_checksummed_index_names_the_file(make_h5, checksummed):
    path = make_h5((5, 7, 4), name="index")
    _flip(path, keys.EP_LEN, at=1)
    with pytest.raises(DatasetFormatError, match=r"index\.h5, which is damaged or truncated"):
        HDF5Dataset(path)


def test_checksummed_file_appends_resumes_and_reads_back(tmp_path, synth, checksummed):
    path = tmp_path / "append.h5"
    lengths = (3, 4, 5, 4)
    with HDF5Writer(path) as w:  # SWMR, raw chunks filled over several commits, gzip-compressed images
        for e in range(3):
            w.write_episodes([synth(e, lengths[e], (24, 24))], next_seed=e + 1)
    with HDF5Writer(path) as w:
        w.write_episodes([synth(3, lengths[3], (24, 24))], next_seed=4)
    ds = HDF5Dataset(path, preload=False)
    for col in (keys.STATE, keys.PIXELS, keys.STEP_IDX):
        expected = np.concatenate([synth(e, n, (24, 24))[col] for e, n in enumerate(lengths)])
        np.testing.assert_array_equal(ds.get_col_data(col), expected)
    with h5py.File(path) as f:
        assert f[keys.STATE].fletcher32 and f[keys.PIXELS].compression == "gzip"


def test_chunk_torn_by_a_killed_commit_is_resealed_when_resumed(tmp_path, synth, checksummed):
    """A kill in the middle of the pwrite that rewrites a raw chunk: its first page new, its checksum old."""
    path = tmp_path / "torn.h5"
    w = HDF5Writer(path)
    w.write_episodes([synth(0, 5)])
    before = path.read_bytes()
    chunk = w._file[keys.STATE].id.get_chunk_info(0)
    w.write_episodes([synth(1, 7)])  # rewrites the chunk in place (same address and size)
    assert w._file[keys.STATE].id.get_chunk_info(0) == chunk
    after = path.read_bytes()
    w.close()
    torn = bytearray(before)
    torn[chunk.byte_offset : chunk.byte_offset + 4096] = after[chunk.byte_offset : chunk.byte_offset + 4096]
    path.write_bytes(bytes(torn))
    with pytest.raises(DatasetFormatError, match="column 'state'"):
        HDF5Dataset(path)
    with HDF5Writer(path) as w:  # the resume re-seals it; the committed episode is intact
        assert w.num_episodes == 1
        w.write_episodes([synth(1, 7)])
    ds = HDF5Dataset(path)
    np.testing.assert_array_equal(
        ds.get_col_data(keys.STATE), np.concatenate([synth(0, 5)[keys.STATE], synth(1, 7)[keys.STATE]])
    )


def test_reader_reads_again_a_chunk_caught_mid_rewrite(make_h5, monkeypatch):
    """A live writer rewrites the last raw chunk in place: a read overlapping it sees a torn chunk once."""
    from stable_worldmodel.data import hdf5

    path = make_h5((5, 7))
    real, calls = hdf5.HDF5Dataset._read_rows, []

    def torn_once(self, col, start, stop):
        calls.append(col)
        if len(calls) == 1:
            raise OSError("Can't synchronously read data (filter returned failure during read)")
        return real(self, col, start, stop)

    monkeypatch.setattr(hdf5.HDF5Dataset, "_read_rows", torn_once)
    ds = HDF5Dataset(path, preload=False)
    assert ds.get_col_data(keys.STATE).shape == (12, 2) and len(calls) == 2


@pytest.mark.parametrize("n", [2, 7, 720, 722, 4096])
def test_fletcher32_matches_hdf5(tmp_path, n):
    data = np.random.default_rng(n).integers(0, 256, n, dtype=np.uint8)
    with h5py.File(tmp_path / "f.h5", "w") as f:
        dset = f.create_dataset("x", data=data, chunks=(n,), fletcher32=True)
        _, raw = dset.id.read_direct_chunk((0,))
    assert raw[-4:] == _checksum.fletcher32(data.tobytes()).to_bytes(4, "little")


# -- a dataset name ending in '/' -------------------------------------------------------------
def test_record_dataset_refuses_a_name_ending_in_a_slash(tmp_path):
    from stable_worldmodel.world.recording import record_dataset

    with pytest.raises(ConfigError, match=r"got 'x/'.*did you mean 'x'\?"):
        record_dataset(None, "x/", episodes=1, cache_dir=tmp_path)
    with pytest.raises(ConfigError, match=r"got 'a/b/'.*did you mean 'a/b'\?"):
        dataset_file("a/b/", tmp_path)
    assert list(tmp_path.iterdir()) == []
    assert dataset_file("a/b", tmp_path) == tmp_path / "a" / "b.h5"


def test_reading_a_name_ending_in_a_slash(tmp_path, synth):
    with pytest.raises(ConfigError, match=r"got 'x/'; did you mean 'x'\?"):
        HDF5Dataset("x/", cache_dir=tmp_path)
    for shard in range(2):  # the folder of a sharded dataset may be named with its slash
        with HDF5Writer(tmp_path / "x" / f"shard_{shard:05d}.h5") as w:
            w.write_episodes([synth(shard, 3)])
    assert resolve_dataset_path("x/", tmp_path) == tmp_path / "x"
    assert HDF5Dataset("x/", cache_dir=tmp_path).num_episodes == 2

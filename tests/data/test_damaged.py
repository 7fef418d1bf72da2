"""Damaged or structurally wrong files: a DatasetFormatError naming the file and the fault, within 2 seconds."""

from __future__ import annotations

import os
import time

import h5py
import numpy as np
import pytest

from stable_worldmodel import keys
from stable_worldmodel.data import HDF5Dataset, dataset_info
from stable_worldmodel.errors import DatasetFormatError

FAST_S = 2.0


@pytest.fixture
def base(make_h5, tmp_path, monkeypatch):
    """A finished recording in the cache: 6 episodes of 5 rows, 24x24 images (compressed, one row per chunk)."""
    monkeypatch.setenv("STABLEWM_HOME", str(tmp_path))
    return make_h5((5,) * 6, name="base", image=(24, 24))


def _read_all(path):
    """Everything a user does with a dataset: open, index, items, episodes, info."""
    ds = HDF5Dataset(path, preload=False)
    for i in range(len(ds)):
        ds[i]
    for e in range(ds.num_episodes):
        ds.load_episode(e)
    ds.get_col_data(keys.PIXELS)
    ds.close()
    return dataset_info(path.stem)


def _expect_fast_error(path, match=None):
    t0 = time.monotonic()
    with pytest.raises(DatasetFormatError, match=match) as err:
        _read_all(path)
    assert time.monotonic() - t0 < FAST_S
    assert path.name in str(err.value)
    return err


@pytest.mark.parametrize("fraction", [0.05, 0.3, 0.6, 0.95])
def test_truncated_file(base, fraction):
    raw = base.read_bytes()
    base.write_bytes(raw[: int(len(raw) * fraction)])
    _expect_fast_error(base)


def _metadata_positions(path):
    """Byte positions inside HDF5 metadata: the superblock and each dataset's object header."""
    positions = [20]
    with h5py.File(path) as f:
        for name in (keys.EP_LEN, keys.EP_OFFSET, keys.PIXELS, keys.STATE):
            positions.append(h5py.h5o.get_info(f[name].id).addr + 9)
    return positions


@pytest.mark.parametrize("which", range(5))
def test_bit_flip_in_metadata(base, which):
    pos = _metadata_positions(base)[which]
    raw = bytearray(base.read_bytes())
    raw[pos] ^= 0x10
    base.write_bytes(bytes(raw))
    _expect_fast_error(base)


def test_bit_flip_in_a_compressed_chunk_names_the_rows(base):
    with h5py.File(base) as f:
        chunk = f[keys.PIXELS].id.get_chunk_info(7)
    raw = bytearray(base.read_bytes())
    raw[chunk.byte_offset + chunk.size // 2] ^= 0xFF
    base.write_bytes(bytes(raw))
    _expect_fast_error(base, match="rows .* of column 'pixels'")


def _rewrite(path, name, data=None, group=False):
    with h5py.File(path, "a") as f:
        del f[name]
        if group:
            f.create_group(name)
        else:
            f[name] = data


STRUCTURAL = {
    "ep_len scalar": (keys.EP_LEN, np.int32(5), "1-D integer dataset 'ep_len'"),
    "ep_len 2-D": (keys.EP_LEN, np.full((6, 2), 5, np.int32), "1-D integer dataset 'ep_len'"),
    "ep_len float": (keys.EP_LEN, np.full(6, 5.0), "1-D integer dataset 'ep_len'"),
    "ep_len zero": (
        keys.EP_LEN,
        np.array([5, 5, 0, 5, 5, 5], np.int32),
        r"positive episode lengths, got ep_len\[2\] = 0",
    ),
    "ep_len negative": (keys.EP_LEN, np.array([5, -5, 5, 5, 5, 5], np.int32), r"ep_len\[1\] = -5"),
    "ep_len too long": (keys.EP_LEN, np.array([5, 5, 5, 5, 5, 50], np.int32), "75 rows in every column"),
    "offset negative": (keys.EP_OFFSET, np.array([-1, 5, 10, 15, 20, 25]), "non-negative offsets"),
    "offsets overlap": (keys.EP_OFFSET, np.array([0, 5, 8, 15, 20, 25]), "episode 2 at row 8 inside episode 1"),
    "offsets out of order": (keys.EP_OFFSET, np.array([0, 5, 10, 25, 20, 15]), "episode 4 at row 20 inside episode 3"),
    "offset out of range": (keys.EP_OFFSET, np.array([0, 5, 10, 15, 20, 900]), "905 rows in every column"),
    "too few offsets": (keys.EP_OFFSET, np.array([0, 5, 10]), "3 offsets for 6 episodes"),
    "byte-string column": (keys.STATE, np.array([b"x"] * 30), "numeric columns.*'state'"),
    "short column": (keys.STATE, np.zeros((20, 2)), "30 rows in every column.*got 20 in 'state'"),
}


@pytest.mark.parametrize("case", STRUCTURAL)
def test_structurally_wrong_file(base, case):
    name, data, match = STRUCTURAL[case]
    _rewrite(base, name, data)
    _expect_fast_error(base, match=match)


def test_index_that_is_a_group_or_missing(base):
    _rewrite(base, keys.EP_LEN, group=True)
    _expect_fast_error(base, match="'ep_len'.*got Group")
    with h5py.File(base, "a") as f:
        del f[keys.EP_LEN]
    _expect_fast_error(base, match="'ep_len'.*got missing")


def test_not_hdf5_at_all(base):
    base.write_bytes(b"this is not an HDF5 file" * 100)
    _expect_fast_error(base, match="readable HDF5 file")


def test_folder_or_fifo_named_like_a_dataset(tmp_path):
    (tmp_path / "dir.h5").mkdir()
    with pytest.raises(DatasetFormatError, match="dir.h5'?, which is a folder"):
        HDF5Dataset(tmp_path / "dir.h5")
    os.mkfifo(tmp_path / "pipe.h5")
    t0 = time.monotonic()
    with pytest.raises(DatasetFormatError, match="pipe.h5'?, which is a FIFO"):
        HDF5Dataset(tmp_path / "pipe.h5")
    assert time.monotonic() - t0 < FAST_S


def test_swm_show_dataset_reports_a_damaged_file_without_traceback(base, swm, error_line):
    raw = base.read_bytes()
    base.write_bytes(raw[: len(raw) // 2])
    t0 = time.monotonic()
    result = swm("show", "dataset", "base")
    assert result.exit_code != 0 and time.monotonic() - t0 < FAST_S
    assert "base.h5" in error_line(result) and "Traceback" not in result.output

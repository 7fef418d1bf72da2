"""HDF5Writer: layout, validation, resume, loud failures, superblock sealing."""

from __future__ import annotations

import h5py
import numpy as np
import pytest

from stable_worldmodel import keys
from stable_worldmodel.data import _superblock
from stable_worldmodel.data.writer import NEXT_SEED_ATTR, HDF5Writer
from stable_worldmodel.errors import DatasetFormatError




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
        assert f[keys.PIXELS].compression == "gzip"


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


def test_resume_drops_uncommitted_rows(make_h5, synth):
    path = make_h5((3, 4))
    with h5py.File(path, "a") as f:  # rows of an episode that never got its ep_len entry
        for name in (keys.PIXELS, keys.ACTION, keys.STATE, keys.STEP_IDX, keys.TERMINATED):
            f[name].resize(f[name].shape[0] + 5, axis=0)
    with HDF5Writer(path) as w:
        w.write_episodes([synth(2, 2)])
    with h5py.File(path, "r") as f:
        assert f[keys.STATE].shape[0] == 9
        assert f[keys.STATE][7:, 0].tolist() == [2.0, 2.0]


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
    real = h5py.Dataset.__setitem__

    def full(self, key, value):
        if self.name == "/" + keys.PIXELS:
            raise OSError(28, "No space left on device")
        return real(self, key, value)

    monkeypatch.setattr(h5py.Dataset, "__setitem__", full)
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
    w.write_episodes([synth(0, 3)])
    assert not _superblock.needs_repair(path)
    with h5py.File(path, "r", locking=False) as f:  # a plain reader while the writer holds it
        assert f[keys.EP_LEN][:].tolist() == [3]
    w.write_episodes([synth(1, 2)])
    w.close()
    with h5py.File(path, "r") as f:
        assert f[keys.EP_LEN][:].tolist() == [3, 2]


def test_repair_clears_flags_left_by_a_killed_writer(make_h5):
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

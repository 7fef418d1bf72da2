"""HDF5Dataset: windows, frameskip, keys, caching, episodes, errors, DataLoader workers."""

from __future__ import annotations

import numpy as np
import pytest
import torch

from stable_worldmodel import keys
from stable_worldmodel.data import HDF5Dataset
from stable_worldmodel.errors import UnknownNameError

LENGTHS = (5, 7, 4)


def expected_window(synth, ep, start, num_steps, frameskip):
    full = synth(ep, LENGTHS[ep])
    span = num_steps * frameskip
    out = {k: v[start : start + span : frameskip] for k, v in full.items()}
    out[keys.ACTION] = full[keys.ACTION][start : start + span].reshape(num_steps, -1)
    out[keys.PIXELS] = out[keys.PIXELS].transpose(0, 3, 1, 2)
    return out


@pytest.mark.parametrize("preload", [True, False])
@pytest.mark.parametrize("num_steps, frameskip", [(1, 1), (2, 1), (3, 1), (2, 2), (1, 3)])
def test_every_window_matches_the_written_rows(make_h5, synth, num_steps, frameskip, preload):
    ds = HDF5Dataset(make_h5(LENGTHS), num_steps=num_steps, frameskip=frameskip, preload=preload)
    span = num_steps * frameskip
    starts = [(e, s) for e, n in enumerate(LENGTHS) for s in range(n - span + 1)]
    assert len(ds) == len(starts)
    for idx, (ep, start) in enumerate(starts):
        item = ds[idx]
        want = expected_window(synth, ep, start, num_steps, frameskip)
        assert set(item) == set(want)
        for k, v in want.items():
            assert isinstance(item[k], torch.Tensor)
            np.testing.assert_array_equal(item[k].numpy(), v, err_msg=k)
    assert ds[-1][keys.STATE][0, 0] == len(LENGTHS) - 1
    with pytest.raises(IndexError):
        ds[len(ds)]


def test_action_shape_and_image_layout(make_h5):
    ds = HDF5Dataset(make_h5(LENGTHS), num_steps=2, frameskip=3)
    item = ds[0]
    assert item[keys.ACTION].shape == (2, 6)
    assert item[keys.PIXELS].shape == (2, 3, 8, 8) and item[keys.PIXELS].dtype == torch.uint8


def test_keys_to_load_cache_and_transform(make_h5, synth):
    path = make_h5(LENGTHS)
    ds = HDF5Dataset(
        path,
        num_steps=2,
        keys_to_load=[keys.STATE, keys.ACTION],
        keys_to_cache=[keys.STATE],
        transform=lambda item: {**item, "n": len(item)},
    )
    item = ds[4]  # episode 1, start 0
    assert set(item) == {keys.STATE, keys.ACTION, "n"}
    np.testing.assert_array_equal(item[keys.STATE].numpy(), synth(1, 7)[keys.STATE][:2])


def test_unknown_key_and_missing_file(make_h5, tmp_path):
    path = make_h5(LENGTHS)
    with pytest.raises(KeyError, match="state") as err:
        HDF5Dataset(path, keys_to_load=["stat"])
    assert isinstance(err.value, UnknownNameError)
    with pytest.raises(FileNotFoundError, match="nope.h5"):
        HDF5Dataset("nope", cache_dir=tmp_path)


def test_name_in_cache_dir(make_h5, tmp_path):
    make_h5(LENGTHS, name="mine")
    assert HDF5Dataset("mine", cache_dir=tmp_path).num_episodes == 3


def test_episode_access(make_h5, synth):
    ds = HDF5Dataset(make_h5(LENGTHS))
    assert ds.lengths.tolist() == list(LENGTHS) and ds.offsets.tolist() == [0, 5, 12]
    assert ds.load_episode(1)[keys.STATE].shape == (7, 2)
    chunks = ds.load_chunk([0, 2], [1, 0], [3, 4])
    np.testing.assert_array_equal(chunks[1][keys.STEP_IDX].numpy(), [0, 1, 2, 3])
    np.testing.assert_array_equal(ds.get_col_data(keys.STEP_IDX), np.concatenate([np.arange(n) for n in LENGTHS]))
    row = ds.get_row_data(6)
    assert row[keys.STATE].tolist() == [1.0, 1.0]
    assert ds.get_row_data([0, 6])[keys.STATE].shape == (2, 2)
    assert set(ds.column_names) == {keys.PIXELS, keys.ACTION, keys.STATE, keys.STEP_IDX, keys.TERMINATED}


def test_dataloader_with_workers(make_h5):
    ds = HDF5Dataset(make_h5(LENGTHS), num_steps=2)
    ds[0]  # open in the parent first: workers must open their own handle
    loader = torch.utils.data.DataLoader(ds, batch_size=4, num_workers=2, shuffle=False)
    batches = list(loader)
    states = torch.cat([b[keys.STATE] for b in batches])
    assert states.shape == (len(ds), 2, 2)
    np.testing.assert_array_equal(states.numpy(), np.stack([ds[i][keys.STATE].numpy() for i in range(len(ds))]))


@pytest.mark.parametrize("preload", [True, False])
@pytest.mark.parametrize("num_steps, frameskip", [(1, 1), (2, 2), (3, 1)])
def test_getitems_is_the_list_of_items(make_h5, num_steps, frameskip, preload):
    ds = HDF5Dataset(
        make_h5(LENGTHS),
        num_steps=num_steps,
        frameskip=frameskip,
        preload=preload,
        transform=lambda item: {**item, "twice": item[keys.STATE] * 2},
    )
    idx = [len(ds) - 1, 0, 3, -1, 2, 2]
    batch = ds.__getitems__(idx)
    assert len(batch) == len(idx)
    for got, i in zip(batch, idx, strict=False):
        want = ds[i]
        assert set(got) == set(want)
        for k in want:
            assert got[k].dtype == want[k].dtype and got[k].shape == want[k].shape
            torch.testing.assert_close(got[k], want[k], rtol=0, atol=0, equal_nan=True)
    assert ds.__getitems__([]) == []
    with pytest.raises(IndexError, match=str(len(ds))):
        ds.__getitems__([0, len(ds)])
    with pytest.raises(TypeError, match="ints"):
        ds.__getitems__([0.5])
    with pytest.raises(TypeError, match="ints"):
        ds[1.0]


def test_preload_defaults_to_small_datasets(make_h5, monkeypatch, synth):
    from stable_worldmodel.data import hdf5

    path = make_h5(LENGTHS)
    small = HDF5Dataset(path, keys_to_load=[keys.PIXELS, keys.STATE])
    assert set(small._cache) == {keys.PIXELS, keys.STATE}  # only the loaded columns
    monkeypatch.setattr(hdf5, "PRELOAD_BYTES", 10)
    assert HDF5Dataset(path)._cache == {}
    assert set(HDF5Dataset(path, preload=True)._cache) == set(small.stored_columns)
    lazy = HDF5Dataset(path, preload=False, keys_to_cache=[keys.PIXELS])
    assert set(lazy._cache) == {keys.PIXELS}
    # images kept in memory still read back as (N, H, W, C) rows everywhere
    want = np.concatenate([synth(e, n)[keys.PIXELS] for e, n in enumerate(LENGTHS)])
    for ds in (small, lazy, HDF5Dataset(path, preload=False)):
        np.testing.assert_array_equal(ds.get_col_data(keys.PIXELS), want)
        np.testing.assert_array_equal(ds.get_row_data(6)[keys.PIXELS], want[6])
        np.testing.assert_array_equal(ds.load_episode(1)[keys.PIXELS].numpy(), want[5:12].transpose(0, 3, 1, 2))
        assert ds[0][keys.PIXELS].is_contiguous()


def test_dataloader_batches_equal_direct_reads(make_h5):
    ds = HDF5Dataset(make_h5((30, 40)), num_steps=3, frameskip=2)
    loader = torch.utils.data.DataLoader(ds, batch_size=8, num_workers=2, shuffle=False)
    batches = list(loader)
    for k in ds.column_names:
        got = torch.cat([b[k] for b in batches])
        want = torch.stack([ds[i][k] for i in range(len(ds))])
        torch.testing.assert_close(got, want, rtol=0, atol=0, equal_nan=True)
    got.add_(1) if got.dtype != torch.bool else got.logical_not_()  # writable, no warning


@pytest.mark.parametrize("preload", [True, False])
def test_items_do_not_share_memory_with_the_cache(make_h5, preload):
    ds = HDF5Dataset(make_h5(LENGTHS), num_steps=2, preload=preload)
    before = {k: v.clone() for k, v in ds[3].items()}
    for item in (ds[3], ds.__getitems__([3, 4])[0], ds.load_episode(0), ds.load_chunk([0], 3, 5)[0]):
        for v in item.values():
            v.zero_() if v.dtype != torch.bool else v.logical_not_()
    for k, v in ds[3].items():
        torch.testing.assert_close(v, before[k], rtol=0, atol=0, equal_nan=True)


def test_plain_h5py_opens_the_file_next_to_a_dataset(make_h5):
    import h5py

    path = make_h5(LENGTHS)
    ds = HDF5Dataset(path, preload=False)
    ds[0]
    with h5py.File(path) as f, h5py.File(path, "r") as g:  # the usual inspection, in the same process
        assert f[keys.EP_LEN][:].tolist() == list(LENGTHS) == g[keys.EP_LEN][:].tolist()
    with h5py.File(path, "r") as f:  # and the other way round
        assert HDF5Dataset(path, preload=False)[0][keys.STATE].shape == (1, 2)


def test_a_new_reader_sees_episodes_committed_since_an_older_reader_opened(tmp_path, synth):
    from stable_worldmodel.data.writer import HDF5Writer

    path = tmp_path / "present.h5"
    with HDF5Writer(path) as w:
        w.write_episodes([synth(0, 3)])
    old = HDF5Dataset(path, preload=False)  # keeps the file open in this process
    assert old.num_episodes == 1 and old[0][keys.STATE].shape[0] == 1
    with HDF5Writer(path) as w:
        w.write_episodes([synth(1, 4), synth(2, 5)])
    new = HDF5Dataset(path, preload=False)
    assert new.lengths.tolist() == [3, 4, 5]
    assert new.get_col_data(keys.STATE)[:, 0].tolist() == [0] * 3 + [1] * 4 + [2] * 5
    live = HDF5Writer(path)  # still open while the script reads
    live.write_episodes([synth(3, 2)])
    assert HDF5Dataset(path).lengths.tolist() == [3, 4, 5, 2]
    live.close()
    assert old.num_episodes == 1  # a reader keeps the episodes it opened with


def test_a_strided_window_decodes_only_the_frames_it_keeps(make_h5, synth):
    """Images stored one frame per chunk (64x64 ones are) are read frame by frame: a window of 3 frames at
    frameskip 4 decodes 3 chunks, not the 12 rows it spans (nor a 1-MiB block of 85 frames around them)."""
    image = (64, 64)
    ds = HDF5Dataset(make_h5((30,), image=image), num_steps=3, frameskip=4, preload=False)
    assert ds._handle()[keys.PIXELS].chunks[0] == 1
    reads = []
    checked = ds._checked
    ds._checked = lambda shard, col, start, stop: reads.append((col, stop - start)) or checked(shard, col, start, stop)
    frames = synth(0, 30, image)[keys.PIXELS].transpose(0, 3, 1, 2)
    item = ds[5]
    np.testing.assert_array_equal(item[keys.PIXELS].numpy(), frames[5:17:4])
    assert sorted(n for col, n in reads if col == keys.PIXELS) == [1, 1, 1]
    reads.clear()
    batch = ds._batch([0, 9])
    np.testing.assert_array_equal(batch[keys.PIXELS][1].numpy(), frames[9:21:4])
    assert sum(n for col, n in reads if col == keys.PIXELS) <= 6  # frames 9 and 13 of window 1 are cached already

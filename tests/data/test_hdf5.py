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


@pytest.mark.parametrize("num_steps, frameskip", [(1, 1), (2, 1), (3, 1), (2, 2), (1, 3)])
def test_every_window_matches_the_written_rows(make_h5, synth, num_steps, frameskip):
    ds = HDF5Dataset(make_h5(LENGTHS), num_steps=num_steps, frameskip=frameskip)
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
    ds = HDF5Dataset(path, num_steps=2, keys_to_load=[keys.STATE, keys.ACTION], keys_to_cache=[keys.STATE],
                     transform=lambda item: {**item, "n": len(item)})
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

"""Folder, video, merged, concatenated and goal datasets built from a small HDF5 file."""

from __future__ import annotations

import numpy as np
import pytest

from stable_worldmodel import keys
from stable_worldmodel.data import (
    ConcatDataset,
    Dataset,
    FolderDataset,
    GoalDataset,
    HDF5Dataset,
    ImageDataset,
    MergeDataset,
    VideoDataset,
)
from stable_worldmodel.data.folder import write_folder_dataset
from stable_worldmodel.data.video_dataset import write_video_dataset
from stable_worldmodel.errors import ConfigError

LENGTHS = (5, 7, 4)


@pytest.fixture
def h5(make_h5):
    return HDF5Dataset(make_h5(LENGTHS, image=(16, 16)), num_steps=2)


def assert_same_numeric(a: Dataset, b: Dataset):
    assert len(a) == len(b)
    for i in range(len(a)):
        x, y = a[i], b[i]
        for k in (keys.STATE, keys.ACTION, keys.STEP_IDX):
            np.testing.assert_array_equal(x[k].numpy(), y[k].numpy())


def test_folder_dataset_round_trip(h5, tmp_path):
    write_folder_dataset(h5, tmp_path / "folder")
    ds = FolderDataset(tmp_path / "folder", num_steps=2)
    assert issubclass(ImageDataset, FolderDataset) and isinstance(ds, Dataset)
    assert sorted(ds.column_names) == sorted(h5.column_names)
    assert_same_numeric(ds, h5)
    diff = np.abs(ds[3][keys.PIXELS].numpy().astype(int) - h5[3][keys.PIXELS].numpy().astype(int))
    assert ds[3][keys.PIXELS].shape == (2, 3, 16, 16) and diff.max() <= 8  # JPEG is lossy


def test_video_dataset_round_trip(h5, tmp_path):
    pytest.importorskip("av")
    write_video_dataset(h5, tmp_path / "video")
    ds = VideoDataset(tmp_path / "video", num_steps=2)
    assert_same_numeric(ds, h5)
    for i in (0, 6, len(ds) - 1):
        got, want = ds[i][keys.PIXELS].numpy().astype(int), h5[i][keys.PIXELS].numpy().astype(int)
        assert got.shape == want.shape and np.abs(got - want).mean() < 4  # H.264 is lossy
    with pytest.raises(ConfigError):
        VideoDataset(tmp_path / "video", decoder="nope")


def test_directory_dataset_errors(h5, tmp_path):
    with pytest.raises(FileNotFoundError, match="does not exist"):
        FolderDataset(tmp_path / "missing")
    write_folder_dataset(h5, tmp_path / "folder")
    with pytest.raises(ValueError, match="video"):
        VideoDataset(tmp_path / "folder")


def test_merge_dataset(h5, make_h5, tmp_path):
    write_folder_dataset(h5, tmp_path / "f")
    folder = FolderDataset(tmp_path / "f", keys_to_load=[keys.STATE, keys.STEP_IDX], num_steps=2)
    merged = MergeDataset([HDF5Dataset(h5.path, keys_to_load=[keys.ACTION], num_steps=2), folder])
    assert set(merged.column_names) == {keys.ACTION, keys.STATE, keys.STEP_IDX}
    assert_same_numeric(merged, h5)
    with pytest.raises(ConfigError, match="episode lengths"):
        MergeDataset([h5, HDF5Dataset(make_h5((3, 3), name="other"))])


def test_concat_dataset(make_h5, synth):
    a = HDF5Dataset(make_h5((5, 7), name="a"), num_steps=2, frameskip=2)
    b = HDF5Dataset(make_h5((4,), name="b"), num_steps=2, frameskip=2)
    cat = ConcatDataset([a, b])
    assert cat.lengths.tolist() == [5, 7, 4] and cat.offsets.tolist() == [0, 5, 12]
    assert len(cat) == 2 + 4 + 1
    last = cat[len(cat) - 1]
    np.testing.assert_array_equal(last[keys.STATE].numpy(), synth(0, 4)[keys.STATE][0:4:2])
    np.testing.assert_array_equal(cat.get_col_data(keys.STEP_IDX), np.concatenate([np.arange(n) for n in (5, 7, 4)]))


def test_goal_dataset(h5):
    assert len(GoalDataset(h5, seed=0)) == len(h5)
    current = GoalDataset(h5, goal_probabilities=(0, 0, 1), seed=0)
    item = current[0]
    assert item[keys.goal_key(keys.PIXELS)].shape == (1, 3, 16, 16)
    np.testing.assert_array_equal(item[keys.goal_key(keys.STATE)][0].numpy(), item[keys.STATE][-1].numpy())
    future = GoalDataset(h5, goal_probabilities=(0, 1, 0), gamma=0.5, seed=0)
    for idx in range(len(h5)):
        ep, step = h5.locate(idx)
        goal = future[idx][keys.goal_key(keys.STATE)][0].numpy()
        assert goal[0] == ep and step + 1 < goal[1] + 1 <= h5.lengths[ep]  # later step, same episode
    rand = GoalDataset(h5, goal_probabilities=(1, 0, 0), seed=1)
    episodes = {int(rand[i][keys.goal_key(keys.STATE)][0, 0]) for i in range(len(h5))}
    assert len(episodes) > 1
    assert np.array_equal(rand[3][keys.goal_key(keys.STATE)], rand[3][keys.goal_key(keys.STATE)])  # seeded
    with pytest.raises(ConfigError, match="goal_probabilities"):
        GoalDataset(h5, goal_probabilities=(0.5, 0.6, 0))
    with pytest.raises(KeyError):
        GoalDataset(h5, goal_keys={"nope": "goal_nope"})


@pytest.mark.parametrize("cls_name", ["MergeDataset", "ConcatDataset"])
def test_composites_require_a_dataset(cls_name):
    from stable_worldmodel import data
    from stable_worldmodel.errors import ConfigError

    with pytest.raises(ConfigError, match=f"{cls_name} requires at least one dataset"):
        getattr(data, cls_name)([])


def test_one_image_rule_for_arrays_rows_and_batches():
    """``data.writer.is_image_column`` is the one rule; the array, rows and batch predicates apply it."""
    import torch

    from stable_worldmodel.data.dataset import image_like
    from stable_worldmodel.data.info import is_image
    from stable_worldmodel.data.writer import is_image_column
    from stable_worldmodel.planning.io import is_image as is_image_batch

    for channels in (1, 2, 3, 4, 5):
        for dtype in (np.uint8, np.float32):
            expected = channels in (1, 3, 4) and dtype is np.uint8
            shape = (6, 5, channels)
            assert is_image_column(shape, dtype) is expected
            assert is_image_column(shape, np.dtype(dtype).name) is expected
            assert is_image(np.zeros(shape, dtype)) is expected
            assert image_like(np.zeros((2, *shape), dtype)) is expected
            batch = torch.zeros((2, 1, *shape), dtype=torch.uint8 if dtype is np.uint8 else torch.float32)
            assert is_image_batch(batch) is expected

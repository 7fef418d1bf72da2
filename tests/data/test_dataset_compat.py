"""The 0.0.3 / 0.1.1 surface of the Dataset base and of the composite datasets."""

from __future__ import annotations

import numpy as np
import pytest
import torch

from stable_worldmodel import keys
from stable_worldmodel.data import ConcatDataset, Dataset, GoalDataset, HDF5Dataset, MergeDataset
from stable_worldmodel.errors import ConfigError, UnknownNameError

LENGTHS = (5, 7, 4)


class SliceDataset(Dataset):
    """A user subclass written against 0.0.3: positional base arguments and ``_load_slice``."""

    def __init__(self, lengths, frameskip=1, num_steps=1, transform=None):
        offsets = np.concatenate([[0], np.cumsum(lengths)[:-1]])
        super().__init__(np.asarray(lengths), offsets, frameskip, num_steps, transform)
        self.rows = np.arange(int(np.sum(lengths)), dtype=np.float32)

    @property
    def column_names(self):
        return ["obs", "action"]

    def _load_slice(self, ep_idx, start, end):
        g0, g1 = self.offsets[ep_idx] + start, self.offsets[ep_idx] + end
        obs = torch.from_numpy(self.rows[g0:g1][:: self.frameskip].copy())
        action = torch.from_numpy(np.stack([self.rows[g0:g1], -self.rows[g0:g1]], 1))
        steps = {"obs": obs, "action": action}
        return self.transform(steps) if self.transform else steps

    def get_col_data(self, col):
        return self.rows if col == "obs" else np.stack([self.rows, -self.rows], 1)

    def get_row_data(self, row_idx):
        return {"obs": self.rows[row_idx], "action": np.stack([self.rows, -self.rows], 1)[row_idx]}


class ReadDataset(Dataset):
    """A subclass of ours, given lengths and offsets positionally, reading through ``_read``."""

    def __init__(self, lengths, **kw):
        super().__init__(lengths, None, **kw)
        self._columns = ["x"]
        self.data = np.arange(int(np.sum(lengths)))[:, None] * np.ones((1, 3))

    def _read(self, col, start, stop):
        return self.data[start:stop]


class DatasetLike:
    """Not a Dataset at all: only the public methods the composites may use."""

    def __init__(self, lengths, base=0.0, cols=("obs",)):
        self.lengths = np.asarray(lengths)
        self.offsets = np.concatenate([[0], np.cumsum(self.lengths)[:-1]])
        self.num_steps, self.frameskip = 1, 1
        self.cols = list(cols)
        self.rows = base + np.arange(int(self.lengths.sum()), dtype=np.float64)
        self.clip_indices = [(e, s) for e, n in enumerate(self.lengths) for s in range(n)]

    @property
    def column_names(self):
        return self.cols

    def __len__(self):
        return len(self.clip_indices)

    def __getitem__(self, idx):
        ep, s = self.clip_indices[idx]
        row = self.offsets[ep] + s
        return {c: torch.tensor([self.rows[row]]) for c in self.cols}

    def load_chunk(self, episodes_idx, start, end):
        return [
            {c: torch.tensor(self.rows[self.offsets[e] + s : self.offsets[e] + t]) for c in self.cols}
            for e, s, t in zip(episodes_idx, start, end, strict=False)
        ]

    def load_episode(self, ep):
        return self.load_chunk([ep], [0], [self.lengths[ep]])[0]

    def get_col_data(self, col):
        return self.rows

    def get_row_data(self, row_idx):
        return {c: self.rows[row_idx] for c in self.cols}


def test_base_takes_lengths_and_offsets_first_as_in_003():
    ds = SliceDataset([3, 5], frameskip=2, num_steps=2)
    assert ds.lengths.tolist() == [3, 5] and ds.offsets.tolist() == [0, 3]
    assert ds.clip_indices == [(1, 0), (1, 1)] and len(ds) == 2  # windows of 4 rows fit episode 1 only
    item = ds[1]  # episode 1, start 1: rows 4..7
    assert item["obs"].tolist() == [4.0, 6.0] and item["action"].shape == (2, 4)
    assert ds.load_episode(0)["obs"].tolist() == [0.0, 2.0]  # strided by its own _load_slice, as in 0.0.3
    chunk = ds.load_chunk([1], [0], [4])[0]
    assert chunk["obs"].tolist() == [3.0, 5.0] and chunk["action"].shape == (2, 4)
    assert len(ds.__getitems__([0, 1])) == 2 and ds.get_dim("action") == 2


def test_base_keeps_keyword_use_and_rejects_the_old_positional_form():
    ds = ReadDataset([2, 3], num_steps=2)
    assert ds.offsets.tolist() == [0, 2] and ds.clip_indices == [(0, 0), (1, 0), (1, 1)]
    assert ds[2]["x"].tolist() == [[3.0] * 3, [4.0] * 3] and ds.get_dim("x") == 3
    ds.lengths = [5]  # 0.0.3 subclasses assign these attributes
    ds.offsets = [0]
    assert len(ds) == 4
    with pytest.raises(ConfigError, match="by keyword"):
        Dataset(2, 3)
    with pytest.raises(ConfigError, match="one offset per episode"):
        Dataset([2, 3], [0])


def test_clip_indices_h5_path_and_get_dim(make_h5):
    path = make_h5(LENGTHS)
    ds = HDF5Dataset(path, num_steps=2, frameskip=2)
    assert ds.h5_path == path
    assert ds.clip_indices == [(0, 0), (0, 1), (1, 0), (1, 1), (1, 2), (1, 3), (2, 0)]
    assert [ds.locate(i) for i in range(len(ds))] == ds.clip_indices
    assert ds.get_dim(keys.PIXELS) == 8 * 8 * 3 and ds.get_dim(keys.ACTION) == 2 and ds.get_dim(keys.STEP_IDX) == 1
    ds.clip_indices = [(2, 1), (0, 0)]  # assigned samples are used as given
    assert len(ds) == 2 and ds[0][keys.STATE][0].tolist() == [2.0, 1.0]
    with pytest.raises(UnknownNameError, match="not found"):
        ds.get_dim("nope")


def test_column_names_are_the_loaded_keys_as_in_003(make_h5):
    ds = HDF5Dataset(make_h5(LENGTHS), keys_to_load=[keys.STATE])
    assert ds.column_names == [keys.STATE] and keys.PIXELS in ds.stored_columns
    assert ds.get_col_data(keys.ACTION).shape == (16, 2)  # any stored column can still be read


def test_merge_and_concat_take_any_dataset_like():
    a, b = DatasetLike([2, 3], cols=("obs",)), DatasetLike([2, 3], base=100, cols=("obs", "other"))
    merged = MergeDataset([a, b])
    assert merged.keys_map == [["obs"], ["other"]] and merged.column_names == ["obs", "other"]
    assert merged[3] == {"obs": torch.tensor([3.0]), "other": torch.tensor([103.0])}
    assert merged.load_chunk([1], [0], [2])[0]["other"].tolist() == [102.0, 103.0]
    assert merged.get_row_data(4) == {"obs": 4.0, "other": 104.0} and merged.get_dim("other") == 1
    picked = MergeDataset([a, b], keys_from_dataset=[[], ["obs", "other"]])
    assert picked[0]["obs"].item() == 100.0

    cat = ConcatDataset([a, DatasetLike([4], base=50, cols=("obs", "extra"))])
    assert cat.column_names == ["obs", "extra"] and len(cat) == 9
    assert cat.lengths.tolist() == [2, 3, 4] and cat.offsets.tolist() == [0, 2, 5]
    assert cat[5]["obs"].item() == 50.0 and cat[-1]["obs"].item() == 53.0
    assert [c["obs"].tolist() for c in cat.load_chunk([2, 0], [1, 0], [3, 1])] == [[51.0, 52.0], [0.0]]
    assert cat.get_row_data(6)["obs"] == 51.0  # rows, not samples, are mapped to the members
    assert cat.get_col_data("obs").shape == (9,)
    with pytest.raises(UnknownNameError, match="not found"):
        cat.get_col_data("extra")  # missing from dataset 0: its rows would not line up


def test_composite_errors_keep_the_003_phrases(make_h5):
    for cls in (MergeDataset, ConcatDataset):
        with pytest.raises(ConfigError, match="Need at least one dataset"):
            cls([])
    with pytest.raises(UnknownNameError, match="not found"):
        MergeDataset([DatasetLike([2])], keys_from_dataset=[["nope"]])
    with pytest.raises(UnknownNameError, match="not found"):
        MergeDataset([DatasetLike([2])]).get_col_data("nope")
    ds = HDF5Dataset(make_h5(LENGTHS))
    with pytest.raises(ConfigError, match="sum to 1.0"):
        GoalDataset(ds, goal_probabilities=(0.5, 0.6, 0.0))
    with pytest.raises(UnknownNameError, match="not found"):
        GoalDataset(ds, goal_keys={"nope": "goal_nope"})


def test_goal_dataset_keeps_its_arguments_and_takes_any_dataset_like(make_h5):
    ds = HDF5Dataset(make_h5(LENGTHS), num_steps=2)
    given = (0.0, 0.0, 1.0)
    goal = GoalDataset(ds, goal_probabilities=given, seed=0)
    assert goal.goal_probabilities is given
    assert goal.episode_lengths.tolist() == list(LENGTHS) and goal.episode_offsets.tolist() == [0, 5, 12]
    item = goal[0]
    np.testing.assert_array_equal(item[keys.goal_key(keys.STATE)][0].numpy(), item[keys.STATE][-1].numpy())
    like = GoalDataset(
        DatasetLike([3, 4]), goal_probabilities=[0, 1, 0], goal_keys={"obs": "goal_obs"}, gamma=0.5, seed=1
    )
    for idx in range(len(like)):
        ep, start = like.dataset.clip_indices[idx]
        goal_row = like[idx]["goal_obs"].item()
        assert (
            like.episode_offsets[ep] + start < goal_row < like.episode_offsets[ep] + like.episode_lengths[ep]
            or start == like.episode_lengths[ep] - 1
        )
    assert (
        len(GoalDataset(MergeDataset([ds]), goal_probabilities=(1, 0, 0), seed=0)[3]) == len(ds.column_names) + 2
    )  # goal_pixels, goal_state


def test_record_video_needs_only_column_names_and_load_episode(tmp_path):
    from stable_worldmodel.data import record_video_from_dataset

    class Frames:
        column_names = ["pixels"]

        def load_episode(self, ep):
            return {"pixels": torch.full((5, 3, 8, 8), 40 * ep, dtype=torch.uint8)}

    paths = record_video_from_dataset(tmp_path, Frames(), [0, 2], max_steps=3, fps=5)
    assert [p.name for p in paths] == ["episode_0.mp4", "episode_2.mp4"] and all(p.stat().st_size for p in paths)
    with pytest.raises(KeyError, match="not found"):
        record_video_from_dataset(tmp_path, Frames(), 0, viewname="top")


def test_module_paths_of_003_and_011_import():
    from stable_worldmodel.data.dataset import FolderDataset as F1  # 0.0.3
    from stable_worldmodel.data.dataset import HDF5Dataset as H1
    from stable_worldmodel.data.dataset import VideoDataset as V1
    from stable_worldmodel.data.formats.folder import FolderDataset as F2  # 0.1.1
    from stable_worldmodel.data.formats.folder import FolderWriter
    from stable_worldmodel.data.formats.hdf5 import HDF5Dataset as H2  # noqa: F401
    from stable_worldmodel.data.formats.hdf5 import HDF5Writer  # noqa: F401 (the import is what the test checks)
    from stable_worldmodel.data.formats.video import VideoDataset as V2  # noqa: F401
    from stable_worldmodel.data.formats.video import VideoWriter  # noqa: F401 (the import is what the test checks)
    from stable_worldmodel.data.normalization import get_scaler  # noqa: F401
    from stable_worldmodel.data.utils import column_normalizer, get_cache_dir, load_dataset  # noqa: F401

    assert (F1, H1, V1) == (F2, H2, V2) and H1 is HDF5Dataset and FolderWriter.__name__ == "FolderWriter"


def test_goal_dataset_private_helpers_of_003(make_h5):
    """0.0.3's GoalDataset helpers, which research subclasses call: ``_sample_goal_kind``,
    ``_sample_random_step``, ``_sample_future_step``, ``_get_clip_info``, ``_load_single_step``."""
    ds = HDF5Dataset(make_h5(LENGTHS), num_steps=2, frameskip=2)
    goal = GoalDataset(ds, goal_probabilities=(0.2, 0.5, 0.3), gamma=0.5, seed=3)
    kinds = [goal._sample_goal_kind() for _ in range(300)]
    assert set(kinds) == {"random", "future", "current"} and 0.35 < kinds.count("future") / 300 < 0.65
    assert goal._total_steps == sum(LENGTHS) and goal._episode_cumlen.tolist() == list(np.cumsum(LENGTHS))
    for _ in range(50):
        ep, step = goal._sample_random_step()
        assert 0 <= step < LENGTHS[ep]
        ep, fut = goal._sample_future_step(1, 2)
        assert ep == 1 and fut > 2 and (fut - 2) % 2 == 0 and fut <= LENGTHS[1] - 1
    assert goal._sample_future_step(0, LENGTHS[0] - 1) == (0, LENGTHS[0] - 1)  # nothing left: the step itself
    assert goal._get_clip_info(0) == (0, 0)
    row = goal._load_single_step(1, 3)
    np.testing.assert_array_equal(row[keys.STATE].numpy(), ds.get_col_data(keys.STATE)[LENGTHS[0] + 3 : LENGTHS[0] + 4])

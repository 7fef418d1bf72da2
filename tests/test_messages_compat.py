"""Phrases of release 0.0.3's error messages that user code matches on stay inside our typed messages."""

from __future__ import annotations

import numpy as np
import pytest

import stable_worldmodel as swm
from stable_worldmodel.errors import SWMError


def _goal_dataset_bad_probabilities(tmp_path):
    from stable_worldmodel.data import GoalDataset

    GoalDataset(None, goal_probabilities=(0.5, 0.5))


def _rgb_box_without_channels(tmp_path):
    swm.spaces.RGBBox(shape=(4,))


def _constraint_never_satisfied(tmp_path):
    swm.spaces.Box(
        low=np.zeros(2), high=np.ones(2), init_value=np.zeros(2, np.float32), constrain_fn=lambda x: False
    ).sample()


def _merge_nothing(tmp_path):
    from stable_worldmodel.data import MergeDataset

    MergeDataset([])


def _missing_dataset(tmp_path):
    from stable_worldmodel.data import HDF5Dataset

    HDF5Dataset(tmp_path / "nothing.h5")


@pytest.mark.parametrize(
    ("make_error", "phrase"),
    [
        (_goal_dataset_bad_probabilities, "3-tuple"),
        (_goal_dataset_bad_probabilities, "sum to 1.0"),
        (_rgb_box_without_channels, "channel of size 3"),
        (_constraint_never_satisfied, "constrain_fn not satisfied"),
        (_merge_nothing, "Need at least one dataset"),
        (_missing_dataset, "not found"),
    ],
)
def test_phrase_kept(make_error, phrase, tmp_path):
    with pytest.raises(Exception) as err:  # noqa: PT011 - the class is checked below
        make_error(tmp_path)
    assert phrase in str(err.value)
    assert isinstance(err.value, (SWMError, RuntimeError, FileNotFoundError))

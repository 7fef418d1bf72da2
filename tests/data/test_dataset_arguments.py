"""Bad arguments to the datasets: typed errors that name the value and what is accepted."""

from __future__ import annotations

import pytest

from stable_worldmodel import keys
from stable_worldmodel.data import HDF5Dataset
from stable_worldmodel.errors import ArgumentTypeError, ConfigError, UnknownNameError


@pytest.fixture
def path(make_h5):
    return make_h5((5, 7, 4))


@pytest.mark.parametrize(
    ("kwargs", "error", "match"),
    [
        (
            dict(keys_to_load="pixels"),
            ConfigError,
            r"keys_to_load to be a list of column names, got the string 'pixels'; write \['pixels'\]",
        ),
        (dict(keys_to_load=[]), ConfigError, "keys_to_load to be a non-empty list"),
        (dict(keys_to_load=["pixel"]), UnknownNameError, "'pixel'.*pixels"),
        (
            dict(num_steps=8),
            ConfigError,
            r"num_steps \* frameskip <= the longest episode \(7 rows\), got num_steps=8 \* frameskip=1 = 8",
        ),
        (dict(num_steps=3, frameskip=3), ConfigError, "= 9: no sample fits"),
        (dict(transform=5), ConfigError, "transform to be a callable"),
        (dict(num_steps=0), ConfigError, "num_steps to be an integer >= 1"),
        (dict(frameskip=1.5), ConfigError, "frameskip to be an integer >= 1"),
    ],
)
def test_constructor_arguments(path, kwargs, error, match):
    with pytest.raises(error, match=match):
        HDF5Dataset(path, **kwargs)


@pytest.mark.parametrize("index", ["a", 1.5, None, True])
def test_non_int_indices(path, index):
    ds = HDF5Dataset(path)
    with pytest.raises(ArgumentTypeError, match="indices must be ints"):
        ds[index]
    with pytest.raises(ArgumentTypeError, match="load_episode requires an int episode index"):
        ds.load_episode(index)
    assert isinstance(ArgumentTypeError("x"), TypeError)  # still what Python code expects from a bad index


def test_longest_episode_exactly_one_window_is_fine(path):
    ds = HDF5Dataset(path, num_steps=7)
    assert len(ds) == 1 and ds[0][keys.STATE].shape[0] == 7

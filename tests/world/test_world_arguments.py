"""Every bad argument to World and its loops gets a typed error naming the value, before any work starts."""

from __future__ import annotations

import os

import numpy as np
import pytest

import stable_worldmodel as swm
from stable_worldmodel import keys
from stable_worldmodel.errors import ConfigError, UnknownNameError
from stable_worldmodel.policy import RandomPolicy

TOY = "swm/Toy-v0"


def world(**kwargs):
    w = swm.World(
        TOY, num_envs=2, image_shape=(16, 16), max_episode_steps=3, verbose=0, vectorization_mode="sync", **kwargs
    )
    w.set_policy(RandomPolicy(seed=0))
    return w


@pytest.mark.parametrize("shape", ["64", (64.7, 32.2), (64, 64, 3), (True, True), (0, 8), 64])
def test_image_shape(shape):
    with pytest.raises(ConfigError, match=r"World image_shape requires an \(H, W\) pair of positive integers"):
        swm.World(TOY, num_envs=1, image_shape=shape, verbose=0)


def test_image_shape_with_channels_says_to_drop_them():
    with pytest.raises(ConfigError, match=r"give only \(H, W\)"):
        swm.World(TOY, num_envs=1, image_shape=(64, 64, 3), verbose=0)


def test_unknown_env_kwarg_names_the_accepted_ones():
    with pytest.raises(UnknownNameError, match=r"keyword argument of swm/Toy-v0 \(ToyEnv\) 'render_sise'.*render_size"):
        world(render_sise=3)


BAD_SEEDS = ["3", 1.5, -1, True, 2**40]


@pytest.mark.parametrize("seed", BAD_SEEDS + [[1, 2]])
def test_world_seed(seed):
    with pytest.raises(ConfigError, match=r"World requires seed to be an int in \[0, 2\*\*32\)"):
        world(seed=seed)


@pytest.mark.parametrize("seed", BAD_SEEDS + [[1, "a"], [1, 2, 3]])
def test_reset_seed(seed):
    with pytest.raises(ConfigError, match="World.reset requires"):
        world().reset(seed=seed)


def test_reset_seed_list_with_one_seed_per_env_is_fine():
    w = world()
    w.reset(seed=[4, 9])
    assert w.infos[keys.STATE].shape[0] == 2


@pytest.mark.parametrize("seed", BAD_SEEDS + [[1, 2]])
def test_evaluate_seed(seed):
    with pytest.raises(ConfigError, match="World.evaluate requires seed"):
        world().evaluate(episodes=1, seed=seed)


@pytest.mark.parametrize("seed", BAD_SEEDS + [[1, 2]])
def test_record_dataset_seed(seed, tmp_path):
    with pytest.raises(ConfigError, match="World.record_dataset requires seed"):
        world().record_dataset("x", episodes=1, seed=seed, cache_dir=tmp_path)
    assert not list(tmp_path.iterdir())  # nothing was written


@pytest.mark.parametrize(
    ("name", "why"),
    [
        ("", "an empty name"),
        (None, "a NoneType"),
        ("a\0b", "NUL"),
        ("../x", r"'\.\.' would leave the cache folder"),
        ("pusht/../../x", r"'\.\.'"),
        ("/abs/x", "an absolute path"),
        ("x.h5", r"drop the '\.h5'"),
        (5, "a int"),
    ],
)
def test_record_dataset_name(name, why, tmp_path):
    with pytest.raises(ConfigError, match=f"record_dataset requires a dataset name .*{why}"):
        world().record_dataset(name, episodes=1, seed=0, cache_dir=tmp_path)


def test_record_dataset_subfolder_name_stays_under_the_cache(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)  # a name with a folder is not taken relative to the working directory
    path = world().record_dataset("pusht/shard_0", episodes=1, seed=0, cache_dir=tmp_path / "cache")
    assert path == tmp_path / "cache" / "pusht" / "shard_0.h5" and path.is_file()
    assert swm.data.HDF5Dataset("pusht/shard_0", cache_dir=tmp_path / "cache").num_episodes == 1
    home = world().record_dataset("pusht/shard_1", episodes=1, seed=0)
    assert home == swm.data.get_cache_dir() / "pusht" / "shard_1.h5"


def test_cache_dir_that_is_a_file(tmp_path):
    (tmp_path / "file").write_text("x")
    with pytest.raises(ConfigError, match="cache_dir requires a folder, got .*file'?, which is a file"):
        world().record_dataset("x", episodes=1, seed=0, cache_dir=tmp_path / "file")


def test_stablewm_home_that_is_a_file_or_unwritable(tmp_path, monkeypatch):
    (tmp_path / "file").write_text("x")
    monkeypatch.setenv("STABLEWM_HOME", str(tmp_path / "file"))
    with pytest.raises(ConfigError, match=r"\$STABLEWM_HOME\) requires a folder"):
        world().record_dataset("x", episodes=1, seed=0)
    if os.geteuid() == 0:
        pytest.skip("root writes to read-only folders")
    (tmp_path / "ro").mkdir(mode=0o500)
    monkeypatch.setenv("STABLEWM_HOME", str(tmp_path / "ro"))
    with pytest.raises(ConfigError, match="writable folder"):
        world().record_dataset("x", episodes=1, seed=0)


@pytest.mark.parametrize(
    ("options", "error", "match"),
    [
        (5, ConfigError, "options to be a dict"),
        ("all", ConfigError, "options to be a dict"),
        ({"variation": 5}, ConfigError, "'variation' requires a list of factor names"),
        ({"variation": "all"}, ConfigError, r"write \['all'\]"),
        ({"variation_values": [1, 2]}, ConfigError, "'variation_values' requires a dict"),
        ({"variations": ["all"]}, UnknownNameError, "reset option.*'variations'.*variation"),
        ({"state": ["a", "b"]}, ConfigError, "'state' requires an array of numbers"),
        ({"state": [np.nan, 0.5]}, ConfigError, "'state' requires finite numbers"),
        ({"state": [0.5, 0.5, 0.5]}, ConfigError, r"'state' requires shape \(2,\)"),
        ({"goal_state": [1e9, 0.5]}, ConfigError, r"goal_state\[0\] = 1e\+09 outside \[0, 1\]"),
        ([{"variation": ["all"]}], ConfigError, r"one options dict per env \(2\)"),
        ([{}, 3], ConfigError, "each env's options to be a dict or None"),
    ],
)
def test_reset_options(options, error, match):
    with pytest.raises(error, match=match):
        world().reset(seed=0, options=options)


def test_bad_options_are_refused_by_the_loops_too(tmp_path):
    with pytest.raises(ConfigError, match="'variation_values' requires a dict"):
        world().evaluate(episodes=1, seed=0, options={"variation_values": [1]})
    with pytest.raises(ConfigError, match="'state' requires finite numbers"):
        world().record_dataset("x", episodes=1, seed=0, cache_dir=tmp_path, options={"state": [np.inf, 0]})

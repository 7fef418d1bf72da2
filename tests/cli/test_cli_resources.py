"""``swm list``, ``swm show`` and ``swm delete`` on datasets and models the tests create."""

from __future__ import annotations

import pytest

from stable_worldmodel.data import get_cache_dir, list_datasets, list_models


@pytest.fixture
def two_datasets(record_toy):
    record_toy("alpha", episodes=2)
    record_toy("beta", episodes=3, variation=["agent.color"])
    return ["alpha", "beta"]


@pytest.fixture
def two_models():
    root = get_cache_dir()
    for name in ("wm-small", "wm-large"):
        (root / f"{name}_weights.ckpt").write_bytes(b"w")
        (root / f"{name}_object.ckpt").write_bytes(b"o")
    return ["wm-large", "wm-small"]


# -- list --------------------------------------------------------------------------------
def test_list_datasets(swm, two_datasets):
    result = swm("list", "dataset")
    assert result.exit_code == 0
    assert "Cached datasets (2)" in result.stdout
    for name in two_datasets:
        assert name in result.stdout


def test_list_empty_names_the_cache(swm):
    result = swm("list", "dataset")
    assert result.exit_code == 0
    assert "No cached datasets" in result.stdout and str(get_cache_dir()) in result.stdout


def test_list_models_accepts_plural(swm, two_models):
    result = swm("list", "models")
    assert result.exit_code == 0
    assert "Cached models (2)" in result.stdout and "wm-small" in result.stdout and "wm-large" in result.stdout


def test_list_worlds(swm):
    result = swm("list", "world")
    assert result.exit_code == 0
    for env_id in ("swm/Toy-v0", "swm/TwoRoom-v1", "swm/PushT-v1"):
        assert env_id in result.stdout


def test_list_unknown_kind(swm, error_line):
    result = swm("list", "datset")
    assert result.exit_code == 1
    line = error_line(result)
    assert "'datset'" in line and "Did you mean 'dataset'" in line and "model" in line and "world" in line


# -- show --------------------------------------------------------------------------------
def test_show_dataset_panel(swm, two_datasets):
    result = swm("show", "dataset", "beta")
    assert result.exit_code == 0
    out = result.stdout
    assert "dataset beta" in out
    assert "episodes" in out and " 3 " in out  # three recorded episodes
    assert "(16, 16, 3)" in out  # observation and goal shapes
    assert "pixels" in out and "action" in out  # columns
    assert "agent" in out and "color" in out  # the recorded factor, as a tree
    assert "alpha" not in out


def test_show_several_and_all(swm, two_datasets):
    several = swm("show", "dataset", "alpha", "beta")
    every = swm("show", "dataset", "--all")
    assert several.exit_code == every.exit_code == 0
    for out in (several.stdout, every.stdout):
        assert "dataset alpha" in out and "dataset beta" in out
    assert several.stdout == every.stdout


def test_show_world_spaces_and_factors(swm):
    result = swm("show", "world", "swm/Toy-v0")
    assert result.exit_code == 0
    out = result.stdout
    assert "world swm/Toy-v0" in out
    assert "Observation space" in out and "Action space" in out and "Box" in out
    assert "factors of variation" in out and "background" in out and "speed" in out


def test_show_requires_names_or_all(swm, error_line, two_datasets):
    result = swm("show", "dataset")
    assert result.exit_code == 1
    line = error_line(result)
    assert "--all" in line and "alpha" in line


def test_show_unknown_dataset_suggests(swm, error_line, two_datasets):
    result = swm("show", "dataset", "alpha", "bet")
    assert result.exit_code == 1
    line = error_line(result)
    assert "'bet'" in line and "Did you mean 'beta'" in line
    assert "dataset alpha" not in result.stdout  # checked before anything is shown


def test_show_unknown_world_and_kind(swm, error_line):
    result = swm("show", "world", "swm/TwoRom-v1")
    assert result.exit_code == 1
    assert "swm/TwoRoom-v1" in error_line(result)
    result = swm("show", "model", "x")
    assert result.exit_code == 1
    line = error_line(result)
    assert "'model'" in line and "dataset" in line and "world" in line


# -- delete ------------------------------------------------------------------------------
def test_delete_confirm_yes(swm, two_datasets):
    result = swm("delete", "dataset", "alpha", input="y\n")
    assert result.exit_code == 0
    assert "Delete 1 dataset (alpha)?" in result.output
    assert "Deleted dataset alpha" in result.stdout
    assert list_datasets() == ["beta"]


def test_delete_confirm_no_keeps_everything(swm, two_datasets):
    result = swm("delete", "dataset", "alpha", "beta", input="n\n")
    assert result.exit_code == 1
    assert "Delete 2 datasets (alpha, beta)?" in result.output
    assert "Nothing deleted." in result.stderr
    assert list_datasets() == two_datasets


def test_delete_without_an_answer_aborts(swm, two_datasets):
    result = swm("delete", "dataset", "alpha", input="")
    assert result.exit_code == 1
    assert list_datasets() == two_datasets


def test_delete_yes_skips_the_prompt(swm, two_datasets):
    result = swm("delete", "dataset", "alpha", "beta", "--yes")
    assert result.exit_code == 0
    assert "?" not in result.output
    assert list_datasets() == []


def test_delete_all_names_must_exist(swm, error_line, two_datasets):
    result = swm("delete", "dataset", "alpha", "gamma", "--yes")
    assert result.exit_code == 1
    assert "'gamma'" in error_line(result)
    assert list_datasets() == two_datasets  # alpha was not deleted either


def test_delete_models(swm, two_models):
    result = swm("delete", "model", "wm-small", "-y")
    assert result.exit_code == 0
    assert list_models() == ["wm-large"]
    assert not list(get_cache_dir().glob("wm-small_*"))


def test_delete_unknown_kind(swm, error_line, two_datasets):
    result = swm("delete", "world", "swm/Toy-v0", "--yes")
    assert result.exit_code == 1
    line = error_line(result)
    assert "'world'" in line and "dataset" in line and "model" in line


def test_delete_requires_names(swm, error_line):
    result = swm("delete", "dataset")
    assert result.exit_code == 2
    assert "NAMES" in error_line(result).upper()

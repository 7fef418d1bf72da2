"""A user mistake on the command line gives one ``Error:`` line and a non-zero exit, never a traceback."""

from __future__ import annotations

import re
import sys

import numpy as np
import pytest

from stable_worldmodel.data import HDF5Dataset
from stable_worldmodel.data.video_dataset import write_video_dataset


@pytest.fixture
def a_file(tmp_path):
    path = tmp_path / "afile"
    path.write_text("not a folder")
    return path


@pytest.mark.parametrize(
    ("args", "match"),
    [
        (["--video", "{f}/v"], "swm eval --video requires a folder that can be created, got '.*afile/v'"),
        (["--video", "{f}"], "Invalid value for '--video': .*afile' is a file"),
        (["--json", "{f}/out.json"], "swm eval --json requires a folder, got '.*afile', which is a file"),
    ],
)
def test_unwritable_outputs_fail_before_any_episode(swm, error_line, a_file, args, match):
    result = swm("eval", "swm/Toy-v0", "--episodes", "1", *[a.format(f=a_file) for a in args])
    assert result.exit_code in (1, 2)  # 2: Click's own check of the option
    assert re.search(match, error_line(result))


def test_demo_out_that_is_a_file(swm, error_line, a_file):
    result = swm("demo", "--out", str(a_file / "x"), "--model", "none")
    assert result.exit_code == 1 and "swm demo --out requires a folder" in error_line(result)


def test_cache_folder_that_is_a_file(swm, error_line, a_file, monkeypatch):
    monkeypatch.setenv("STABLEWM_HOME", str(a_file))
    for args in (["list", "dataset"], ["collect", "swm/Toy-v0", "--episodes", "1"]):
        result = swm(*args)
        assert result.exit_code == 1 and "which is a file; point it at a folder" in error_line(result)


@pytest.mark.parametrize(
    ("name", "why"),
    [("../escape", "would leave the cache folder"), ("/abs/x", "an absolute path"), ("x.h5", "drop the")],
)
def test_collect_name_that_escapes_the_cache(swm, error_line, name, why):
    result = swm("collect", "swm/Toy-v0", "--episodes", "1", "--name", name)
    assert result.exit_code == 1 and why in error_line(result)


def test_collect_into_a_folder_named_like_the_dataset(swm, error_line, _stablewm_home):
    (_stablewm_home / "x.h5").mkdir(parents=True)
    result = swm("collect", "swm/Toy-v0", "--episodes", "1", "--name", "x")
    assert result.exit_code == 1 and "x.h5' to be a dataset file, got a folder" in error_line(result)
    assert "holds" not in result.output


def test_collect_into_a_sub_folder_and_show_it(swm, _stablewm_home):
    result = swm("collect", "swm/Toy-v0", "--episodes", "1", "--name", "toy/shard_0", "--max-steps", "3")
    assert result.exit_code == 0, result.output
    assert (_stablewm_home / "toy" / "shard_0.h5").is_file()
    listed = swm("list", "dataset").output  # a folder of shard_*.h5 files is one (sharded) dataset
    assert "│ toy  │" in listed and "toy/shard_0" not in listed
    assert swm("show", "dataset", "toy/shard_0").exit_code == 0
    assert swm("show", "dataset", "toy").exit_code == 0


def test_missing_optional_dependency_names_the_pip_command(swm, error_line, tmp_path, _stablewm_home, monkeypatch):
    from stable_worldmodel.data.writer import HDF5Writer

    with HDF5Writer(tmp_path / "src.h5") as w:
        w.write_episodes([{"pixels": np.zeros((3, 8, 8, 3), np.uint8), "action": np.zeros((3, 2), np.float32)}])
    write_video_dataset(HDF5Dataset(tmp_path / "src.h5"), _stablewm_home / "vid")
    monkeypatch.setitem(sys.modules, "av", None)  # as if neither video decoder were installed
    monkeypatch.setitem(sys.modules, "decord", None)
    result = swm("show", "dataset", "vid")
    assert result.exit_code == 1
    assert 'pip install "stable-worldmodel[video]"' in error_line(result)


def test_list_dataset_names_unfinished_first_recordings(swm, _stablewm_home):
    _stablewm_home.mkdir(parents=True, exist_ok=True)
    (_stablewm_home / ".killed.h5.partial").write_bytes(b"x")
    result = swm("list", "dataset")
    assert (
        result.exit_code == 0
        and "Unfinished first recording" in result.output
        and ".killed.h5.partial" in result.output
    )


def test_upstream_command_names(swm, _stablewm_home):
    assert swm("collect", "swm/Toy-v0", "-n", "1", "--name", "d", "--max-steps", "3").exit_code == 0
    assert "d" in swm("datasets").output
    assert "dataset d" in swm("inspect", "d").output
    assert swm("checkpoints", "nothing-matches").exit_code == 0
    assert "factors of variation" in swm("fovs", "Toy-v0").output  # without the swm/ prefix

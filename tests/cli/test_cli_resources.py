"""``swm list``, ``swm show`` and ``swm delete`` on datasets and models the tests create."""

from __future__ import annotations

import json

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


@pytest.fixture
def checkpoint():
    """A checkpoint folder ``checkpoints/runx`` (tiny dummy model) with a protocol; returns its parameter count."""
    from stable_worldmodel import wm
    from stable_worldmodel.wm.utils import save_pretrained

    model = wm.make("dummy", "tiny", action_dim=2)
    weights = save_pretrained(model, "runx", config=wm.get_config("dummy", "tiny").target_tree(2))
    protocol = {
        "model": "dummy",
        "dataset": "toy-expert",
        "steps": 40,
        "history_size": 1,
        "frameskip": 5,
        "image_size": 16,
        "final": {"train_loss": 0.25, "val_loss": 0.5},
    }
    (weights.parent / "protocol.json").write_text(json.dumps(protocol))
    return sum(v.numel() for v in model.state_dict().values())


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


def test_list_models_both_layouts(swm, two_models, checkpoint):
    result = swm("list", "model")
    assert result.exit_code == 0
    assert "Cached models (3)" in result.stdout
    for name in ("runx", "wm-small", "wm-large"):
        assert name in result.stdout


def test_list_worlds(swm):
    result = swm("list", "world")
    assert result.exit_code == 0
    for env_id in ("swm/Toy-v0", "swm/TwoRoom-v2", "swm/PushT-v1"):
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
    model = swm("show", "model")
    assert model.exit_code == 1 and "requires NAMES or --all" in error_line(model)


def test_show_unknown_dataset_suggests(swm, error_line, two_datasets):
    result = swm("show", "dataset", "alpha", "bet")
    assert result.exit_code == 1
    line = error_line(result)
    assert "'bet'" in line and "Did you mean 'beta'" in line
    assert "dataset alpha" not in result.stdout  # checked before anything is shown


def test_show_unknown_world_and_kind(swm, error_line):
    result = swm("show", "world", "swm/TwoRom-v1")
    assert result.exit_code == 1
    assert "swm/TwoRoom-v2" in error_line(result)
    result = swm("show", "solver", "x")
    assert result.exit_code == 1
    line = error_line(result)
    assert "'solver'" in line and "model" in line and "dataset" in line and "world" in line


def test_show_checkpoint_folder(swm, checkpoint):
    result = swm("show", "model", "runx")
    assert result.exit_code == 0
    out = result.stdout
    assert "model runx" in out and "checkpoints/runx" in out
    assert "weights.pt" in out and "config.json" in out and "protocol.json" in out and "KiB" in out
    assert "stable_worldmodel.wm.dummy.DummyWorldModel" in out
    assert f"{checkpoint:,}" in out  # counted from the state_dict
    assert "toy-expert" in out and "frameskip" in out and " 5 " in out and "image size" in out
    assert "final train loss" in out and "0.25" in out and "final val loss" in out


def test_show_checkpoint_without_protocol(swm):
    from stable_worldmodel import wm
    from stable_worldmodel.wm.utils import save_pretrained

    save_pretrained(
        wm.make("dummy", "tiny", action_dim=2), "upstream", config=wm.get_config("dummy", "tiny").target_tree(2)
    )
    result = swm("show", "model", "upstream")
    assert result.exit_code == 0
    assert "DummyWorldModel" in result.stdout and "no protocol.json" in result.stdout


def test_show_pickled_model_lists_files_without_loading(swm, two_models, checkpoint):
    result = swm("show", "models", "--all")  # the pickled files hold b"o": unpickling them would fail
    assert result.exit_code == 0
    out = result.stdout
    assert "model runx" in out and "model wm-small" in out and "model wm-large" in out
    assert "wm-small_object.ckpt" in out and "pickled" in out
    assert "wm-small_weights.ckpt" not in out  # not something AutoCostModel loads


def test_show_unknown_model_suggests(swm, error_line, checkpoint):
    result = swm("show", "model", "runz")
    assert result.exit_code == 1
    line = error_line(result)
    assert "'runz'" in line and "Did you mean 'runx'" in line


def test_list_models_names_the_model_types(swm):
    result = swm("list", "model")
    assert result.exit_code == 0
    assert "Model types" in result.stdout
    for name in ("lewm", "pldm", "prejepa", "tdmpc2", "dreamer", "gcbc", "frame"):
        assert name in result.stdout


def test_show_model_type_gives_presets_and_fields(swm):
    result = swm("show", "model", "tdmpc2")
    assert result.exit_code == 0, result.output
    out = " ".join(result.stdout.split())
    assert "model type tdmpc2" in out and "TDMPC2Config" in out and "needs reward yes" in out
    assert "swm eval ENV --policy wm:RUN" in out and "--set KEY=VALUE" in out
    assert "tiny pixel_encoder='conv'" in out and "paper" in out  # each preset with the fields it sets
    assert "goal_proprio_dim 0" in out and "num_q 5" in out  # every field with its default
    assert ":class:" not in out and "``" not in out  # the docstring's reST is plain text
    gc = swm("show", "model", "gcbc", "frame")  # configs that cannot be built bare still show their defaults
    assert gc.exit_code == 0, gc.output
    assert "model type gcbc" in gc.stdout and "policy gc:RUN" in " ".join(gc.stdout.split())
    assert "model type frame" in gc.stdout and "source" in gc.stdout


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


def test_delete_checkpoint_folder(swm, two_models, checkpoint):
    folder = get_cache_dir() / "checkpoints" / "runx"
    declined = swm("delete", "model", "runx", input="n\n")
    assert declined.exit_code == 1 and "Delete 1 model (runx)?" in declined.output and folder.is_dir()
    result = swm("delete", "model", "runx", input="y\n")
    assert result.exit_code == 0
    assert "Deleted model runx" in result.stdout
    assert not folder.exists()
    assert "runx" not in swm("list", "model").stdout
    assert list_models() == ["wm-large", "wm-small"]  # the pickled ones are untouched


def test_delete_unknown_kind(swm, error_line, two_datasets):
    result = swm("delete", "world", "swm/Toy-v0", "--yes")
    assert result.exit_code == 1
    line = error_line(result)
    assert "'world'" in line and "dataset" in line and "model" in line


def test_delete_requires_names(swm, error_line):
    result = swm("delete", "dataset")
    assert result.exit_code == 2
    assert "NAMES" in error_line(result).upper()


def test_list_shows_format_counts_size_date_and_partial_runs(swm, _stablewm_home):
    """``swm list dataset`` / ``model``: what is in the cache at a glance (format, episodes, steps, size on disk,
    last change; a run's model, dataset and steps done, with snapshots and runs stopped early marked)."""
    import json
    import re

    from stable_worldmodel.train import train

    assert (
        swm("collect", "swm/Toy-v0", "-n", "2", "--max-steps", "3", "--image-size", "16", "--name", "d").exit_code == 0
    )
    row = next(line for line in swm("list", "dataset").stdout.splitlines() if line.startswith("│ d "))
    cells = [c.strip() for c in row.strip("│").split("│")]
    assert cells[:4] == ["d", "hdf5", "2", "8"] and re.fullmatch(r"[\d.]+ KiB", cells[4])
    assert re.fullmatch(r"\d{4}-\d\d-\d\d \d\d:\d\d", cells[5])
    train(
        "dummy", "d", "tiny", steps=4, name="m", device="cpu", progress=False, frameskip=1, batch_size=4, ckpt_every=2
    )
    protocol = _stablewm_home / "checkpoints" / "m" / "protocol.json"
    listed = {
        c[0]: c
        for line in swm("list", "model").stdout.splitlines()
        if line.startswith("│ ") and (c := [x.strip() for x in line.strip("│").split("│")])
    }
    assert listed["m"][1:4] == ["dummy", "d", "4"]
    assert listed["m/step_000002"][3] == "2 of 4 (snapshot)"
    record = json.loads(protocol.read_text())
    protocol.write_text(json.dumps({**record, "steps_done": 3, "final": None}))  # as a run killed at step 3 leaves it
    partial = next(line for line in swm("list", "model").stdout.splitlines() if line.startswith("│ m "))
    assert "3 of 4 (partial)" in partial

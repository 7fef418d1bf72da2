"""``swm train --config FILE``: a YAML or JSON file of the keys ``--set`` takes; the file < ``--set`` < the
flags given; unknown keys are one error line naming the file; the run records the file in protocol.json."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from stable_worldmodel.errors import ConfigError
from stable_worldmodel.train.trainer import TrainResult

QUICK = ("--device", "cpu", "--frameskip", "1", "--batch-size", "8")


@pytest.fixture
def calls(monkeypatch):
    """Replace ``stable_worldmodel.train.train`` by a recorder of its arguments (nothing trains)."""
    seen: list[dict] = []

    def fake_train(model, dataset, preset="tiny", **kwargs):
        seen.append({"model": model, "dataset": dataset, "preset": preset, **kwargs})
        run = kwargs.get("name") or f"{dataset}-{model}"
        return TrainResult(run, Path("/nowhere") / run, 1, 0.0, None, 0.0, 0.0)

    monkeypatch.setattr("stable_worldmodel.train.train", fake_train)
    return seen


@pytest.fixture
def config_file(tmp_path):
    """``config_file(text, name="run.yaml")``: a config file with ``text`` in it."""

    def write(text: str, name: str = "run.yaml") -> str:
        path = tmp_path / name
        path.write_text(text)
        return str(path)

    return write


YAML = """\
dataset: toy
steps: 7
lr: 1e-3            # PyYAML reads this as text: it is a number here
seed: 3
ckpt_every: 2       # a trainer key without a flag
logger: none
embed_dim: 16
vit_overrides:      # a field holding a mapping takes it whole
  num_hidden_layers: 2
"""


def test_config_file_keys_go_where_their_flags_and_set_go(swm, calls, config_file):
    result = swm("train", "lewm", "--config", config_file(YAML))
    assert result.exit_code == 0, result.output
    (call,) = calls
    assert call["dataset"] == "toy" and call["steps"] == 7 and call["lr"] == pytest.approx(1e-3)
    assert call["seed"] == 3 and call["ckpt_every"] == 2 and call["logger"] == "none"
    assert call["embed_dim"] == 16 and call["vit_overrides"] == {"num_hidden_layers": 2}
    record = call["protocol_extra"]["train_config"]
    assert record["file"] == str(Path(config_file(YAML)).resolve()) and record["overridden"] == []
    assert record["applied"]["steps"] == 7 and record["applied"]["lr"] == pytest.approx(1e-3)


def test_the_file_is_under_set_which_is_under_the_flags_given(swm, calls, config_file):
    path = config_file(YAML)
    result = swm("train", "lewm", "--config", path, "--steps", "9", "--set", "seed=5", "--set", "embed_dim=32")
    assert result.exit_code == 0, result.output
    (call,) = calls
    assert call["steps"] == 9 and call["seed"] == 5 and call["embed_dim"] == 32 and call["lr"] == pytest.approx(1e-3)
    record = call["protocol_extra"]["train_config"]
    assert sorted(record["overridden"]) == ["embed_dim", "seed", "steps"]
    assert "steps" not in record["applied"] and record["applied"]["ckpt_every"] == 2
    # a flag and --set that disagree stay an error, with or without a file
    clash = swm("train", "lewm", "--config", path, "--steps", "9", "--set", "steps=8")
    assert clash.exit_code == 1 and "one value for steps" in clash.stderr


def test_nested_mappings_are_dotted_keys_and_json_works(swm, calls, config_file):
    path = config_file(json.dumps({"dataset": "toy", "vit_overrides.hidden_size": 96, "depth": 3}), "run.json")
    assert swm("train", "lewm", "--config", path).exit_code == 0
    assert calls[-1]["vit_overrides.hidden_size"] == 96 and calls[-1]["depth"] == 3
    nested = config_file("dataset: toy\nloss_weights:\n  std_loss: 2.0\n")
    assert swm("train", "pldm", "--config", nested).exit_code == 0
    assert calls[-1]["loss_weights"] == {"std_loss": 2.0}


def test_dotted_keys_set_one_entry_of_a_mapping_field():
    from stable_worldmodel.wm import get_config

    cfg = get_config("lewm", "small", **{"vit_overrides.hidden_size": 96})
    assert cfg.vit_overrides == {"num_hidden_layers": 6, "hidden_size": 96}  # on top of the preset's
    with pytest.raises(ConfigError, match=r"no field 'predictor.depth'.*'depth'"):
        get_config("lewm", "tiny", **{"predictor.depth": 2})


@pytest.mark.parametrize(
    "text, needles",
    [
        ("dataset: toy\nckpt_evry: 2\n", ["unknown key 'ckpt_evry'", "Did you mean one of 'ckpt_every'"]),
        ("dataset: toy\nembed_dmi: 8\n", ["unknown key 'embed_dmi'", "Did you mean one of 'embed_dim'"]),
        ("dataset: toy\npredictor:\n  depth: 2\n", ["unknown key 'predictor.depth'", "Did you mean 'depth'?"]),
        ("dataset: toy\nsource: run\n", ["unknown key 'source'"]),  # a field of the frame decoder only
        ("dataset: toy\nsteps: 0\n", ["run.yaml: steps requires an integer >= 1, got 0"]),
        ("dataset: toy\nlogger: wandbb\n", ["Unknown logger 'wandbb'. Did you mean 'wandb'?"]),
        ("- a\n- b\n", ["requires a mapping of KEY: VALUE", "got a list"]),
        ("dataset: [toy\n", ["requires valid YAML"]),
    ],
    ids=["trainer-key", "field", "nested", "other-model", "bad-value", "bad-logger", "not-a-mapping", "bad-yaml"],
)
def test_a_bad_config_file_is_one_error_line_naming_it(swm, calls, config_file, error_line, text, needles):
    path = config_file(text)
    result = swm("train", "lewm", "--config", path)
    assert result.exit_code == 1
    line = error_line(result)
    for needle in needles:
        assert needle in line, line
    if "unknown key" in needles[0]:
        assert path in line
    assert not calls


def test_a_missing_config_file_is_one_error_line(swm, calls, error_line, tmp_path):
    result = swm("train", "lewm", "--config", str(tmp_path / "nope.yaml"))
    assert result.exit_code == 1 and "nope.yaml', which does not exist" in error_line(result)


def test_the_run_records_the_file_and_show_model_shows_it(swm, toy, config_file, _stablewm_home):
    path = config_file("steps: 2\nname: fromfile\nlog_every: 1\nwarmup_steps: 0\n")
    result = swm("train", "dummy", "--dataset", toy, "--config", path, "--set", "log_every=2", *QUICK)
    assert result.exit_code == 0, result.output
    protocol = json.loads((_stablewm_home / "checkpoints" / "fromfile" / "protocol.json").read_text())
    assert protocol["steps"] == 2 and protocol["config"]["warmup_steps"] == 0
    assert protocol["train_config"] == {
        "file": str(Path(path).resolve()),
        "applied": {"steps": 2, "name": "fromfile", "warmup_steps": 0},
        "overridden": ["log_every"],
    }
    shown = " ".join(swm("show", "model", "fromfile").stdout.split())
    assert f"config file {Path(path).resolve()}" in shown.replace("│ ", "")
    assert 'steps=2, name="fromfile", warmup_steps=0' in shown and "log_every (by flags or --set)" in shown

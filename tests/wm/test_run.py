"""``stable_worldmodel.wm.run``: a run opened once (name parsed once, protocol read once into a
typed, validated ``RunProtocol``, files read once), used by swm eval, the planners and AutoCostModel."""

from __future__ import annotations

import json
import os
import time
from pathlib import Path

import pytest
import torch
from _tiny import ACTION_DIM, TINY

import stable_worldmodel.wm as wm
from stable_worldmodel.errors import CheckpointError, ConfigError
from stable_worldmodel.wm import run as run_module
from stable_worldmodel.wm import utils as wmu
from stable_worldmodel.wm.run import PROTOCOL_VERSION, Run, RunProtocol, split_spec


@pytest.fixture
def saved(_stablewm_home):
    """Run ``r``: a tiny LeWM with a protocol as ``swm train`` writes it (partial: 4 of 8 steps)."""
    tree = wm.get_config("lewm", "tiny", **TINY).target_tree(ACTION_DIM)
    model = wmu.instantiate(tree)
    protocol = {
        "version": PROTOCOL_VERSION,
        "model": "lewm",
        "preset": "tiny",
        "dataset": "toy",
        "image_size": 16,
        "image_mean": [0.5] * 3,
        "image_std": [0.5] * 3,
        "frameskip": 2,
        "history_size": 2,
        "action_dim": ACTION_DIM,
        "dataset_image_shape": [16, 16, 3],
        "train_episodes": [0, 2],
        "val_episodes": [1],
        "steps": 8,
        "steps_done": 4,
        "final": None,
        "normalizers": {},
        "config": {"embed_dim": 8},
        "future_key": [1, 2],
    }
    folder = _stablewm_home / "checkpoints" / "r"
    wmu.write_checkpoint(model, folder, tree, protocol)
    return folder


def test_split_spec():
    assert split_spec("wm:r") == ("wm", "r") and split_spec("gc:a/b") == ("gc", "a/b")
    assert split_spec("r") == (None, "r") and split_spec("/tmp/x.pt") == (None, "/tmp/x.pt")
    with pytest.raises(ConfigError, match="requires a name after wm:"):
        split_spec("wm:")


def test_open_parses_once_and_types_the_protocol(saved):
    run = Run.open("wm:r")
    assert (run.prefix, run.name, run.folder, run.policy_name) == ("wm", "r", saved, "wm:r")
    p = run.protocol
    assert (p.version, p.model, p.dataset, p.image_size, p.frameskip, p.history_size) == (1, "lewm", "toy", 16, 2, 2)
    assert p.train_episodes == (0, 2) and p.frame_size == (16, 16) and p.action_dim == ACTION_DIM
    assert p.partial and (p.steps_done, p.steps) == (4, 8)
    assert p.to_dict()["future_key"] == [1, 2]  # unknown keys travel on
    assert Run.open("r").policy_name == "wm:r" and Run.open(saved).name == str(saved)


def test_the_same_unchanged_run_is_read_once(saved, monkeypatch):
    reads, builds = [], []
    read_json, load = wmu._read_json, wmu.load_checkpoint
    monkeypatch.setattr(wmu, "_read_json", lambda *a: reads.append(a[0].name) or read_json(*a))
    monkeypatch.setattr(wmu, "load_checkpoint", lambda *a, **k: builds.append(a[0]) or load(*a, **k))
    run_module._OPENED.clear()
    first, second = Run.open("wm:r"), Run.open("r")
    assert first.protocol is second.protocol and reads == ["protocol.json"]
    a, b = first.load_model(), second.load_model()
    assert a is not b and len(builds) == 1  # each caller its own copy, the files read once
    assert reads == ["protocol.json", "config.json"]
    assert all(torch.equal(x, y) for x, y in zip(a.state_dict().values(), b.state_dict().values(), strict=True))
    time.sleep(0.01)
    data = json.loads((saved / "protocol.json").read_text())
    data["steps_done"] = 8
    (saved / "protocol.json").write_text(json.dumps(data))
    os.utime(saved / "protocol.json")
    assert Run.open("wm:r").protocol.steps_done == 8 and reads.count("protocol.json") == 2  # changed: read again


@pytest.mark.parametrize(
    "key, value, match",
    [
        ("image_size", "16", "image_size to be an integer >= 1"),
        ("frameskip", 0, "frameskip to be an integer >= 1"),
        ("train_episodes", [0, "1"], "train_episodes to be a list of integers"),
        ("image_mean", "grey", "image_mean to be a list of numbers"),
        ("final", "done", "final to be a mapping or null"),
        ("version", PROTOCOL_VERSION + 1, "newer than this stable-worldmodel reads"),
    ],
)
def test_a_bad_protocol_entry_is_a_typed_error_naming_the_file_and_key(saved, key, value, match):
    data = json.loads((saved / "protocol.json").read_text())
    data[key] = value
    (saved / "protocol.json").write_text(json.dumps(data))
    with pytest.raises(CheckpointError, match=match) as err:
        Run.open("wm:r")
    assert str(saved / "protocol.json") in str(err.value)


def test_an_upstream_checkpoint_without_protocol_gets_upstreams_defaults(saved):
    (saved / "protocol.json").unlink()
    p = Run.open("r").protocol
    assert (p.image_size, p.image_mean, p.frameskip, p.trained_here, p.partial) == (
        224,
        (0.485, 0.456, 0.406),
        1,
        False,
        False,
    )
    assert p == RunProtocol.from_dict({})


def test_a_missing_run_names_where_it_looked(_stablewm_home, saved):
    with pytest.raises(FileNotFoundError, match="Did you mean 'r'"):
        Run.open("wm:rr")


def test_a_long_lived_process_keeps_at_most_8_runs_open(_stablewm_home):
    """Opened runs (and the models built from them) are kept for reuse, the 8 most recent only."""
    model = torch.nn.Linear(2, 2)
    for i in range(9):
        wmu.write_checkpoint(
            model,
            _stablewm_home / "checkpoints" / f"r{i}",
            {"_target_": "torch.nn.Linear", "in_features": 2, "out_features": 2},
        )
    run_module._OPENED.clear()
    for i in range(9):
        Run.open(f"r{i}").load_model()
    kept = {Path(key[0]).parent.name for key in run_module._OPENED}
    assert len(run_module._OPENED) == 8 and "r0" not in kept and "r8" in kept

"""``swm train --set KEY=VALUE`` and the flags are one mechanism: ``--set lr=0.1`` goes where
``--lr 0.1`` goes; both with different values is one error line naming both, the same value is fine."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from stable_worldmodel.errors import ConfigError
from stable_worldmodel.train.trainer import TrainResult


@pytest.fixture
def calls(monkeypatch):
    """Replace ``stable_worldmodel.train.train`` by a recorder of its arguments (nothing trains)."""
    seen: list[dict] = []

    def fake_train(model, dataset, preset="tiny", **kwargs):
        seen.append({"model": model, "dataset": dataset, "preset": preset, **kwargs})
        run = kwargs.get("name") or f"{dataset}-{model}"
        return TrainResult(run, Path("/nowhere") / run, 1, 0.0, None, 0.0, 0.0)  # the real type: no drift

    monkeypatch.setattr("stable_worldmodel.train.train", fake_train)
    return seen


@pytest.mark.parametrize(
    "args, expected",
    [
        (("--set", "lr=0.1"), {"lr": 0.1}),
        (("--set", "batch_size=4", "--set", "steps=3"), {"batch_size": 4, "steps": 3}),
        (("--set", "seed=5", "--set", "device=cpu"), {"seed": 5, "device": "cpu"}),
        (("--lr", "0.1", "--set", "lr=0.1"), {"lr": 0.1}),  # the same value twice is fine
        (("--steps", "3", "--set", "steps=3"), {"steps": 3}),
        (("--frameskip", "2", "--set", "frameskip=2"), {"frameskip": 2}),
        (("--set", "embed_dim=8"), {"embed_dim": 8, "lr": None}),  # a plain config field stays an override
    ],
    ids=["lr", "batch-steps", "seed-device", "same-lr", "same-steps", "same-frameskip", "config-field"],
)
def test_set_routes_to_the_flag(swm, calls, args, expected):
    result = swm("train", "lewm", "--dataset", "toy", *args)
    assert result.exit_code == 0, result.output
    (call,) = calls
    assert {k: call.get(k) for k in expected} == expected


@pytest.mark.parametrize(
    "args, needles",
    [
        (("--lr", "0.1", "--set", "lr=0.2"), ["one value for lr", "--lr 0.1", "--set lr=0.2"]),
        (("--steps", "3", "--set", "steps=4"), ["one value for steps", "--steps 3", "--set steps=4"]),
        (
            ("--device", "cpu", "--set", "device=cuda"),
            ["one value for device", "--device 'cpu'", "--set device='cuda'"],
        ),
        (("--seed", "1", "--set", "seed=2"), ["one value for seed", "--seed 1", "--set seed=2"]),
        (
            ("--frameskip", "2", "--set", "frameskip=5"),
            ["one value for frameskip", "--frameskip 2", "--set frameskip=5"],
        ),
        (("--set", "model=pldm"), ["one value for model", "MODEL 'lewm'", "--set model='pldm'"]),
        (("--set", "steps=0"), ["--set steps requires an integer >= 1, got 0"]),
        (("--set", "lr=-1"), ["--set lr requires a number > 0, got '-1'"]),
        (("--set", "lr=fast"), ["--set lr requires a number, got 'fast'"]),
    ],
    ids=["lr", "steps", "device", "seed", "frameskip", "model", "bad-steps", "negative-lr", "bad-lr"],
)
def test_set_and_flag_with_different_values_is_one_error_line(swm, calls, error_line, args, needles):
    result = swm("train", "lewm", "--dataset", "toy", *args)
    assert result.exit_code == 1
    line = error_line(result)
    for needle in needles:
        assert needle in line, line
    assert not calls  # nothing trained


def test_merge_settings_raises_a_config_error_naming_both():
    from stable_worldmodel.cli.train import merge_settings

    with pytest.raises(ConfigError, match=r"got --lr 0.1 and --set lr=0.2"):
        merge_settings({"lr": 0.1}, {"lr"}, {"lr": 0.2})
    flags, overrides = merge_settings({"lr": None}, set(), {"lr": 0.2, "embed_dim": 8})
    assert flags == {"lr": 0.2} and overrides == {"embed_dim": 8}


def test_set_lr_trains_with_that_lr(swm, record_toy, one_torch_thread):
    record_toy("toy", episodes=3)
    tiny = [
        "image_size=16",
        "embed_dim=8",
        "cnn_width=8",
        "depth=1",
        "heads=2",
        "dim_head=4",
        "mlp_dim=16",
        "projector_hidden=16",
        "sigreg_num_proj=16",
        "batch_size=4",
        "frameskip=1",
    ]
    sets = [a for item in ("lr=0.01", "steps=1", *tiny) for a in ("--set", item)]
    result = swm("train", "lewm", "--dataset", "toy", "--name", "r", "--device", "cpu", *sets)
    assert result.exit_code == 0, result.output
    from stable_worldmodel.data import get_cache_dir

    protocol = json.loads((Path(get_cache_dir()) / "checkpoints" / "r" / "protocol.json").read_text())
    assert protocol["config"]["lr"] == 0.01 and protocol["steps"] == 1

"""``swm train``: what it prints on success, and its one-line errors (tiny dummy runs on the toy dataset)."""

from __future__ import annotations

import json
import math
import re

import pytest
import torch

from stable_worldmodel.train.data import TrainData
from stable_worldmodel.wm import get_config

#: a few steps of the dummy model on the CPU, frames one env step apart
QUICK = ("--device", "cpu", "--frameskip", "1", "--batch-size", "8")


def no_runs(home) -> bool:
    return not (home / "checkpoints").exists() or not any((home / "checkpoints").iterdir())


def test_train_prints_the_checkpoint_and_the_rate(swm, toy, _stablewm_home):
    result = swm("train", "dummy", "--dataset", toy, "--steps", "5", "--name", "r", *QUICK)
    assert result.exit_code == 0, result.output
    assert result.stderr == ""  # no progress bar when stderr is not a terminal
    summary, where = result.stdout.strip().splitlines()
    match = re.fullmatch(
        r"Trained dummy \(tiny\) on toy: 5 steps in \d+ s \((\d+) samples/s\), "
        r"train loss (\d+\.\d{4}), val loss (\d+\.\d{4})",
        summary,
    )
    assert match, summary
    assert int(match[1]) > 0
    folder = _stablewm_home / "checkpoints" / "r"
    assert where == f"Checkpoint: {folder} (plan with: swm eval ENV --policy wm:r); loss curve: {folder / 'loss.png'}"

    protocol = json.loads((folder / "protocol.json").read_text())
    assert protocol["steps_done"] == 5 and protocol["frameskip"] == 1 and protocol["model"] == "dummy"
    assert f"{protocol['final']['train_loss']:.4f}" == match[2] and f"{protocol['final']['val_loss']:.4f}" == match[3]
    assert (folder / "weights.pt").is_file() and (folder / "loss.png").is_file()


def test_init_from_and_a_resume_that_extends(swm, toy, _stablewm_home, error_line):
    base = ("train", "dummy", "--dataset", toy, *QUICK)
    assert swm(*base, "--steps", "3", "--name", "a").exit_code == 0
    tuned = swm(*base, "--steps", "2", "--name", "b", "--init-from", "a")
    assert tuned.exit_code == 0, tuned.output
    assert json.loads((_stablewm_home / "checkpoints" / "b" / "protocol.json").read_text())["init_from"]["run"] == "a"
    longer = swm(*base, "--steps", "5", "--name", "a", "--resume")
    assert longer.exit_code == 0 and "Trained dummy (tiny) on toy: 5 steps" in longer.stdout, longer.output
    online = swm("train", "tdmpc2", "--online", "swm/Toy-v0", "--init-from", "a")
    assert online.exit_code != 0 and "drop --init-from" in error_line(online)


def test_eval_every_prints_the_last_and_best_evaluation(swm, toy, _stablewm_home):
    args = ("train", "dummy", "--dataset", toy, "--steps", "4", "--name", "e", *QUICK)
    result = swm(*args, "--eval-every", "2", "--eval-episodes", "1")
    assert result.exit_code == 0, result.output
    line = result.stdout.strip().splitlines()[-1]
    assert re.fullmatch(
        r"Evaluations: last (0|100)\.0% \[[\d.]+, [\d.]+\] at step 4; best (0|100)\.0% at step [24] "
        r"\(swm eval ENV --policy wm:e/best\)",
        line,
    ), line
    assert (_stablewm_home / "checkpoints" / "e" / "best" / "weights.pt").is_file()


def test_eval_protocol_is_checked_before_training(swm, toy, error_line):
    args = ("train", "dummy", "--dataset", toy, "--steps", "2", "--name", "p", *QUICK)
    typo = swm(*args, "--eval-every", "1", "--eval-protocol", "upstrem")
    assert typo.exit_code == 1 and "Did you mean 'upstream'" in error_line(typo), typo.output
    # the toy episodes are 3 to 13 rows: no goal lies 25 steps on
    short = swm(*args, "--eval-every", "1", "--eval-protocol", "upstream")
    assert short.exit_code == 1 and "longer than the protocol's goal offset (25 steps" in error_line(short)
    assert swm(*args).exit_code == 0  # nothing was left behind under the name


def test_a_second_run_of_that_name_needs_resume(swm, toy, error_line):
    args = ("train", "dummy", "--dataset", toy, "--steps", "4", "--name", "r", *QUICK)
    first = swm(*args)
    assert first.exit_code == 0, first.output
    again = swm(*args)
    assert again.exit_code == 1
    assert "checkpoints/r exists: continue it with swm train --resume" in error_line(again)
    resumed = swm(*args, "--resume")
    assert resumed.exit_code == 0, resumed.output
    loss = re.compile(r"train loss \d+\.\d{4}, val loss \d+\.\d{4}")
    assert loss.search(resumed.stdout)[0] == loss.search(first.stdout)[0]


def test_epochs_bound_the_run(swm, toy):
    num_train = TrainData(toy, get_config("dummy", "tiny", frameskip=1), seed=0, device=torch.device("cpu")).num_train
    result = swm("train", "dummy", "--dataset", toy, "--epochs", "1.5", "--name", "r", *QUICK)
    assert result.exit_code == 0, result.output
    assert f": {math.ceil(1.5 * num_train / 8)} steps in " in result.stdout


def test_set_overrides_config_fields(swm, toy, _stablewm_home):
    result = swm(
        "train",
        "dummy",
        "--dataset",
        toy,
        "--steps",
        "2",
        "--name",
        "r",
        *QUICK,
        "--set",
        "warmup_steps=12",
        "--set",
        "image_mean=[0.4, 0.4, 0.4]",
    )
    assert result.exit_code == 0, result.output
    config = json.loads((_stablewm_home / "checkpoints" / "r" / "protocol.json").read_text())["config"]
    assert config["warmup_steps"] == 12 and list(config["image_mean"]) == [0.4, 0.4, 0.4]


@pytest.mark.parametrize("flag", [("--compile",), ("--set", "compile=true")], ids=["flag", "set"])
def test_compile_flag_compiles_the_training_loss(swm, toy, _stablewm_home, compile_recorder, flag):
    result = swm("train", "dummy", "--dataset", toy, "--steps", "2", "--name", "r", *QUICK, *flag)
    assert result.exit_code == 0, result.output
    assert compile_recorder.names == ["loss"]
    assert json.loads((_stablewm_home / "checkpoints" / "r" / "protocol.json").read_text())["compile"] is True


def test_unknown_model_is_one_line_naming_the_close_one(swm, toy, error_line, _stablewm_home):
    result = swm("train", "lewn", "--dataset", toy)
    assert result.exit_code == 1
    assert error_line(result) == (
        "Error: Unknown world model 'lewn'. Did you mean 'lewm'? "
        "Accepted: dinowm, dreamer, dummy, frame, gcbc, gciql, gcivl, lewm, pldm, prejepa, tdmpc2"
    )
    assert no_runs(_stablewm_home)


def test_unknown_dataset_is_one_line_naming_the_cached_ones(swm, toy, error_line, _stablewm_home):
    result = swm("train", "dummy", "--dataset", "tyo", "--steps", "2")
    assert result.exit_code == 1
    line = error_line(result)
    assert "'tyo'" in line and f"Did you mean '{toy}'?" in line and line.endswith(f": {toy}")
    assert no_runs(_stablewm_home)


@pytest.mark.parametrize(
    ("args", "code", "expected"),
    [
        (("--steps", "3", "--epochs", "1"), 1, "train requires steps or epochs, got both"),
        (("--precision", "fp32"), 1, "precision in ('32', 'bf16', '16'), got 'fp32'"),
        (("--device", "gpu"), 1, "device among auto, cpu, cuda, cuda:N, mps, got 'gpu'"),
        (("--preset", "tiyn"), 1, "got 'tiyn'. Did you mean 'tiny'?"),
        (("--steps", "0"), 2, "'--steps': expected an integer >= 1, got 0"),
        (("--epochs", "0"), 2, "'--epochs': requires a number > 0, got '0'"),
        (("--lr", "-1"), 2, "'--lr': requires a number > 0, got '-1'"),
        (("--frameskip", "x"), 2, "'--frameskip'"),
        (
            ("--set", "lr"),
            2,
            "A config override requires KEY=VALUE (a config field of the model, e.g. proprio_dim=2), got 'lr'",
        ),
        (("--set", "warmup_stepz=8"), 1, "DummyConfig has no field 'warmup_stepz'. Did you mean 'warmup_steps'"),
    ],
    ids=lambda v: " ".join(v) if isinstance(v, tuple) else None,
)
def test_bad_values_are_one_line(swm, toy, error_line, _stablewm_home, args, code, expected):
    result = swm("train", "dummy", "--dataset", toy, "--name", "r", *args)
    assert result.exit_code == code
    assert expected in error_line(result)
    assert no_runs(_stablewm_home)


def test_without_a_terminal_progress_comes_as_plain_lines(swm, toy, monkeypatch):
    monkeypatch.setenv("STABLEWM_PROGRESS_SECONDS", "0")  # a line at every log (default: every 30 s)
    result = swm("train", "dummy", "--dataset", toy, "--steps", "4", "--name", "p", *QUICK)
    assert result.exit_code == 0, result.output
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1  # the log steps: here only the last (log_every 10)
    assert re.fullmatch(r"train p: step 4/4 \(100%\), loss \d+\.\d{4}, \d+ samples/s, ETA 0m00s", lines[0]), lines


def test_ctrl_c_saves_a_checkpoint_and_prints_the_resume_command(swm, toy, monkeypatch, _stablewm_home):
    """The first Ctrl-C stops after the current step, saves it and prints how to resume; the resumed
    run ends with the weights of an uninterrupted one."""
    import os
    import signal
    import sys

    from stable_worldmodel.train import trainer as trainer_module

    before = signal.getsignal(signal.SIGINT)
    args = ("train", "dummy", "--dataset", toy, "--steps", "8", *QUICK)
    assert swm(*args, "--name", "whole").exit_code == 0
    step = trainer_module.Trainer._train_step_loss

    def interrupted_at_3(self, bs):
        if self.step == 2:  # during step 3
            os.kill(os.getpid(), signal.SIGINT)
        return step(self, bs)

    monkeypatch.setattr(trainer_module.Trainer, "_train_step_loss", interrupted_at_3)
    monkeypatch.setattr(sys, "argv", ["swm", *args, "--name", "cut"])
    cut = swm(*args, "--name", "cut")
    assert cut.exit_code == 130, cut.output
    folder = _stablewm_home / "checkpoints" / "cut"
    assert f"Interrupted at step 3 of 8: checkpoint at step 3 saved in {folder}. Resume with:" in cut.stderr
    assert f"swm train dummy --dataset {toy} --steps 8" in cut.stderr and "--name cut --resume" in cut.stderr
    assert json.loads((folder / "protocol.json").read_text())["steps_done"] == 3
    monkeypatch.setattr(trainer_module.Trainer, "_train_step_loss", step)
    assert swm(*args, "--name", "cut", "--resume").exit_code == 0
    whole, resumed = (torch.load(_stablewm_home / "checkpoints" / n / "weights.pt") for n in ("whole", "cut"))
    assert all(torch.equal(whole[k], resumed[k]) for k in whole)
    assert signal.getsignal(signal.SIGINT) is before  # the handler of before the run is back


def test_show_model_shows_how_the_run_was_made(swm, toy):
    import stable_worldmodel

    assert swm("train", "dummy", "--dataset", toy, "--steps", "2", "--name", "made", *QUICK).exit_code == 0
    shown = swm("show", "model", "made").stdout
    assert f"stable_worldmodel {stable_worldmodel.__version__}" in shown
    for row in ("command", "host", "started", "ended"):
        assert f"│ {row} " in shown, row

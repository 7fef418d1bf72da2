"""Runs are as safe as datasets (issue 26): the training state holds no pickle, one trainer per
run (a lock that dies with its holder), a run killed before its first checkpoint starts again,
and a run killed mid-way shows as partial (``final: null``)."""

from __future__ import annotations

import json
import os
import random
import signal
import subprocess
import sys
import textwrap
import time

import numpy as np
import pytest
import torch

from stable_worldmodel.errors import CheckpointError, RunBusyError
from stable_worldmodel.train.run import STATE_NAME, load_train_state


def test_train_state_loads_with_weights_only_and_resumes_exactly(fit):
    whole = fit("dummy", "whole", steps=6, log_every=2)
    state = torch.load(whole.folder / STATE_NAME, weights_only=True)
    assert state["step"] == 6 and state["format"] == 1
    assert torch.is_tensor(state["rng"]["numpy"]["keys"]) and torch.is_tensor(state["rng"]["python"]["state"])


def _as_old_pickled_state(path) -> None:
    """Rewrite a train state the way runs before format 1 stored it: RNG states as numpy / Python tuples (pickled)."""
    state = torch.load(path, weights_only=True)
    rng = state["rng"]
    n = rng["numpy"]
    rng["numpy"] = (
        n["name"],
        np.asarray(n["keys"].numpy(), dtype=np.uint32),
        n["pos"],
        n["has_gauss"],
        n["cached_gaussian"],
    )
    p = rng["python"]
    rng["python"] = (p["version"], tuple(p["state"].tolist()), p["gauss_next"])
    del state["format"]
    torch.save(state, path)
    with pytest.raises(Exception):  # noqa: B017 (torch's UnpicklingError): it really needs pickle now
        torch.load(path, weights_only=True)


def test_an_old_pickled_train_state_is_refused_under_the_setting_and_loads_with_a_warning(fit, monkeypatch):
    from test_train_api import Crash, crash_after

    with monkeypatch.context() as mp:
        crash_after(mp, 5)
        with pytest.raises(Crash):
            fit("dummy", "old", steps=8, log_every=2, ckpt_every=4)
    from stable_worldmodel.wm.utils import checkpoint_root

    path = checkpoint_root() / "old" / STATE_NAME
    _as_old_pickled_state(path)
    monkeypatch.setenv("STABLEWM_REFUSE_PICKLE", "1")
    with pytest.raises(CheckpointError, match=rf"refuses the pickled training state .*{STATE_NAME}"):
        fit("dummy", "old", steps=8, log_every=2, ckpt_every=4, resume=True)
    monkeypatch.delenv("STABLEWM_REFUSE_PICKLE")
    with pytest.warns(UserWarning, match=rf"{STATE_NAME} is a pickled training state"):
        resumed = fit("dummy", "old", steps=8, log_every=2, ckpt_every=4, resume=True)
    assert resumed.steps == 8
    assert torch.load(path, weights_only=True)["format"] == 1  # rewritten without pickle


def test_old_rng_tuples_restore_the_same_streams():
    from stable_worldmodel.train.run import rng_state, set_rng_state

    gen = torch.Generator().manual_seed(3)
    np.random.seed(1)
    random.seed(2)
    saved = rng_state(gen)
    expected = (np.random.rand(), random.random(), torch.rand(1, generator=gen).item(), torch.rand(1).item())
    np.random.seed(9)
    random.seed(9)
    set_rng_state(saved, gen)
    assert (np.random.rand(), random.random(), torch.rand(1, generator=gen).item(), torch.rand(1).item()) == expected


def test_a_damaged_train_state_is_a_typed_error(tmp_path):
    path = tmp_path / STATE_NAME
    path.write_bytes(b"PK\x03\x04 not a whole zip")
    with pytest.raises(CheckpointError, match="damaged or truncated"):
        load_train_state(path)


# -- one writer per run ---------------------------------------------------------------------------
HOLDER = textwrap.dedent("""
    import sys, time
    from pathlib import Path
    from stable_worldmodel.wm.run import lock_run
    lock = lock_run(Path(sys.argv[1]), "busy")
    print("locked", flush=True)
    time.sleep(120)
""")


@pytest.fixture
def holder(_stablewm_home):
    """A process holding the lock of run ``busy`` (as a trainer does for its whole life)."""
    folder = _stablewm_home / "checkpoints" / "busy"
    proc = subprocess.Popen([sys.executable, "-c", HOLDER, str(folder)], stdout=subprocess.PIPE, text=True)
    assert proc.stdout.readline().strip() == "locked"
    yield proc
    proc.kill()
    proc.wait()


def test_a_second_trainer_on_a_run_gets_run_busy_naming_the_holder(fit, holder):
    start = time.monotonic()
    with pytest.raises(
        RunBusyError, match=rf"Run 'busy' requires a single trainer, got one already training it: pid {holder.pid} on "
    ):
        fit("dummy", "busy", steps=2)
    assert time.monotonic() - start < 1.0
    holder.send_signal(signal.SIGKILL)  # the lock dies with its holder
    holder.wait()
    assert fit("dummy", "busy", steps=2).steps == 2


def test_swm_train_on_a_busy_run_is_one_error_line_and_a_non_zero_exit(swm, toy, holder, error_line):
    result = swm(
        "train",
        "dummy",
        "--dataset",
        toy,
        "--name",
        "busy",
        "--steps",
        "2",
        "--device",
        "cpu",
        "--set",
        "image_size=16",
        "--set",
        "frameskip=1",
    )
    assert result.exit_code != 0
    line = error_line(result)
    assert "requires a single trainer" in line and f"pid {holder.pid}" in line


def test_the_lock_is_released_when_training_fails(fit, monkeypatch):
    from test_train_api import Crash, crash_after

    from stable_worldmodel.data._lock import lock_path
    from stable_worldmodel.wm.utils import checkpoint_root

    with monkeypatch.context() as mp:
        crash_after(mp, 1)
        with pytest.raises(Crash):
            fit("dummy", "fails", steps=2)
    assert not lock_path(checkpoint_root() / "fails").exists()
    assert fit("dummy", "fails", steps=2, resume=True).steps == 2  # same process, same run: the lock is free


# -- killed runs ----------------------------------------------------------------------------------
def _killed_before_first_checkpoint(folder) -> None:
    folder.mkdir(parents=True)
    (folder / "metrics.jsonl").write_text(json.dumps({"step": 1, "train/loss": 1.0}) + "\n")


def test_a_run_killed_before_its_first_checkpoint_is_reused_by_a_plain_rerun(fit, _stablewm_home):
    folder = _stablewm_home / "checkpoints" / "early"
    _killed_before_first_checkpoint(folder)
    result = fit("dummy", "early", steps=2, log_every=1)
    assert result.steps == 2 and (folder / "weights.pt").is_file()
    assert [
        json.loads(x)["step"] for x in (folder / "metrics.jsonl").read_text().splitlines() if "train/loss" in x
    ] == [1, 2]


def test_resume_of_a_run_killed_before_its_first_checkpoint_starts_from_step_0(fit, _stablewm_home, caplog):
    folder = _stablewm_home / "checkpoints" / "early"
    _killed_before_first_checkpoint(folder)
    result = fit("dummy", "early", steps=2, resume=True)
    assert result.steps == 2
    assert "Run 'early' has no checkpoint to resume" in caplog.text and "starting from step 0" in caplog.text


def test_a_run_killed_mid_way_keeps_final_null(fit, monkeypatch, _stablewm_home):
    from test_train_api import Crash, crash_after

    with monkeypatch.context() as mp:
        crash_after(mp, 5)
        with pytest.raises(Crash):
            fit("dummy", "mid", steps=8, ckpt_every=4)
    protocol = json.loads((_stablewm_home / "checkpoints" / "mid" / "protocol.json").read_text())
    assert protocol["final"] is None and (protocol["steps_done"], protocol["steps"]) == (4, 8)
    done = fit("dummy", "mid", steps=8, ckpt_every=4, resume=True)
    protocol = json.loads((done.folder / "protocol.json").read_text())
    assert protocol["final"] is not None and protocol["steps_done"] == 8


def test_no_pickle_is_written_by_a_run(fit):
    """Every file of a run folder loads with weights_only=True (nothing needs unpickling)."""
    result = fit("dummy", "clean", steps=4, ckpt_every=2)
    for path in [*result.folder.rglob("*.pt"), *result.folder.rglob("*.ckpt")]:
        torch.load(path, weights_only=True)
    assert os.path.getsize(result.folder / STATE_NAME) > 0

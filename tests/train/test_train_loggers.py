"""Where a run's metrics go: ``logger="tensorboard"`` (default), ``"wandb"`` (W&B, offline here) or ``"none"``
(metrics.jsonl / metrics.csv always); ``swm train --logger``. Tiny dummy runs on the toy dataset."""

from __future__ import annotations

import json
import struct
import time

import pytest

from stable_worldmodel.errors import DependencyNotInstalled, UnknownNameError

QUICK = ("--device", "cpu", "--frameskip", "1", "--batch-size", "8")


@pytest.fixture
def wandb_offline(tmp_path, monkeypatch):
    """W&B in offline mode, every file it writes under ``tmp_path/wandb_dir`` (no network, nothing in ~)."""
    pytest.importorskip("wandb")
    root = tmp_path / "wandb_dir"
    root.mkdir()
    for var, value in {
        "WANDB_MODE": "offline",
        "WANDB_DIR": str(root),
        "WANDB_CONFIG_DIR": str(root / "config"),
        "WANDB_CACHE_DIR": str(root / "cache"),
        "WANDB_DATA_DIR": str(root / "data"),
        "WANDB_SILENT": "true",
        "WANDB_CONSOLE": "off",
    }.items():
        monkeypatch.setenv(var, value)
    monkeypatch.delenv("WANDB_PROJECT", raising=False)
    return root


def wandb_records(path):
    """The records of a ``run-<id>.wandb`` file (wandb's append-only log: a 7-byte header, then
    32 KiB blocks of chunks ``crc32 (4) | length (2, LE) | type (1: whole, 2: first, 3: middle, 4: last)``)."""
    from wandb.proto import wandb_internal_pb2 as pb

    data = path.read_bytes()
    assert data[:4] == b":W&B", path
    pos, block, chunks = 7, 32768, b""
    while pos + 7 <= len(data):
        if block - pos % block < 7:  # a block's tail too short for a chunk header is zero padding
            pos += block - pos % block
            continue
        _, length, kind = struct.unpack("<IHB", data[pos : pos + 7])
        chunks += data[pos + 7 : pos + 7 + length]
        pos += 7 + length
        if kind in (1, 4):
            record = pb.Record()
            record.ParseFromString(chunks)
            chunks = b""
            yield record


def offline_run(root, run_id):
    """``(history rows, config, exit code)`` of the offline W&B run ``run_id`` under ``root``
    (its runs, resumed ones included, merged in the order they were written)."""
    files = sorted(root.rglob(f"offline-run-*-{run_id}/run-{run_id}.wandb"), key=lambda p: p.parent.name)
    assert files, sorted(p.name for p in root.rglob("*"))
    history, config, exit_code = [], {}, None
    for file in files:
        for record in wandb_records(file):
            kind = record.WhichOneof("record_type")
            if kind == "history":
                history.append(
                    {item.key or "/".join(item.nested_key): json.loads(item.value_json) for item in record.history.item}
                )
            elif kind == "run":
                config.update({item.key: json.loads(item.value_json) for item in record.run.config.update})
            elif kind == "exit":
                exit_code = record.exit.exit_code
    return history, config, exit_code


def test_wandb_offline_logs_every_record_with_its_step_and_the_run_config(fit, wandb_offline, _stablewm_home):
    result = fit("dummy", "wb", steps=4, log_every=2, logger="wandb", wandb_project="proj")
    folder = result.folder
    info = json.loads((folder / "wandb.json").read_text())
    assert info["project"] == "proj" and info["name"] == "wb" and info["mode"] == "offline"
    assert (folder / "tensorboard").is_dir()  # TensorBoard stays on
    protocol = json.loads((folder / "protocol.json").read_text())
    assert protocol["logger"] == "wandb" and protocol["wandb"]["id"] == info["id"]

    history, config, exit_code = offline_run(wandb_offline, info["id"])
    assert exit_code == 0  # finished
    logged = {row["_step"]: row for row in history}
    for record in result.history:  # every metrics record, at its step
        for key, value in record.items():
            if key != "step":
                assert logged[record["step"]][key] == pytest.approx(value), (record, key)
    assert {2, 4} <= set(logged) and "train/loss" in logged[4] and "val/loss" in logged[4]
    assert config["model_config"]["image_size"] == 16
    assert config["train"]["steps"] == 4 and config["train"]["dataset"] == "toy"
    assert config["provenance"]["versions"]["stable_worldmodel"]
    assert not (_stablewm_home / "checkpoints" / "wb" / "wandb").exists()  # WANDB_DIR is honoured


def test_resume_continues_the_same_wandb_run(fit, wandb_offline, monkeypatch):
    from stable_worldmodel.train import trainer as trainer_module

    step = trainer_module.Trainer._train_step_loss

    def broken(self, bs):
        if self.step == 3:
            raise RuntimeError("boom")
        return step(self, bs)

    monkeypatch.setattr(trainer_module.Trainer, "_train_step_loss", broken)
    with pytest.raises(RuntimeError, match="boom"):
        fit("dummy", "wr", steps=4, log_every=1, ckpt_every=2, logger="wandb")
    folder = wandb_offline.parent / "stablewm_home" / "checkpoints" / "wr"
    first = json.loads((folder / "wandb.json").read_text())["id"]
    assert offline_run(wandb_offline, first)[2] == 1  # the failed run was finished, marked failed
    monkeypatch.setattr(trainer_module.Trainer, "_train_step_loss", step)
    second = int(time.time())
    while int(time.time()) == second:  # wandb names an offline run's folder by the second it starts and its id
        time.sleep(0.05)
    resumed = fit("dummy", "wr", steps=4, log_every=1, ckpt_every=2, logger="wandb", resume=True)
    assert json.loads((resumed.folder / "wandb.json").read_text())["id"] == first
    history, _, exit_code = offline_run(wandb_offline, first)
    assert exit_code == 0 and {row["_step"] for row in history} >= {1, 2, 3, 4}


def test_logger_none_writes_no_tensorboard_folder(fit):
    result = fit("dummy", "quiet", steps=2, logger="none")
    names = {p.name for p in result.folder.iterdir()}
    assert "tensorboard" not in names and "wandb.json" not in names
    assert {"metrics.jsonl", "metrics.csv"} <= names
    assert json.loads((result.folder / "protocol.json").read_text())["logger"] == "none"
    assert (fit("dummy", "loud", steps=2).folder / "tensorboard").is_dir()  # the default


def test_bad_logger_is_refused_before_training(fit, swm, toy, error_line, _stablewm_home):
    with pytest.raises(UnknownNameError, match="Unknown logger 'wandbb'. Did you mean 'wandb'?"):
        fit("dummy", "bad", steps=2, logger="wandbb")
    from stable_worldmodel.train.online import train_online

    with pytest.raises(UnknownNameError, match="Unknown logger 'tb'"):
        train_online("tdmpc2", "swm/Toy-v0", logger="tb")
    result = swm("train", "dummy", "--dataset", toy, "--steps", "2", "--logger", "tensorbord", *QUICK)
    assert result.exit_code == 1
    line = error_line(result)
    assert "'tensorbord'" in line and "Did you mean 'tensorboard'?" in line and "none, tensorboard, wandb" in line
    assert not (_stablewm_home / "checkpoints").exists()


def test_missing_wandb_names_the_extra(fit, swm, toy, error_line, monkeypatch):
    import stable_worldmodel._optional as optional

    available = optional.is_available
    monkeypatch.setattr(optional, "is_available", lambda module: module != "wandb" and available(module))
    with pytest.raises(DependencyNotInstalled, match=r"pip install 'stable-worldmodel\[wandb\]'"):
        fit("dummy", "nowb", steps=2, logger="wandb")
    result = swm("train", "dummy", "--dataset", toy, "--steps", "2", "--logger", "wandb", *QUICK)
    assert result.exit_code == 1 and "pip install 'stable-worldmodel[wandb]'" in error_line(result)


def test_swm_train_logger_wandb_and_show_model(swm, toy, wandb_offline, _stablewm_home):
    args = ("train", "dummy", "--dataset", toy, "--steps", "2", "--name", "cw", *QUICK)
    result = swm(*args, "--logger", "wandb", "--wandb-project", "cli-proj")
    assert result.exit_code == 0, result.output
    info = json.loads((_stablewm_home / "checkpoints" / "cw" / "wandb.json").read_text())
    assert info["project"] == "cli-proj"
    shown = " ".join(swm("show", "model", "cw").stdout.split())
    assert f"wandb run cli-proj/{info['id']} offline" in shown and "logger wandb" in shown

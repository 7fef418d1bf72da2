"""Data-parallel training (2 gloo processes on the CPU): gradients equal a single process's on
the global batch, SIGReg and VCReg included, and ``swm train`` runs under ``torchrun``."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import torch
from _nets import TINY_JEPA

from stable_worldmodel.errors import ConfigError
from stable_worldmodel.train import distributed

GLOBAL_BATCH = 8
#: a width-8 CNN world model at 16x16 with one predictor layer
NET = dict(TINY_JEPA, history_size=2, warmup_steps=0)

# One process of the gradient check: the same seeded model and global batch everywhere, this
# process's slice through DDP inside global_batch(), gradients written by rank 0.
WORKER = r"""
import os, sys, torch, torch.distributed as dist
sys.path.insert(0, sys.argv[3])
from grads_common import build, batch_of
from stable_worldmodel.train import distributed
from stable_worldmodel.train.trainer import _Loss
from torch.nn.parallel import DistributedDataParallel
rank, world, model_name, out = int(sys.argv[1]), int(sys.argv[2]), sys.argv[4], sys.argv[5]
os.environ.update(RANK=str(rank), WORLD_SIZE=str(world), LOCAL_RANK=str(rank))
info, _ = distributed.setup(torch.device("cpu"), 8)
model = distributed.global_batch_norm(build(model_name))
ddp = DistributedDataParallel(_Loss(model))
batch = {k: info.shard(v) for k, v in batch_of().items()}
torch.manual_seed(1)  # SIGReg's directions: the same draw in every process
with distributed.global_batch():
    loss = ddp(batch)["loss"]
loss.backward()
if rank == 0:
    torch.save({n: p.grad for n, p in model.named_parameters() if p.grad is not None}, out)
del ddp  # it holds the process group: release it before leaving the group, not at interpreter exit
distributed.cleanup(info)
"""

COMMON = r"""
import torch
from stable_worldmodel import keys, wm
NET = %r
def build(name):
    torch.manual_seed(0)
    extra = {"sigreg_num_proj": 16} if name == "lewm" else {"idm_hidden": 16}
    return wm.make(name, "tiny", action_dim=2, **{**NET, **extra})
def batch_of():
    g = torch.Generator().manual_seed(3)
    return {keys.PIXELS: torch.randn(8, 3, 3, 16, 16, generator=g), keys.ACTION: torch.randn(8, 3, 2, generator=g)}
"""


def _free_port() -> int:
    import socket

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest.mark.parametrize("model_name", ["lewm", "pldm"])  # SIGReg, VCReg
def test_ddp_gradients_equal_single_process_gradients(model_name, tmp_path):
    (tmp_path / "grads_common.py").write_text(COMMON % (NET,))
    (tmp_path / "worker.py").write_text(WORKER)
    env = {**os.environ, "MASTER_ADDR": "127.0.0.1", "MASTER_PORT": str(_free_port()), "OMP_NUM_THREADS": "1"}
    out = tmp_path / "ddp.pt"
    procs = [
        subprocess.Popen(
            [sys.executable, str(tmp_path / "worker.py"), str(r), "2", str(tmp_path), model_name, str(out)],
            env=env,
            stdout=subprocess.PIPE,
            stderr=subprocess.STDOUT,
            text=True,
        )
        for r in range(2)
    ]
    logs = [p.communicate(timeout=120)[0] for p in procs]
    assert all(p.returncode == 0 for p in procs), logs
    ddp = torch.load(out)

    sys.path.insert(0, str(tmp_path))
    try:
        import grads_common

        model = grads_common.build(model_name)
        torch.manual_seed(1)
        model.loss(grads_common.batch_of())["loss"].backward()
    finally:
        sys.path.remove(str(tmp_path))
        sys.modules.pop("grads_common", None)
    single = {n: p.grad for n, p in model.named_parameters() if p.grad is not None}
    assert set(ddp) == set(single)
    for name, grad in single.items():
        torch.testing.assert_close(ddp[name], grad, atol=1e-5, rtol=1e-4, msg=name)


def test_gather_is_the_identity_outside_a_process_group():
    x = torch.randn(2, 4, 3)
    with distributed.global_batch():
        assert distributed.gather_batch(x, dim=-2) is x
    assert distributed.DistInfo().shard(np.arange(6)).tolist() == list(range(6))
    assert distributed.DistInfo(rank=1, world_size=2).shard(np.arange(6)).tolist() == [3, 4, 5]


def test_global_batch_must_divide(monkeypatch):
    monkeypatch.setenv("WORLD_SIZE", "3")
    with pytest.raises(ConfigError, match="multiple of the 3 processes, got batch_size=8; use --batch-size 6"):
        distributed.setup(torch.device("cpu"), 8)


def test_swm_train_under_torchrun_matches_a_single_process_run(toy, swm, _stablewm_home):
    """2 gloo processes and 1 process train the same steps on the same global batches: the
    weights agree, and only process 0 wrote metrics."""
    args = [
        "train",
        "lewm",
        "--dataset",
        toy,
        "--steps",
        "4",
        "--batch-size",
        str(GLOBAL_BATCH),
        "--device",
        "cpu",
        "--seed",
        "0",
    ]
    single = swm(*args, "--name", "one")
    assert single.exit_code == 0, single.output
    env = {**os.environ, "STABLEWM_HOME": str(_stablewm_home), "OMP_NUM_THREADS": "1"}
    torchrun = [
        sys.executable,
        "-m",
        "torch.distributed.run",
        "--nproc-per-node",
        "2",
        "--master-port",
        str(_free_port()),
    ]
    out = subprocess.run(
        [*torchrun, "-m", "stable_worldmodel.cli", *args, "--name", "two"],
        env=env,
        capture_output=True,
        text=True,
        timeout=240,
    )
    assert out.returncode == 0, out.stdout[-3000:] + out.stderr[-3000:]
    root = Path(_stablewm_home) / "checkpoints"
    w1, w2 = torch.load(root / "one" / "weights.pt"), torch.load(root / "two" / "weights.pt")
    for key, value in w1.items():
        torch.testing.assert_close(w2[key], value, atol=1e-4, rtol=1e-3, msg=key)
    protocol = json.loads((root / "two" / "protocol.json").read_text())
    assert protocol["distributed"] == {"processes": 2, "backend": "gloo"}
    lines = (root / "two" / "metrics.jsonl").read_text().splitlines()
    assert [json.loads(line)["step"] for line in lines if "train/loss" in json.loads(line)] == [4]

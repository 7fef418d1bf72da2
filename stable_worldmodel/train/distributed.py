"""Multi-process training with PyTorch distributed (DDP), launched by ``torchrun``.

``swm train ...`` and :func:`stable_worldmodel.train.train` detect ``torchrun``'s environment
(``WORLD_SIZE`` > 1) and join the process group themselves: gloo on CPU, NCCL on CUDA (one GPU
per process, ``cuda:LOCAL_RANK``). Nothing else changes on the command line::

    torchrun --nproc-per-node 4 -m stable_worldmodel.cli train lewm --dataset tr --device cuda

How a step runs on N processes (the *global* batch is ``--batch-size``, which N must divide):

- every process draws the same global batch of sample ids (one shared, seeded generator) and
  loads its contiguous 1/N slice;
- the model's loss runs on the slice inside :func:`global_batch`, where batch-statistic losses
  that must see the whole batch (SIGReg) all-gather their input with autograd
  (:func:`gather_batch`), so their value and gradients are those of a single process on the
  global batch;
- batch-norm layers normalise with the statistics of the global batch
  (:func:`global_batch_norm`: ``SyncBatchNorm`` needs a GPU, this works on gloo too);
- DDP averages the gradients, so the update equals a single-process update on the global batch
  (tested to 1e-5);
- process 0 alone logs, validates, writes checkpoints and the loss plot.
"""

from __future__ import annotations

import contextlib
import os
from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np
import torch

from ..errors import ConfigError

_GATHER: list[bool] = []  # non-empty inside global_batch()


@dataclass(frozen=True)
class DistInfo:
    """Where this process stands: ``rank`` of ``world_size`` (1 when not distributed)."""

    rank: int = 0
    world_size: int = 1
    local_rank: int = 0

    @property
    def enabled(self) -> bool:
        return self.world_size > 1

    @property
    def is_main(self) -> bool:
        return self.rank == 0

    def shard(self, index: np.ndarray) -> np.ndarray:
        """This process's contiguous slice of a global batch ``index`` (the size divides evenly)."""
        n = len(index) // self.world_size
        return index[self.rank * n : (self.rank + 1) * n]


def env_world_size() -> int:
    """``WORLD_SIZE`` as set by ``torchrun`` (1 when absent)."""
    return int(os.environ.get("WORLD_SIZE", "1"))


def setup(device: torch.device, batch_size: int) -> tuple[DistInfo, torch.device]:
    """Join ``torchrun``'s process group (once) and return this process's place and device.

    Outside ``torchrun`` (or with one process) this is a no-op. CUDA processes get
    ``cuda:LOCAL_RANK``; ``batch_size`` (the global batch) must be a multiple of the world size.
    """
    import torch.distributed as dist

    world = env_world_size()
    if world <= 1:
        return DistInfo(), device
    if batch_size % world:
        raise ConfigError(
            f"distributed training requires the global batch size to be a multiple of the {world} processes, "
            f"got batch_size={batch_size}; use --batch-size {max(world, batch_size - batch_size % world)}"
        )
    local = int(os.environ.get("LOCAL_RANK", "0"))
    if device.type == "cuda":
        device = torch.device("cuda", local)
        torch.cuda.set_device(device)
    if not dist.is_initialized():
        dist.init_process_group("nccl" if device.type == "cuda" else "gloo")
    return DistInfo(dist.get_rank(), dist.get_world_size(), local), device


def barrier(info: DistInfo) -> None:
    """Wait for every process (no-op when not distributed)."""
    if info.enabled:
        import torch.distributed as dist

        dist.barrier()


def mean_over_processes(info: DistInfo, value: float) -> float:
    """The mean of ``value`` over the processes (``value`` itself when not distributed)."""
    if not info.enabled:
        return value
    import torch.distributed as dist

    t = torch.tensor([float(value)], dtype=torch.float64)
    if dist.get_backend() == "nccl":
        t = t.cuda()
    dist.all_reduce(t)
    return float(t.item()) / info.world_size


@contextlib.contextmanager
def global_batch() -> Iterator[None]:
    """Inside, :func:`gather_batch` all-gathers across processes (the training step only:
    validation on process 0 alone must not wait for the others)."""
    _GATHER.append(True)
    try:
        yield
    finally:
        _GATHER.pop()


def gather_batch(x: torch.Tensor, dim: int) -> torch.Tensor:
    """``x`` concatenated over every process along ``dim``, differentiable, in rank order.

    The identity outside :func:`global_batch` or without a process group. The backward pass
    sums each process's gradient for every slice, so with DDP's averaging a loss computed on the
    gathered batch gets the gradients of a single process holding the whole batch.
    """
    import torch.distributed as dist

    if not _GATHER or not dist.is_available() or not dist.is_initialized() or dist.get_world_size() == 1:
        return x
    return _AllGather.apply(x, dim)


class _AllGather(torch.autograd.Function):
    """All-gather along ``dim`` whose backward all-reduces (sums) the gradient and keeps this
    process's slice (works on gloo, which has no reduce-scatter)."""

    @staticmethod
    def forward(ctx, x: torch.Tensor, dim: int) -> torch.Tensor:
        import torch.distributed as dist

        world, rank = dist.get_world_size(), dist.get_rank()
        parts = [torch.empty_like(x) for _ in range(world)]
        dist.all_gather(parts, x.contiguous())
        ctx.dim, ctx.rank, ctx.size = dim, rank, x.shape[dim]
        return torch.cat(parts, dim=dim)

    @staticmethod
    def backward(ctx, grad: torch.Tensor):
        import torch.distributed as dist

        grad = grad.contiguous()
        dist.all_reduce(grad)
        return grad.narrow(ctx.dim, ctx.rank * ctx.size, ctx.size), None


class _GlobalBatchNorm(torch.nn.modules.batchnorm._BatchNorm):
    """A batch-norm layer whose training statistics are those of the gathered global batch (the
    class a layer of ``model`` is switched to by :func:`global_batch_norm`; same parameters,
    buffers and state-dict keys)."""

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        if not (self.training and _GATHER):
            return super().forward(x)
        import torch.distributed as dist

        n = x.shape[0]
        full = gather_batch(x, dim=0)
        if self.num_batches_tracked is not None:
            self.num_batches_tracked.add_(1)
        momentum = self.momentum if self.momentum is not None else 1.0 / float(self.num_batches_tracked)
        out = torch.nn.functional.batch_norm(
            full, self.running_mean, self.running_var, self.weight, self.bias, True, momentum, self.eps
        )
        return out.narrow(0, dist.get_rank() * n, n)


def global_batch_norm(model: torch.nn.Module) -> torch.nn.Module:
    """Switch every ``BatchNorm1d/2d/3d`` of ``model`` (in place) to global-batch statistics
    under :func:`global_batch`; elsewhere they behave as before."""
    for module in model.modules():
        if isinstance(module, torch.nn.modules.batchnorm._BatchNorm) and not isinstance(module, _GlobalBatchNorm):
            base = type(module)
            module.__class__ = type(f"Global{base.__name__}", (_GlobalBatchNorm, base), {})
    return model


def cleanup(info: DistInfo) -> None:
    """Leave the process group (after a final barrier)."""
    if info.enabled:
        import torch.distributed as dist

        if dist.is_initialized():
            dist.barrier()
            dist.destroy_process_group()

"""Cheaper batches out of DataLoader worker processes.

A DataLoader worker sends each batch to the main process through a pipe, and torch ships
every CPU tensor in it as a shared-memory file descriptor: one socket handshake with the
worker per tensor. A recorded dataset has a dozen columns, most of them a few hundred bytes
per batch, so those handshakes cost more than reading the data (about half of the time of a
two-worker loader on a 2-core machine). Inside our datasets' worker processes only, tensors
of at most ``SMALL_TENSOR_BYTES`` are therefore pickled by value (a copy of a few KiB into the
same pipe message); larger ones (images) still travel as shared memory. The main process
receives ordinary, writable tensors either way.
"""

from __future__ import annotations

import os

SMALL_TENSOR_BYTES = 128 << 10

_prepared_pid: int | None = None


def _reduce_tensor(tensor):
    import torch
    from torch.multiprocessing.reductions import reduce_tensor

    small = (
        type(tensor) is torch.Tensor
        and tensor.device.type == "cpu"
        and tensor.layout == torch.strided
        and not tensor.requires_grad
        and not tensor.is_conj()
        and not tensor.is_neg()
        and tensor.dtype not in (torch.bfloat16, torch.complex32)
        and tensor.numel() * tensor.element_size() <= SMALL_TENSOR_BYTES
    )
    if small:
        return torch.from_numpy, (tensor.numpy(),)  # numpy arrays pickle by value
    return reduce_tensor(tensor)


def prepare_worker() -> None:
    """In a DataLoader worker process, send small tensors by value (once per process)."""
    global _prepared_pid
    pid = os.getpid()
    if _prepared_pid == pid:
        return
    from torch.utils.data import get_worker_info

    if get_worker_info() is None:  # the main process: leave its pickling alone
        return
    from multiprocessing.reduction import ForkingPickler

    import torch

    ForkingPickler.register(torch.Tensor, _reduce_tensor)
    _prepared_pid = pid

"""Moving large arrays from env workers to the main process through shared memory.

A worker writes each large array of a result into a shared-memory block it owns (one per
key, reused every step) and sends a small :class:`ShmRef` instead of the bytes; the main
process copies the array out before it sends the next command, so a block is never written
while it is being read. Small arrays still travel through the pipe.
"""

from __future__ import annotations

import sys
from dataclasses import dataclass
from multiprocessing import resource_tracker, shared_memory
from typing import Any

import numpy as np

MIN_BYTES = 32 * 1024  # below this, pickling through the pipe is as fast


@dataclass(frozen=True)
class ShmRef:
    name: str
    shape: tuple[int, ...]
    dtype: str


class ShmWriter:
    """Worker side: one reusable block per (result slot, key)."""

    def __init__(self) -> None:
        self._blocks: dict[tuple[int, str], shared_memory.SharedMemory] = {}

    def pack(self, slot: int, batch: Any) -> Any:
        if not isinstance(batch, dict):
            return batch
        out = {}
        for key, value in batch.items():
            if not isinstance(value, np.ndarray) or value.nbytes < MIN_BYTES or value.dtype.hasobject:
                out[key] = value
                continue
            block = self._blocks.get((slot, key))
            if block is None or block.size < value.nbytes:
                if block is not None:
                    block.close()
                    block.unlink()
                block = self._blocks[(slot, key)] = shared_memory.SharedMemory(create=True, size=value.nbytes)
            np.ndarray(value.shape, value.dtype, buffer=block.buf)[...] = value
            out[key] = ShmRef(block.name, value.shape, value.dtype.str)
        return out

    def close(self) -> None:
        for block in self._blocks.values():
            block.close()
            try:
                block.unlink()
            except FileNotFoundError:
                pass
        self._blocks.clear()


class ShmReader:
    """Main side: attaches to worker blocks once and copies arrays out."""

    def __init__(self) -> None:
        self._blocks: dict[str, shared_memory.SharedMemory] = {}

    def unpack(self, batch: Any) -> Any:
        if not isinstance(batch, dict):
            return batch
        return {k: self._read(v) if isinstance(v, ShmRef) else v for k, v in batch.items()}

    def _read(self, ref: ShmRef) -> np.ndarray:
        block = self._blocks.get(ref.name)
        if block is None:
            block = _attach(ref.name)
            self._blocks[ref.name] = block
        return np.ndarray(ref.shape, np.dtype(ref.dtype), buffer=block.buf).copy()

    def close(self) -> None:
        """Detach (the worker that created a block unlinks it)."""
        for block in self._blocks.values():
            block.close()
        self._blocks.clear()


def _attach(name: str) -> shared_memory.SharedMemory:
    """Attach to a worker's block without registering it with the resource tracker.

    The worker that created the block owns it (and its tracker entry); before Python 3.13
    attaching registers the name again, and with forked workers sharing our tracker that
    would unbalance the tracker's bookkeeping.
    """
    if sys.version_info >= (3, 13):
        return shared_memory.SharedMemory(name=name, track=False)
    register = resource_tracker.register
    resource_tracker.register = lambda *args, **kwargs: None
    try:
        return shared_memory.SharedMemory(name=name)
    finally:
        resource_tracker.register = register

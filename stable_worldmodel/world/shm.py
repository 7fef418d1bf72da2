"""Moving large arrays from env workers to the main process through shared memory.

A worker writes each large array of a result into a shared-memory block it owns (one per
key, reused every step) and sends a small :class:`ShmRef` instead of the bytes; the main
process copies the array out before it sends the next command, so a block is never written
while it is being read. Small arrays still travel through the pipe.

Lifetime (no block may outlive the processes that use it, however they end):

- A block's name is ``<prefix><n>``, where the prefix is unique to one worker of one pool
  (:func:`new_prefix` plus the worker index), so leftovers can be found by name.
- The main process unlinks a block as soon as it has mapped it. Both processes keep their
  mapping (the memory lives until the last one is unmapped), and from then on there is nothing
  left to clean, whichever process dies.
- A worker unlinks the blocks it made when it closes or exits (:meth:`ShmWriter.abandon`, called
  when its parent dies or on SIGTERM), which covers the blocks the main process never mapped.
- When the main process closes a pool it removes whatever still carries the pool's prefix
  (:func:`sweep`; needs ``/dev/shm``, so Linux only), which covers a worker that was killed.

Blocks are made and mapped outside multiprocessing's resource tracker: the rules above already
free them, and a tracker would unlink them a second time and warn about "leaked" blocks (and,
with forked workers, start one tracker process per worker). Python 3.13 has ``track=False`` for
this; before it the tracker's ``register`` is switched off for the duration of the constructor.
Opt-out: ``vectorization_mode="sync"`` (no workers, no shared memory).
"""

from __future__ import annotations

import os
import secrets
import sys
import threading
from dataclasses import dataclass
from multiprocessing import resource_tracker, shared_memory
from typing import Any

import numpy as np

try:
    import _posixshmem  # what shared_memory itself uses to unlink
except ImportError:  # Windows: a block vanishes with its last handle, there is no name to unlink
    _posixshmem = None

MIN_BYTES = 32 * 1024  # below this, pickling through the pipe is as fast
SHM_DIR = "/dev/shm"  # where Linux lists the blocks


@dataclass(frozen=True)
class ShmRef:
    name: str
    shape: tuple[int, ...]
    dtype: str


def new_prefix() -> str:
    """A fresh name prefix (macOS allows 30 characters per name: keep it short)."""
    return f"swm{secrets.token_hex(4)}_"


class ShmWriter:
    """Worker side: one reusable block per (result slot, key)."""

    def __init__(self, prefix: str | None = None) -> None:
        self.prefix = prefix or new_prefix()
        self._blocks: dict[tuple[int, str], shared_memory.SharedMemory] = {}
        self._names: set[str] = set()  # every block made and not yet unlinked by us
        self._count = 0
        self._lock = threading.RLock()  # against abandon() from the parent-watch thread

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
                block = self._blocks[(slot, key)] = self._replace(block, value.nbytes)
            np.ndarray(value.shape, value.dtype, buffer=block.buf)[...] = value
            out[key] = ShmRef(block.name, value.shape, value.dtype.str)
        return out

    def _replace(self, old: shared_memory.SharedMemory | None, size: int) -> shared_memory.SharedMemory:
        with self._lock:
            if old is not None:
                old.close()
                self._unlink(old.name)
            name = f"{self.prefix}{self._count}"
            self._count += 1
            self._names.add(name)  # before it exists, so that abandon() never misses it
            return _open(name, size)

    def _unlink(self, name: str) -> None:
        unlink(name)
        self._names.discard(name)

    def abandon(self) -> None:
        """For a process about to exit: unlink every block, and keep the lock so that no new
        block can be made afterwards."""
        self._lock.acquire()
        for name in list(self._names):
            try:
                unlink(name)
            except OSError:
                pass

    def close(self) -> None:
        with self._lock:
            for block in self._blocks.values():
                block.close()
            for name in list(self._names):
                self._unlink(name)
            self._blocks.clear()


class ShmReader:
    """Main side: attaches to worker blocks once (then unlinks their names) and copies arrays out."""

    def __init__(self) -> None:
        self._blocks: dict[str, shared_memory.SharedMemory] = {}

    def unpack(self, batch: Any) -> Any:
        if not isinstance(batch, dict):
            return batch
        return {k: self._read(v) if isinstance(v, ShmRef) else v for k, v in batch.items()}

    def _read(self, ref: ShmRef) -> np.ndarray:
        block = self._blocks.get(ref.name)
        if block is None:
            block = self._blocks[ref.name] = _open(ref.name)
            unlink(ref.name)  # both sides have it mapped: the name is no longer needed
        return np.ndarray(ref.shape, np.dtype(ref.dtype), buffer=block.buf).copy()

    def close(self) -> None:
        """Unmap every block."""
        for block in self._blocks.values():
            block.close()
        self._blocks.clear()


def pack_result(writer: ShmWriter, cmd: str, result: Any) -> Any:
    """Route the large arrays of an :class:`EnvGroup` reset/step result through shared memory."""
    if cmd == "reset":
        return (writer.pack(0, result[0]), writer.pack(1, result[1]))
    if cmd == "step":
        return (writer.pack(2, result[0]), *result[1:4], writer.pack(3, result[4]))
    return result


def unpack_result(reader: ShmReader, cmd: str, result: Any) -> Any:
    if cmd == "reset":
        return (reader.unpack(result[0]), reader.unpack(result[1]))
    if cmd == "step":
        return (reader.unpack(result[0]), *result[1:4], reader.unpack(result[4]))
    return result


def unlink(name: str) -> None:
    """Remove a block's name (its memory lives on while mapped); a missing name is fine."""
    if _posixshmem is None:
        return
    try:
        _posixshmem.shm_unlink("/" + name)
    except FileNotFoundError:
        pass


def sweep(prefix: str) -> list[str]:
    """Unlink every block whose name starts with ``prefix``; returns their names (Linux only)."""
    try:
        names = [n for n in os.listdir(SHM_DIR) if n.startswith(prefix)]
    except OSError:
        return []
    for name in names:
        try:
            unlink(name)
        except OSError:
            pass
    return names


def _open(name: str, size: int = 0) -> shared_memory.SharedMemory:
    """Create (``size > 0``) or attach to a block without the resource tracker (module docstring)."""
    create = size > 0
    if sys.version_info >= (3, 13):
        return shared_memory.SharedMemory(name=name, create=create, size=size, track=False)
    register = resource_tracker.register
    resource_tracker.register = lambda *args, **kwargs: None
    try:
        return shared_memory.SharedMemory(name=name, create=create, size=size)
    finally:
        resource_tracker.register = register

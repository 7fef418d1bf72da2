"""One writer per dataset: an advisory lock on ``.<name>.lock`` beside the dataset file.

POSIX record locks (``fcntl.lockf``) belong to the process that took them: the kernel drops
them when that process dies, however it dies, so a lock never outlives a killed holder, and
forked children (env workers, DataLoader workers) never inherit it. They do not exclude a
second lock taken by the same process, so locks held here are also kept in a process-wide set.
The lock file names its holder (pid, host, command) for the error a second writer gets; it is
removed by the holder on release, and a waiter that locked a file removed meanwhile retries.
"""

from __future__ import annotations

import contextlib
import os
import socket
import sys
import threading
import time
from collections.abc import Callable
from pathlib import Path

from ..errors import ConfigError, DatasetBusyError, DiskFullError, is_disk_full

POLL_S = 0.05
_held: set[str] = set()  # lock files held by this process
_held_guard = threading.Lock()


def lock_path(path: str | os.PathLike) -> Path:
    """The lock file of dataset ``path``."""
    path = Path(path)
    return path.with_name(f".{path.name}.lock")


def _describe_self() -> str:
    command = " ".join(Path(a).name if i == 0 else a for i, a in enumerate(sys.argv[:3])) or "python"
    return f"pid {os.getpid()} on {socket.gethostname()} ({command})"


def _read_holder(fd: int) -> str:
    try:
        text = os.pread(fd, 512, 0).decode(errors="replace").strip()
    except OSError:
        text = ""
    return text or "another process"


class WriterLock:
    """Exclusive lock on dataset ``path`` (``with`` or :meth:`acquire` / :meth:`release`).

    ``wait``: False raises :class:`DatasetBusyError` at once when another writer holds the
    dataset; True waits for it; a number waits at most that many seconds. ``busy`` builds the
    error instead, from the holder's description (a run folder's lock raises ``RunBusyError``).
    """

    def __init__(
        self, path: str | os.PathLike, wait: bool | float = False, *, busy: Callable[[str], Exception] | None = None
    ):
        if isinstance(wait, bool):
            timeout = float("inf") if wait else 0.0
        elif isinstance(wait, (int, float)) and wait >= 0:
            timeout = float(wait)
        else:
            raise ConfigError(f"WriterLock requires wait to be a bool or seconds >= 0, got {wait!r}")
        self.dataset = Path(path)
        self.path = lock_path(path)
        self.timeout = timeout
        self.busy = busy
        self._fd: int | None = None
        self._pid: int | None = None

    def acquire(self) -> WriterLock:
        import fcntl

        key = str(self.path.resolve())
        deadline = time.monotonic() + self.timeout
        while True:
            with _held_guard:
                mine = key in _held
                if not mine:
                    fd = os.open(self.path, os.O_RDWR | os.O_CREAT | os.O_CLOEXEC, 0o644)
                    try:
                        fcntl.lockf(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
                        holder = None
                    except OSError:
                        holder = _read_holder(fd)
                        os.close(fd)  # this process holds no lock on the file: closing drops nothing
                    if holder is None:
                        if self._still_linked(fd):
                            _held.add(key)
                            break
                        os.close(fd)  # the holder removed it as we locked it: lock the new one
                        continue
            if time.monotonic() >= deadline:
                holder = "this process" if mine else holder
                if self.busy is not None:
                    raise self.busy(holder)
                how = "wait for it (wait=True in Python)" if self.timeout == 0 else f"waited {self.timeout:g} s"
                raise DatasetBusyError(
                    f"{self.dataset} requires a single writer, got one already writing it: {holder}; "
                    f"let it finish or {how}"
                )
            time.sleep(POLL_S)
        self._fd, self._pid, self._key = fd, os.getpid(), key
        try:
            os.ftruncate(fd, 0)
            os.pwrite(fd, _describe_self().encode(), 0)
        except BaseException as exc:  # a lock that cannot name its holder is not kept (nor left held here)
            with contextlib.suppress(OSError):  # the failure to report is the one above
                self.release()
            if is_disk_full(exc):
                raise DiskFullError(
                    f"WriterLock requires room to write the lock file {self.path}, got {os.strerror(exc.errno)}; "
                    "free some space on that disk (or raise the quota) and try again"
                ) from exc
            raise
        return self

    def _still_linked(self, fd: int) -> bool:
        try:
            return os.stat(self.path).st_ino == os.fstat(fd).st_ino
        except FileNotFoundError:
            return False

    def release(self) -> None:
        """Remove the lock file and drop the lock; idempotent, and a no-op in a forked child."""
        fd, self._fd = self._fd, None
        if fd is None or self._pid != os.getpid():
            return
        try:
            self.path.unlink(missing_ok=True)
        finally:
            with _held_guard:
                _held.discard(self._key)
            os.close(fd)

    def __enter__(self) -> WriterLock:
        return self.acquire()

    def __exit__(self, *exc) -> None:
        self.release()

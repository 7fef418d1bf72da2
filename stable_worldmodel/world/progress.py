"""Progress of long loops (recording, evaluation): a tqdm bar in a terminal, and plain lines on
stderr every :data:`LINE_SECONDS` (``STABLEWM_PROGRESS_SECONDS``) when stderr is not one (SLURM,
nohup, CI logs), so a long job is never silent."""

from __future__ import annotations

import os
import sys
import time
from typing import Any

#: seconds between two progress lines outside a terminal (``STABLEWM_PROGRESS_SECONDS`` overrides)
LINE_SECONDS = 30.0


class _Lines:
    """The part of tqdm's interface the loops use, written as a line every few seconds."""

    def __init__(self, total: int, desc: str, initial: int, unit: str):
        self.total, self.desc, self.n, self.unit = total, desc, initial, unit
        self.every = float(os.environ.get("STABLEWM_PROGRESS_SECONDS", LINE_SECONDS))
        self.start = self.last = time.monotonic()
        self.postfix = ""

    def set_postfix_str(self, text: str, refresh: bool = True) -> None:
        self.postfix = text

    def update(self, n: int = 1) -> None:
        self.n += n
        now = time.monotonic()
        if now - self.last < self.every:
            return
        self.last = now
        extra = f", {self.postfix}" if self.postfix else ""
        sys.stderr.write(f"{self.desc}: {self.n}/{self.total} {self.unit}{extra}, {now - self.start:.0f} s\n")
        sys.stderr.flush()

    def close(self) -> None:
        pass

    def __enter__(self) -> _Lines:
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()


class _Silent(_Lines):
    """A bar that counts and shows nothing (``enabled=False``)."""

    disable = True  # tqdm's name for it

    def update(self, n: int = 1) -> None:
        self.n += n


def progress(total: int, desc: str, *, enabled: bool, initial: int = 0, unit: str = "ep") -> Any:
    """A progress bar (terminal) or progress lines (otherwise) for ``total`` items; a silent
    one when not ``enabled``. Call ``update(k)`` per ``k`` items done (``update(0)`` refreshes)."""
    if not enabled:
        return _Silent(total, desc, initial, unit)
    if not sys.stderr.isatty():
        return _Lines(total, desc, initial, unit)
    from tqdm.auto import tqdm  # only for a bar drawn (the import alone costs ~50 ms)

    return tqdm(total=total, initial=initial, desc=desc, unit=unit, leave=False)

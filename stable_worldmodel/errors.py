"""Exceptions raised by stable_worldmodel.

Every user-facing error derives from :class:`SWMError` and also from the builtin it
refines, so ``except KeyError`` / ``except ValueError`` keep working in user code.
"""

from __future__ import annotations

import difflib
from collections.abc import Iterable

__all__ = [
    "SWMError",
    "UnknownNameError",
    "ConfigError",
    "SpaceError",
    "DependencyNotInstalled",
    "DatasetFormatError",
    "DatasetNotFoundError",
    "NotEnoughDataError",
    "DatasetBusyError",
    "RunBusyError",
    "UntrustedCheckpointError",
    "CheckpointError",
    "RunMismatchError",
    "DiskFullError",
    "check_int",
    "did_you_mean",
]


class SWMError(Exception):
    """Base class of all stable_worldmodel errors."""


class UnknownNameError(SWMError, KeyError):
    """A name (env id, solver, dataset, key, ...) that is not registered."""

    def __str__(self) -> str:  # KeyError quotes its message; we want plain text
        return str(self.args[0]) if self.args else ""


class ConfigError(SWMError, ValueError):
    """An argument or configuration value that cannot be accepted."""


class SpaceError(SWMError, ValueError):
    """A value, shape or dtype that does not fit a space."""


class DependencyNotInstalled(SWMError, ImportError):
    """An optional dependency is missing; the message gives the pip command."""


class DatasetFormatError(SWMError, ValueError):
    """A dataset file that does not have the expected layout."""


class ArgumentTypeError(SWMError, TypeError):
    """An argument of the wrong type where Python expects a TypeError (a dataset index that is not an int...)."""


class WorkerError(SWMError, RuntimeError):
    """An env worker process died, or its env raised (the World is then closed); or the
    workers cannot be started or used from here (an unguarded script, a forked child)."""


class DatasetNotFoundError(ConfigError, FileNotFoundError):
    """A dataset name or path that names nothing on disk; the message says where it looked and
    which datasets are there. Both a ``FileNotFoundError`` (what 0.1.1's ``load_dataset`` raised)
    and a ``ValueError`` (0.0.3's ``dataset_info``)."""


class NotEnoughDataError(SWMError, RuntimeError):
    """Asked for more than the data holds: a window longer than every episode, or a sample from
    an empty replay buffer."""


class DatasetBusyError(SWMError, BlockingIOError):
    """A dataset that another writer (named in the message) is writing."""


class RunBusyError(SWMError, BlockingIOError):
    """A training run that another trainer (named in the message) is writing."""


class UntrustedCheckpointError(SWMError, ValueError):
    """A checkpoint whose config names a ``_target_`` outside the trusted prefixes: nothing was
    imported or called; the message says how to trust it."""


class CheckpointError(ConfigError):
    """A checkpoint that cannot be used as it is: damaged, truncated, holding NaN/inf, or not the
    model its config describes (a :class:`ConfigError`, so a ``ValueError``)."""


class RunMismatchError(ConfigError):
    """A trained run used on an env, image size, action dimension or frameskip other than its own."""


class DiskFullError(SWMError, OSError):
    """A write that failed for lack of space (or a file-size limit); what was written before stays intact."""


def is_disk_full(exc: BaseException) -> bool:
    """``exc`` is an ``OSError`` of no space left, a full quota or a file-size limit (ENOSPC, EDQUOT, EFBIG)."""
    import errno

    return isinstance(exc, OSError) and exc.errno in (errno.ENOSPC, errno.EDQUOT, errno.EFBIG)


def check_int(owner: str, key: str, value: object, minimum: int = 1) -> int:
    """``value`` as an ``int`` when it is an integer (numpy integers too; bools refused) ``>= minimum``,
    else a :class:`ConfigError` ``"<owner> requires <key> to be an integer >= <minimum>, got <value>"``.
    The one check of integer arguments (sizes, counts, steps) across the package."""
    import numbers

    if (
        isinstance(value, bool)
        or type(value).__name__ == "bool_"
        or not isinstance(value, numbers.Integral)
        or value < minimum
    ):
        raise ConfigError(f"{owner} requires {key} to be an integer >= {minimum}, got {value!r}")
    return int(value)


def did_you_mean(name: str, candidates: Iterable[str], n: int = 3) -> str:
    """Return a ``" Did you mean 'x'?"`` suffix, or ``""`` when nothing is close."""
    candidates = list(dict.fromkeys(str(c) for c in candidates))  # each once, first occurrence first
    close = difflib.get_close_matches(str(name), candidates, n=n, cutoff=0.5)
    if not close:
        return ""
    if len(close) == 1:
        return f" Did you mean {close[0]!r}?"
    return " Did you mean one of " + ", ".join(repr(c) for c in close) + "?"


def unknown_name(kind: str, name: str, candidates: Iterable[str]) -> UnknownNameError:
    """Build an :class:`UnknownNameError` naming the bad value and the accepted ones."""
    candidates = sorted(set(str(c) for c in candidates))
    hint = did_you_mean(name, candidates)
    shown = ", ".join(candidates[:20]) + (" ..." if len(candidates) > 20 else "")
    return UnknownNameError(f"Unknown {kind} {name!r}.{hint} Accepted: {shown or '(none)'}")

"""How the ``swm`` command reports mistakes: one line on stderr, a non-zero exit, no traceback.

User errors are the library's typed errors (:class:`~stable_worldmodel.errors.SWMError`),
the ``KeyError`` / ``ValueError`` that stable_worldmodel code itself raises for bad
arguments, and Click's usage errors (missing argument, ``--episodes abc``). Anything else
(a ``ValueError`` from inside numpy or matplotlib included) is a bug and keeps its
traceback. Set ``SWM_DEBUG=1`` to see the traceback of a user error too.
"""

from __future__ import annotations

import os
import sys
from collections.abc import Iterable

from ..errors import ConfigError, SWMError, unknown_name

#: exit status of a bad command line (Click's convention) and of a rejected value
USAGE_EXIT = 2
USER_ERROR_EXIT = 1

USER_ERRORS: tuple[type[BaseException], ...] = (SWMError, KeyError, ValueError, FileNotFoundError, FileExistsError)


def one_line(message: str) -> str:
    """``message`` with every run of whitespace (newlines included) collapsed to one space."""
    return " ".join(str(message).replace("Value error, ", "").split())


def error_line(exc: BaseException) -> str:
    """The single ``Error: ...`` line shown for ``exc``."""
    if isinstance(exc, SWMError):
        text = str(exc)
    elif isinstance(exc, KeyError) and len(exc.args) == 1:
        text = f"unknown key {exc.args[0]!r}"
    else:
        text = str(exc) or type(exc).__name__
    return "Error: " + one_line(text)


def is_user_error(exc: BaseException) -> bool:
    """An :class:`SWMError`, or a ``KeyError`` / ``ValueError`` / missing or existing file raised by
    stable_worldmodel code itself."""
    if isinstance(exc, SWMError):
        return True
    if not isinstance(exc, USER_ERRORS):
        return False
    tb = exc.__traceback__
    if tb is None:
        return False
    while tb.tb_next is not None:
        tb = tb.tb_next
    return str(tb.tb_frame.f_globals.get("__name__", "")).startswith("stable_worldmodel")


def shows_traceback(exc: BaseException) -> bool:
    """True when ``exc`` must propagate with its traceback: not a user error, or ``SWM_DEBUG`` is set."""
    return bool(os.environ.get("SWM_DEBUG")) or not is_user_error(exc)


def report(exc: BaseException, code: int) -> int:
    """Write the error line of ``exc`` to stderr and return ``code``."""
    sys.stderr.write(error_line(exc) + "\n")
    sys.stderr.flush()
    return code


def warn(message: str) -> None:
    """Write ``message`` to stderr as one ``Warning: ...`` line (a warning the command goes on after)."""
    sys.stderr.write("Warning: " + one_line(message) + "\n")
    sys.stderr.flush()


def check_choice(what: str, value: str, accepted: Iterable[str], aliases: dict[str, str] | None = None) -> str:
    """Return ``value`` (or its alias target) when accepted, else raise a "did you mean" error."""
    accepted = list(accepted)
    value = (aliases or {}).get(value, value)
    if value not in accepted:
        raise unknown_name(what, value, accepted)
    return value


def int_in(low: int, high: int | None = None):
    """A Typer ``parser`` accepting integers in ``[low, high]``; its message names the bad value."""
    bounds = f">= {low}" if high is None else f"in [{low}, {high}]"

    def parse(value: object) -> int:
        try:
            number = int(str(value).strip())
        except ValueError:
            raise ValueError(f"expected an integer {bounds}, got {value!r}") from None
        if number < low or (high is not None and number > high):
            raise ValueError(f"expected an integer {bounds}, got {number}")
        return number

    return parse


def require(condition: bool, message: str) -> None:
    """Raise :class:`ConfigError` with ``message`` unless ``condition`` holds."""
    if not condition:
        raise ConfigError(message)


def output_dir(path, option: str):
    """``path`` created as a writable folder now, before long work; a ConfigError naming ``option`` otherwise."""
    from pathlib import Path

    from ..data.utils import usable_dir

    return usable_dir(Path(path).expanduser(), option)


def output_file(path, option: str):
    """``path`` checked as a file that can be written (its folder is created now); ConfigError otherwise."""
    from pathlib import Path

    path = Path(path).expanduser()
    if path.is_dir():
        raise ConfigError(f"{option} requires a file name, got {str(path)!r}, which is a folder")
    output_dir(path.parent, option)
    if path.exists() and not os.access(path, os.W_OK):
        raise ConfigError(f"{option} requires a file it can write, got {str(path)!r} (permission denied)")
    return path

"""How the spaces report problems: one shared logger and the error for values that fail ``check()``.

The logger is published as ``stable_worldmodel.spaces.logging`` (the name release 0.0.3 gave
its logger there), and every warning of this package goes through that attribute, read at call
time. So user code can capture the warnings either way::

    monkeypatch.setattr(swm.spaces.logging, "warning", fake)   # patch the method
    mock.patch("stable_worldmodel.spaces.logging")             # or swap the whole object

Messages are formatted before the call (one string argument, no ``%`` arguments), so a fake
``warning`` receives the complete text as its first argument.
"""

from __future__ import annotations

import logging as _stdlib_logging
import sys

from ..errors import SpaceError

__all__ = ["LOGGER", "SpaceCheckError", "warn"]

LOGGER = _stdlib_logging.getLogger("stable_worldmodel.spaces")


def warn(message: str) -> None:
    """Log ``message`` at WARNING through ``stable_worldmodel.spaces.logging`` as it is now."""
    package = sys.modules.get(__package__ or "")
    getattr(package, "logging", LOGGER).warning(message)


class SpaceCheckError(SpaceError, AssertionError):
    """Values that fail ``check()`` where valid ones are required (``Dict.update``, ``reset_variation_space``).

    Release 0.0.3 raised a bare ``AssertionError`` there, so this error is one too; it is also a
    :class:`~stable_worldmodel.errors.SpaceError` (and so a ``ValueError``).
    """

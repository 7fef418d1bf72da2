"""Number of factors of variation of each registered env, kept on disk between ``swm envs`` calls.

Counting an env's factors builds it, and building all of them takes ~11 s on a laptop core (Craftax's two ids
import JAX: ~6 s of it). The counts of the built-in envs are therefore kept in ``<cache>/envs/factor_counts.json``
(``<cache>``: :func:`~stable_worldmodel.data.get_cache_dir`), under a key made of the package version and a
fingerprint of the package's sources (path, size and modification time of every ``.py`` file): upgrading or
editing the package recomputes them. Envs registered from outside the package are built on every call. A cache that
cannot be read or written is skipped (logged at debug level); the counts are the same either way.
"""

from __future__ import annotations

import hashlib
import json
import logging
import os
from pathlib import Path

log = logging.getLogger(__name__)

_PACKAGE = Path(__file__).resolve().parent.parent
FILE_NAME = "factor_counts.json"


def sources_fingerprint(root: Path = _PACKAGE) -> str:
    """Version of ``stable_worldmodel`` plus a hash of (path, size, mtime) of the ``.py`` files under ``root``."""
    from .. import __version__

    digest = hashlib.sha256(__version__.encode())
    for folder, dirs, files in os.walk(root):
        dirs[:] = sorted(d for d in dirs if d != "__pycache__")
        for name in sorted(f for f in files if f.endswith(".py")):
            path = os.path.join(folder, name)
            stat = os.stat(path)
            digest.update(f"{os.path.relpath(path, root)}:{stat.st_size}:{stat.st_mtime_ns};".encode())
    return f"{__version__}:{digest.hexdigest()[:16]}"


def _is_builtin(env_id: str) -> bool:
    from . import get_entry

    return get_entry(env_id).entry_point.startswith("stable_worldmodel.")


class FactorCounts:
    """``counts.get(env_id)``: the env's number of factors (0 without a variation space), from the cache when it is
    there for the current sources, else by building the env (which may raise its ImportError). :meth:`save` writes
    the new ones back."""

    def __init__(self, cache_dir: str | os.PathLike | None = None):
        self.path: Path | None = None
        self.key = sources_fingerprint()
        self.counts: dict[str, int] = {}
        self._changed = False
        try:
            from ..data.utils import get_cache_dir

            self.path = get_cache_dir(cache_dir, "envs") / FILE_NAME
            stored = json.loads(self.path.read_text()) if self.path.is_file() else {}
            if isinstance(stored, dict) and stored.get("key") == self.key and isinstance(stored.get("counts"), dict):
                self.counts = {k: v for k, v in stored["counts"].items() if isinstance(v, int)}
        except (OSError, ValueError) as exc:  # unreadable cache: count from scratch
            log.debug("factor count cache skipped: %s", exc)

    def get(self, env_id: str) -> int:
        if env_id in self.counts:
            return self.counts[env_id]
        from ..planning.policies import variation_space_of

        space = variation_space_of(env_id)
        count = len(space.names()) if space is not None else 0
        if _is_builtin(env_id):
            self.counts[env_id] = count
            self._changed = True
        return count

    def save(self) -> None:
        """Write the counts (atomically: a reader sees the old file or the new one) when any was computed."""
        if not self._changed or self.path is None:
            return
        tmp = self.path.with_name(f".{FILE_NAME}.tmp{os.getpid()}")
        try:
            tmp.write_text(json.dumps({"key": self.key, "counts": self.counts}, indent=0, sort_keys=True))
            os.replace(tmp, self.path)
            self._changed = False
        except OSError as exc:
            log.debug("factor count cache not written: %s", exc)
            tmp.unlink(missing_ok=True)

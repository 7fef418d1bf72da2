"""Cache directory and small helpers shared by the dataset modules."""

from __future__ import annotations

import os
from pathlib import Path

__all__ = ["get_cache_dir", "resolve_dataset_path"]

ENV_VAR = "STABLEWM_HOME"
DEFAULT_DIRNAME = ".stable_worldmodel"


def get_cache_dir() -> Path:
    """Return the cache directory: ``$STABLEWM_HOME`` or ``~/.stable_worldmodel``.

    The variable is read at call time (never frozen at import) and the directory is
    created only when it does not exist yet.
    """
    root = os.environ.get(ENV_VAR)
    path = Path(root).expanduser() if root else Path.home() / DEFAULT_DIRNAME
    if not path.is_dir():
        path.mkdir(parents=True, exist_ok=True)
    return path


def resolve_dataset_path(name: str | os.PathLike, cache_dir: str | os.PathLike | None = None, suffix: str = ".h5") -> Path:
    """Map a dataset name to ``<cache_dir or get_cache_dir()>/<name><suffix>``.

    ``name`` is taken as a path when it ends with ``suffix``, is an existing file, or
    contains a directory part.
    """
    path = Path(name).expanduser()
    if str(name).endswith(suffix) or path.is_file() or len(path.parts) > 1:
        return path
    root = Path(cache_dir).expanduser() if cache_dir is not None else get_cache_dir()
    return root / f"{name}{suffix}"

"""Cache directory and small helpers shared by the dataset modules."""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

__all__ = ["dataset_file", "get_cache_dir", "resolve_dataset_path"]

ENV_VAR = "STABLEWM_HOME"
DEFAULT_DIRNAME = ".stable_worldmodel"


def _usable_dir(path: Path, what: str) -> Path:
    """``path`` as a folder we can write to (created if missing); ConfigError otherwise."""
    from ..errors import ConfigError

    if path.exists() and not path.is_dir():
        raise ConfigError(f"{what} requires a folder, got {str(path)!r}, which is a file; point it at a folder")
    try:
        path.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise ConfigError(f"{what} requires a folder that can be created, got {str(path)!r}: {exc.strerror or exc}") from None
    if not os.access(path, os.W_OK | os.X_OK):
        raise ConfigError(f"{what} requires a writable folder, got {str(path)!r} (permission denied)")
    return path


def get_cache_dir() -> Path:
    """Return the cache directory: ``$STABLEWM_HOME`` or ``~/.stable_worldmodel``.

    The variable is read at call time (never frozen at import) and the directory is
    created only when it does not exist yet. A file, or a folder that cannot be created or
    written, is a :class:`~stable_worldmodel.errors.ConfigError`.
    """
    root = os.environ.get(ENV_VAR)
    if root:
        return _usable_dir(Path(root).expanduser(), f"the cache folder (${ENV_VAR})")
    return _usable_dir(Path.home() / DEFAULT_DIRNAME, "the cache folder (~/.stable_worldmodel)")


def resolve_dataset_path(name: str | os.PathLike, cache_dir: str | os.PathLike | None = None, suffix: str = ".h5") -> Path:
    """Map a dataset name to ``<cache_dir or get_cache_dir()>/<name><suffix>``.

    ``name`` is taken as a path when it ends with ``suffix`` or is an existing file; names
    with folders (``"pusht/shard_0"``) stay under the cache folder.
    """
    path = Path(name).expanduser()
    if str(name).endswith(suffix) or path.is_file():
        return path
    root = Path(cache_dir).expanduser() if cache_dir is not None else get_cache_dir()
    return root / f"{name}{suffix}"


def dataset_file(name: Any, cache_dir: str | os.PathLike | None = None, suffix: str = ".h5") -> Path:
    """The file a recording named ``name`` is written to: ``<cache_dir>/<name><suffix>``, checked.

    ``name`` is a non-empty relative name; folders in it (``"pusht/shard_0"``) are kept, under
    the cache folder; a name that is absolute, climbs out with ``..``, holds a NUL or already
    ends in ``suffix`` is a :class:`~stable_worldmodel.errors.ConfigError`.
    """
    from ..errors import ConfigError

    def bad(why: str) -> ConfigError:
        return ConfigError(f"record_dataset requires a dataset name such as 'pusht' or 'pusht/shard_0', got {name!r}: {why}")

    if not isinstance(name, (str, os.PathLike)):
        raise bad(f"a {type(name).__name__}, not a string")
    text = os.fspath(name)
    if not isinstance(text, str) or not text.strip():
        raise bad("an empty name")
    if "\0" in text:
        raise bad("it contains a NUL character")
    if Path(text).is_absolute() or text.startswith("~"):
        raise bad("an absolute path; give a name and pass cache_dir= for the folder")
    if ".." in Path(text).parts:
        raise bad("'..' would leave the cache folder")
    if text.endswith(suffix):
        raise bad(f"drop the {suffix!r}, it is added")
    where = "cache_dir" if cache_dir is not None else "the cache folder"
    root = _usable_dir(Path(cache_dir).expanduser(), where) if cache_dir is not None else get_cache_dir()
    return root / f"{text}{suffix}"

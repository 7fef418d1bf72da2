"""Cache directory and small helpers shared by the dataset modules."""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import numpy as np

__all__ = [
    "column_normalizer",
    "dataset_file",
    "get_cache_dir",
    "dataset_candidates",
    "ensure_dir_exists",
    "load_dataset",
    "resolve_dataset",
    "resolve_dataset_dir",
    "resolve_dataset_path",
]

ENV_VAR = "STABLEWM_HOME"
DEFAULT_DIRNAME = ".stable_worldmodel"
DATASETS_SUBFOLDER = "datasets"  # where 0.1.1 keeps datasets inside the cache


def usable_dir(path: Path, what: str) -> Path:
    """``path`` as a folder we can write to (created if missing); ConfigError otherwise."""
    from ..errors import ConfigError

    if path.exists() and not path.is_dir():
        raise ConfigError(f"{what} requires a folder, got {str(path)!r}, which is a file; point it at a folder")
    try:
        path.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise ConfigError(
            f"{what} requires a folder that can be created, got {str(path)!r}: {exc.strerror or exc}"
        ) from None
    if not os.access(path, os.W_OK | os.X_OK):
        raise ConfigError(f"{what} requires a writable folder, got {str(path)!r} (permission denied)")
    return path


def get_cache_dir(
    cache_dir: str | os.PathLike | None = None,
    sub_folder: str | None = None,
    *,
    override_root: str | os.PathLike | None = None,
) -> Path:
    """Return the cache directory: ``cache_dir``, else ``$STABLEWM_HOME``, else ``~/.stable_worldmodel``;
    with ``sub_folder`` (``"datasets"``), that folder inside it.

    ``override_root`` is 0.1.1's name of ``cache_dir``. The variable is read at call time
    (never frozen at import) and the folder is created only when it does not exist yet. A
    file, or a folder that cannot be created or written, is a
    :class:`~stable_worldmodel.errors.ConfigError`.
    """
    from ..errors import ConfigError

    if override_root is not None:
        if cache_dir is not None:
            raise ConfigError(
                "get_cache_dir requires cache_dir or override_root (the same thing), "
                f"got both: {cache_dir!r} and {override_root!r}"
            )
        cache_dir = override_root
    if cache_dir is not None:
        root = usable_dir(Path(cache_dir).expanduser(), "get_cache_dir(cache_dir=...)")
    elif os.environ.get(ENV_VAR):
        root = usable_dir(Path(os.environ[ENV_VAR]).expanduser(), f"the cache folder (${ENV_VAR})")
    else:
        root = usable_dir(Path.home() / DEFAULT_DIRNAME, "the cache folder (~/.stable_worldmodel)")
    if sub_folder is None:
        return root
    sub = Path(str(sub_folder))
    if not str(sub_folder).strip() or sub.is_absolute() or ".." in sub.parts:
        raise ConfigError(
            "get_cache_dir requires sub_folder to be a folder name inside the cache such as 'datasets', "
            f"got {sub_folder!r}"
        )
    return usable_dir(root / sub, f"the cache sub-folder {str(sub_folder)!r}")


def ensure_dir_exists(path: str | os.PathLike) -> None:
    """Create folder ``path`` and its parents when missing (upstream 0.1.1's helper)."""
    Path(path).mkdir(parents=True, exist_ok=True)


def _root(cache_dir: str | os.PathLike | None) -> Path:
    return Path(cache_dir).expanduser() if cache_dir is not None else get_cache_dir()


def _folder_like(text: str) -> bool:
    """``text`` ends in a path separator (``/``, or ``os.sep``/``os.altsep`` where they differ)."""
    return text.endswith(tuple({"/", os.sep, os.altsep or "/"}))


def _strip_seps(text: str) -> str:
    return text.rstrip("".join({"/", os.sep, os.altsep or "/"}))


def resolve_dataset_path(
    name: str | os.PathLike, cache_dir: str | os.PathLike | None = None, suffix: str = ".h5"
) -> Path:
    """Map a dataset name to ``<cache_dir or get_cache_dir()>/<name><suffix>``.

    A name ending in ``/`` is a :class:`~stable_worldmodel.errors.ConfigError` unless it names the
    folder of a sharded dataset (``"x/"`` + suffix would be the hidden file ``x/.h5``).

    ``name`` is taken as a path when it ends with ``suffix`` or is an existing file; names
    with folders (``"pusht/shard_0"``) stay under the cache folder. A name found only in
    the ``datasets`` sub-folder (where 0.1.1 keeps them) resolves there. A sharded dataset (a
    folder ``<name>/`` of ``shard_*<suffix>`` files and no ``<name><suffix>``) resolves to its folder.
    """
    path = Path(name).expanduser()
    if str(name).endswith(suffix) or path.is_file():
        return path
    if _is_shard_folder(path, suffix):
        return path
    root = _root(cache_dir)
    folder = root / str(name)
    if _folder_like(str(name)):  # a sharded dataset's folder, or nothing ('x/' + suffix would be x/.h5)
        if _is_shard_folder(folder, suffix):
            return folder
        from ..errors import ConfigError

        raise ConfigError(
            f"A dataset name requires no trailing {str(name)[-1]!r} "
            f"(unless it names a folder of shard_*{suffix} files), "
            f"got {str(name)!r}; did you mean {_strip_seps(str(name))!r}?"
        )
    for candidate in dataset_candidates(str(name), cache_dir, suffix):
        if candidate.is_file() if candidate.name.endswith(suffix) else _is_shard_folder(candidate, suffix):
            return candidate
    return root / f"{name}{suffix}"


def _is_shard_folder(path: Path, suffix: str = ".h5") -> bool:
    return path.is_dir() and any(path.glob(f"shard_*{suffix}"))


def resolve_dataset_dir(name: str | os.PathLike, cache_dir: str | os.PathLike | None = None) -> Path:
    """``name`` as a directory path when it exists or is absolute, else the first folder of
    :func:`dataset_candidates` that exists (``<cache_dir>/<name>``, ``<cache_dir>/datasets/<name>``),
    else ``<cache_dir>/<name>``."""
    path = Path(name).expanduser()
    if path.is_dir() or path.is_absolute():
        return path
    for candidate in dataset_candidates(str(name), cache_dir):
        if candidate.is_dir():
            return candidate
    return path if len(path.parts) > 1 else _root(cache_dir) / str(name)


def dataset_file(name: Any, cache_dir: str | os.PathLike | None = None, suffix: str = ".h5") -> Path:
    """The file a recording named ``name`` is written to: ``<cache_dir>/<name><suffix>``, checked.

    ``name`` is a non-empty relative name; folders in it (``"pusht/shard_0"``) are kept, under
    the cache folder; a name that is absolute, climbs out with ``..``, holds a NUL or already
    ends in ``suffix`` is a :class:`~stable_worldmodel.errors.ConfigError`.
    """
    from ..errors import ConfigError

    def bad(why: str) -> ConfigError:
        return ConfigError(
            f"record_dataset requires a dataset name such as 'pusht' or 'pusht/shard_0', got {name!r}: {why}"
        )

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
    if _folder_like(text):  # Path() drops the slash: 'x/' would be written as the hidden file x/.h5
        raise bad(f"a name ending in {text[-1]!r} names a folder; did you mean {_strip_seps(text)!r}?")
    if text.endswith(suffix):
        raise bad(f"drop the {suffix!r}, it is added")
    where = "cache_dir" if cache_dir is not None else "the cache folder"
    root = usable_dir(Path(cache_dir).expanduser(), where) if cache_dir is not None else get_cache_dir()
    return root / f"{text}{suffix}"


def dataset_candidates(name: str, cache_dir: str | os.PathLike | None = None, suffix: str = ".h5") -> list[Path]:
    """Where a dataset named ``name`` may be in the cache folder, in the order they are tried:
    ``<name><suffix>``, ``<name>.lance``, ``<name>/`` (a folder format, or shards), then the same
    inside ``datasets/`` (where 0.1.1 keeps them). A name ending in a separator names only folders."""
    root = _root(cache_dir)
    text = _strip_seps(name) if _folder_like(name) else name
    found = []
    for base in (root, root / DATASETS_SUBFOLDER):
        if not _folder_like(name):
            found.append(base / f"{text}{suffix}")
            if suffix == ".h5":
                found.append(base / f"{text}.lance")
        found.append(base / text)
    return found


def resolve_dataset(
    name: str | os.PathLike, cache_dir: str | os.PathLike | None = None, *, who: str = "load_dataset"
) -> Path:
    """The existing file or folder that dataset ``name`` names: a path (absolute, or existing
    relative to the working folder), else the first of :func:`dataset_candidates` that exists.

    The one lookup of a dataset by name, whatever its format (:func:`load_dataset`, the trainer,
    ``dataset_info``, ``delete_dataset``). Raises
    :class:`~stable_worldmodel.errors.DatasetNotFoundError` (a ``FileNotFoundError``) naming
    ``who``, the places it looked and the closest cached names.
    """
    from ..errors import DatasetNotFoundError, did_you_mean

    text = os.fspath(name)
    path = Path(text).expanduser()
    if path.is_absolute() or path.exists():
        if path.exists():
            return path
        raise DatasetNotFoundError(f"{who} requires an existing dataset, got {text!r}: the path does not exist")
    root = _root(cache_dir)
    candidates = dataset_candidates(text, cache_dir)
    for candidate in candidates:
        if candidate.exists():
            return candidate
    from .info import list_datasets

    known = list_datasets(cache_dir)
    hub = (
        " Downloading from the Hugging Face Hub is not supported: download it into that folder first."
        if "/" in text.strip("/")
        else ""
    )
    looked = ", ".join(str(c.relative_to(root)) for c in candidates)
    there = ", ".join(known[:10]) + (f" and {len(known) - 10} more" if len(known) > 10 else "") or "(none)"
    raise DatasetNotFoundError(
        f"{who} requires an existing dataset, got {text!r}: it does not exist in {root} "
        f"(looked for {looked}).{did_you_mean(text, known)}{hub} Datasets there: {there}"
    )


def load_dataset(
    name: str | os.PathLike,
    cache_dir: str | os.PathLike | None = None,
    format: str | None = None,
    *,
    num_steps: int = 1,
    frameskip: int = 1,
    keys_to_load: Any = None,
    keys_to_cache: Any = None,
    transform: Any = None,
    **kwargs: Any,
) -> Any:
    """Open dataset ``name`` with the reader of its format (as 0.1.1): a path, or a name in
    ``cache_dir`` (default :func:`get_cache_dir`; ``datasets/`` inside it is searched too).

    The format is detected (:func:`~stable_worldmodel.data.format.detect_format`) unless
    ``format`` names one. The other arguments go to the reader; ``keys_to_cache`` only
    where the reader takes it (HDF5). Returns the reader, e.g. an
    :class:`~stable_worldmodel.data.HDF5Dataset`.
    """
    from ..errors import ConfigError, DatasetFormatError
    from .format import detect_format, get_format, list_formats

    text = os.fspath(name) if isinstance(name, (str, os.PathLike)) else None
    if not isinstance(text, str) or not text.strip():
        raise ConfigError(f"load_dataset requires a dataset name or path, got {name!r}")
    options = dict(num_steps=num_steps, frameskip=frameskip, keys_to_load=keys_to_load, transform=transform, **kwargs)
    if keys_to_cache is not None:
        options["keys_to_cache"] = keys_to_cache
    if "://" in text:  # a URL: opened only by a format that reads its scheme (lerobot://org/name)
        scheme = text.split("://", 1)[0]
        formats = [get_format(n) for n in ([format] if format is not None else list_formats())]
        fmt = next((f for f in formats if scheme in getattr(f, "schemes", ()) and f.detect(text)), None)
        if fmt is None:
            which = f"format {format!r} does not read" if format is not None else "no registered format reads"
            raise ConfigError(
                f"load_dataset requires a local dataset, got the URL {text!r}: "
                f"{which} {scheme}:// URLs (formats: {', '.join(list_formats())})"
            )
        return fmt.open_reader(text, **options)
    path = resolve_dataset(text, cache_dir)
    if path.is_dir() and format is None and detect_format(path) is None:
        files = sorted(path.glob("*.h5")) + sorted(path.glob("*.hdf5"))
        if len(files) == 1:  # a folder holding one HDF5 file (0.1.1's cache layout)
            path = files[0]
    fmt = get_format(format) if format is not None else detect_format(path)
    if fmt is None:
        raise DatasetFormatError(
            f"load_dataset requires a dataset in a registered format ({', '.join(list_formats())}), got {str(path)!r}, "
            "which none of them recognises; pass format= to force one"
        )
    return fmt.open_reader(path, **options)


def column_normalizer(dataset: Any, source: str, target: str, method: str = "zscore") -> Any:
    """A picklable item transform that writes ``item[target] = scaler(item[source])``, with a
    scaler (``"zscore"``, ``"percentile"`` or ``"none"``) fitted on ``dataset.get_col_data(source)``."""
    from .normalization import ColumnTransform, get_scaler

    scaler = get_scaler(method)
    if method != "none":
        import numpy as np

        scaler.fit(np.asarray(dataset.get_col_data(source)))
    return ColumnTransform(scaler, source=source, target=target)


def convert(
    source: Any,
    dest: str | os.PathLike,
    *,
    source_format: str | None = None,
    dest_format: str = "hdf5",
    cache_dir: str | os.PathLike | None = None,
    progress: bool = True,
    **dest_kwargs: Any,
) -> Path:
    """Copy dataset ``source`` (anything :func:`load_dataset` opens) to ``dest`` in ``dest_format``, episode by episode.

    Upstream 0.1.1's function; the default destination is HDF5 here (upstream's: Lance;
    ``dest_format="lance"`` writes one). ``dest`` gets ``.h5`` (``.lance``) when it has no
    suffix. ``dest_kwargs`` go to the destination writer (e.g. ``mode="overwrite"`` for the
    folder and video formats). Returns the path written.
    """
    from tqdm.auto import tqdm

    from .format import get_format

    src = load_dataset(source, cache_dir=cache_dir, format=source_format)
    fmt = get_format(dest_format)
    dest = Path(dest).expanduser()
    if fmt.name == "hdf5" and dest.suffix not in (".h5", ".hdf5"):
        dest = dest.with_name(dest.name + ".h5")
    if fmt.name == "lance" and dest.suffix.lower() != ".lance":
        dest = dest.with_name(dest.name + ".lance")
    columns = list(getattr(src, "stored_columns", None) or src.column_names)
    data = {col: np.asarray(src.get_col_data(col)) for col in columns}
    lengths, offsets = np.asarray(src.lengths, np.int64), np.asarray(src.offsets, np.int64)
    dest.parent.mkdir(parents=True, exist_ok=True)
    with fmt.open_writer(dest, **dest_kwargs) as writer:
        for ep in tqdm(range(len(lengths)), desc=f"Converting to {fmt.name}", unit="ep", disable=not progress):
            start, stop = int(offsets[ep]), int(offsets[ep] + lengths[ep])
            episode = {col: values[start:stop] for col, values in data.items()}
            if hasattr(writer, "write_episode"):
                writer.write_episode(episode)
            else:
                writer.write_episodes([episode])
    return dest

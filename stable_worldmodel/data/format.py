"""The dataset format registry: one :class:`Format` per on-disk layout.

A format is a class with a ``name`` (the registry key, also ``format=`` of
:func:`~stable_worldmodel.data.load_dataset`), ``detect(path)`` (cheap: a suffix, a marker
file), ``open_reader(path, **kw)``, ``open_writer(path, **kw)`` and ``summary(path)`` (what
``swm show dataset`` prints). Adding one is a file plus a decorator::

    @register_format
    class Parquet(Format):
        name = "parquet"

        @classmethod
        def detect(cls, path):
            return Path(path).suffix == ".parquet"

        @classmethod
        def open_reader(cls, path, **kwargs):
            from .my_reader import ParquetDataset  # heavy imports stay here
            return ParquetDataset(path, **kwargs)

The built-in formats (``data/formats/``) are registered on the first lookup; detection
tries formats in registration order, built-ins first.
"""

from __future__ import annotations

import logging
import os
from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import Any, ClassVar, Protocol, runtime_checkable

import numpy as np

from .. import keys
from ..errors import ConfigError, did_you_mean

__all__ = [
    "BatchedCommits",
    "EPISODE_DATA_KEY",
    "FORMATS",
    "WRITE_MODES",
    "Format",
    "Writer",
    "describe",
    "detect_format",
    "get_format",
    "list_formats",
    "register_format",
    "split_episode_data",
    "validate_write_mode",
]

logger = logging.getLogger(__name__)

FORMATS: dict[str, type[Format]] = {}

#: the ``mode`` every built-in writer takes (upstream's names): ``"append"`` (the default: extend
#: a dataset already there, create it otherwise), ``"overwrite"`` (remove it first) or
#: ``"error"`` (``FileExistsError`` when there is one)
WRITE_MODES = ("append", "overwrite", "error")

#: the episode-dict key of episode-scoped data (one value per episode, not per step; upstream's
#: main). No built-in writer stores it: they drop it with a warning (see :func:`split_episode_data`).
EPISODE_DATA_KEY = "_episode_data"


def validate_write_mode(mode: Any, owner: str = "writer") -> str:
    """``mode`` if it is one of :data:`WRITE_MODES`; :class:`ConfigError` (a ValueError) otherwise."""
    if not isinstance(mode, str) or mode not in WRITE_MODES:
        raise ConfigError(
            f"{owner} requires mode to be one of {', '.join(map(repr, WRITE_MODES))}, "
            f"got {mode!r}.{did_you_mean(str(mode), WRITE_MODES)}"
        )
    return mode


def split_episode_data(episode: Mapping[str, Any]) -> tuple[Mapping[str, Any], dict[str, Any]]:
    """``(per-step columns, episode-scoped data)`` of an episode dict: the second is what it holds
    under :data:`EPISODE_DATA_KEY` (empty when absent); ``episode`` itself is not changed."""
    if EPISODE_DATA_KEY not in episode:
        return episode, {}
    steps = {k: v for k, v in episode.items() if k != EPISODE_DATA_KEY}
    return steps, dict(episode[EPISODE_DATA_KEY] or {})


def per_step_columns(episode: Mapping[str, Any], owner: str) -> Mapping[str, Any]:
    """The per-step columns of ``episode``, for a writer that stores no episode-scoped data: a
    warning names what it drops."""
    steps, data = split_episode_data(episode)
    if data:
        logger.warning("%s stores no episode-scoped data: dropped %s", owner, ", ".join(sorted(map(str, data))))
    return steps


@runtime_checkable
class Writer(Protocol):
    """What ``World.collect(writer=...)``, :func:`~stable_worldmodel.data.convert` and
    ``ReplayBuffer.dump`` write into: a context manager taking episodes (mappings column ->
    ``(L, ...)`` rows, or per-step lists) one at a time or from an iterable."""

    def __enter__(self) -> Any: ...
    def __exit__(self, *exc: Any) -> Any: ...
    def write_episode(self, episode: Mapping[str, Any]) -> None: ...
    def write_episodes(self, episodes: Iterable[Mapping[str, Any]]) -> None: ...


class BatchedCommits:
    """Mixin of a :class:`Writer` that commits ``commit_episodes`` episodes at a time through its
    ``_commit(batch)``: ``write_episode``, ``write_episodes`` and the context manager (``close`` on exit)."""

    commit_episodes: int = 32

    def __enter__(self) -> Any:
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()

    def write_episode(self, episode: Mapping[str, Any]) -> None:
        """Append one episode (one commit)."""
        self.write_episodes([episode])

    def write_episodes(self, episodes: Any, next_seed: int | None = None) -> None:
        """Append ``episodes`` (any iterable), one commit per ``commit_episodes`` of them."""
        batch: list = []
        for episode in episodes:
            batch.append(episode)
            if len(batch) == self.commit_episodes:
                self._commit(batch)
                batch = []
        if batch:
            self._commit(batch)


class Format:
    """One on-disk dataset layout (see the module docstring). Methods are classmethods."""

    name: ClassVar[str] = ""
    summary_options: ClassVar[dict[str, Any]] = {}  # reader arguments that keep summary() cheap
    #: whether the writer stores episode-scoped data (:data:`EPISODE_DATA_KEY`); none built in does
    supports_episode_data: ClassVar[bool] = False

    @classmethod
    def detect(cls, path: str | os.PathLike) -> bool:
        raise NotImplementedError("detect(path) -> bool: does path hold a dataset in this format?")

    @classmethod
    def open_reader(cls, path: str | os.PathLike, **kwargs: Any) -> Any:
        raise NotImplementedError(
            f"format {cls.name!r} does not support reading: open_reader(path, **kwargs) -> Dataset"
        )

    @classmethod
    def open_writer(cls, path: str | os.PathLike, **kwargs: Any) -> Any:
        raise NotImplementedError(
            f"format {cls.name!r} does not support writing (read-only): open_writer(path, **kwargs) -> writer"
        )

    @classmethod
    def summary(cls, path: str | os.PathLike) -> dict[str, Any]:
        """What ``swm show dataset`` prints: see :func:`describe`."""
        ds = cls.open_reader(path, **cls.summary_options)
        try:
            return describe(ds, cls.name, path)
        finally:
            close = getattr(ds, "close", None)  # readers holding a file handle
            if close is not None:
                close()


def register_format(cls: type[Format]) -> type[Format]:
    """Class decorator adding ``cls`` to :data:`FORMATS` under ``cls.name``."""
    name = getattr(cls, "name", "")
    if not isinstance(name, str) or not name:
        raise ConfigError(
            f"register_format requires a class with a non-empty string `name`, got {cls.__name__} with name={name!r}"
        )
    known = FORMATS.get(name)
    if known is not None and known.__qualname__ != cls.__qualname__:
        raise ConfigError(
            f"register_format requires a new format name, got {name!r}, already registered by {known.__qualname__}"
        )
    FORMATS[name] = cls
    return cls


def _builtins() -> None:
    from . import formats  # noqa: F401  (registers hdf5, video, folder, video-meta, folder-meta)


def list_formats() -> list[str]:
    """Registered format names, in detection order."""
    _builtins()
    return list(FORMATS)


def get_format(name: str) -> type[Format]:
    """The format registered as ``name``; unknown names raise :class:`ConfigError` (a ValueError) with a suggestion."""
    _builtins()
    if name not in FORMATS:
        raise ConfigError(
            f"get_format requires a registered format ({', '.join(FORMATS)}), got {name!r} "
            f"(not found).{did_you_mean(str(name), FORMATS)}"
        )
    return FORMATS[name]


def detect_format(path: str | os.PathLike) -> type[Format] | None:
    """The first registered format whose ``detect(path)`` (given a :class:`~pathlib.Path`) is true, else None."""
    _builtins()
    path = Path(path)
    for fmt in FORMATS.values():
        if fmt.detect(path):
            return fmt
    return None


def describe(ds: Any, format_name: str, path: str | os.PathLike) -> dict[str, Any]:
    """The summary of an open dataset: path, format, num_episodes, num_steps (rows), columns,
    obs/action/goal row shapes, episode_length min/max/mean and variation names."""
    columns = list(ds.column_names)
    lengths = np.asarray(ds.lengths)

    def shape(col: str) -> tuple[int, ...] | None:
        if col not in columns or not lengths.sum():
            return None
        row_shape = getattr(ds, "row_shape", None)  # ours; other readers: from one row
        return tuple(row_shape(col)) if row_shape is not None else tuple(np.shape(ds.get_row_data(0)[col]))

    variations = sorted(c[len(keys.VARIATION) + 1 :] for c in columns if c.startswith(keys.VARIATION + "."))
    return {
        "path": str(Path(path)),
        "format": format_name,
        "num_episodes": int(len(lengths)),
        "num_steps": int(lengths.sum()),
        "columns": columns,
        "obs_shape": shape(keys.PIXELS),
        "action_shape": shape(keys.ACTION),
        "goal_shape": shape(keys.GOAL),
        "episode_length": {
            "min": int(lengths.min()) if lengths.size else 0,
            "max": int(lengths.max()) if lengths.size else 0,
            "mean": float(lengths.mean()) if lengths.size else 0.0,
        },
        "variation": {"has_variation": bool(variations), "names": variations},
    }

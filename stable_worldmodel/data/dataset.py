"""The :class:`Dataset` base shared by every dataset kind: episodes, windows, items.

A dataset is a set of episodes stored as flat columns (rows of all episodes concatenated,
episode ``e`` at rows ``offsets[e] : offsets[e] + lengths[e]``). A *sample* is a window of
``num_steps`` frames spaced by ``frameskip`` inside one episode; it reads the
``span = num_steps * frameskip`` rows starting at the window start::

    rows    s  s+1 ... s+fs-1 | s+fs ... | ... s+span-1
    frames  x                 | x        | ...            -> every column[::frameskip]  (T, ...)
    action  a  a   ...  a     | a ...    | ...            -> action (T, frameskip * A)

Every start with ``start + span <= length`` is a sample (no duplicates). Images come out
as ``(T, C, H, W)`` uint8 tensors, everything else as ``(T, ...)`` tensors.

Subclasses implement ``stored_columns`` (or set ``_columns``) and ``_read(col, start, stop) ->
np.ndarray`` (rows of one column) and give ``lengths`` / ``offsets`` (to ``__init__``, by
assignment, or as properties); the rest (indexing, items, episodes, chunks) lives here.
``column_names`` are the columns put in items (``keys_to_load``, by default all, as in 0.0.3).

Subclasses written for release 0.0.3 work unchanged: they call
``super().__init__(lengths, offsets, frameskip, num_steps, transform)`` and implement
``_load_slice(ep_idx, start, end) -> dict`` (frames of one episode, already strided and
transformed) instead of ``_read``; items, episodes and chunks then come from ``_load_slice``.
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Collection, Sequence
from typing import Any

import numpy as np

from .. import keys
from ..errors import ArgumentTypeError, ConfigError, UnknownNameError, check_int, did_you_mean
from ._ipc import prepare_worker

logger = logging.getLogger(__name__)

try:  # the base class of every dataset kind: a torch Dataset when torch is there
    from torch.utils.data import Dataset as _TorchDataset
except ImportError:  # pragma: no cover - torch is a base dependency
    _TorchDataset = object


def _positive(name: str, value: Any, owner: str) -> int:
    return check_int(owner, name, value)


def missing_column(owner: str, name: str, columns: Sequence[str]) -> UnknownNameError:
    """``UnknownNameError`` (a KeyError) for a column ``name`` that ``owner`` does not have."""
    return UnknownNameError(
        f"{owner} column {name!r} not found.{did_you_mean(str(name), columns)} "
        f"Columns: {', '.join(columns) or '(none)'}"
    )


def image_like(arr: np.ndarray) -> bool:
    """Rows ``(N, H, W, C)`` uint8 with C in 1, 3, 4."""
    from .writer import is_image_column

    return arr.ndim == 4 and is_image_column(arr.shape[1:], arr.dtype)


def dense_set(columns: Collection[str] | str | None, owner: str) -> frozenset[str]:
    """``action`` plus ``columns`` (a name or a collection of names): the columns a window reads
    at every row (grouped into ``frameskip`` blocks) instead of every ``frameskip``-th row."""
    extra = [columns] if isinstance(columns, str) else list(columns or ())
    if not all(isinstance(c, str) for c in extra):
        raise ConfigError(f"{owner} requires dense_columns to be column names, got {columns!r}")
    return frozenset({keys.ACTION, *extra})


def group_dense(col: str, rows: Any, num_steps: int, batched: bool = False) -> Any:
    """Rows of a window's dense column, ``(T * frameskip, ...)`` (``(B, ...)`` first when ``batched``),
    grouped per frame: ``action`` into ``(T, frameskip * A)`` blocks, every other dense column into
    ``(T, frameskip, ...)`` (upstream main's convention, a singleton axis when ``frameskip`` is 1)."""
    lead = (rows.shape[0],) if batched else ()
    if col == keys.ACTION:
        return rows.reshape(*lead, num_steps, -1)
    tail = tuple(rows.shape[len(lead) + 1 :])
    return rows.reshape(*lead, num_steps, -1, *tail)


def _episode_array(name: str, value: Any, owner: str) -> np.ndarray:
    """``value`` as a 1-D int64 array of non-negative row counts or offsets."""
    arr = np.asarray(value)
    if arr.ndim != 1 or not (arr.size == 0 or np.issubdtype(arr.dtype, np.integer)) or (arr.size and arr.min() < 0):
        hint = (
            "; frameskip, num_steps and transform now follow lengths and offsets: pass them by keyword"
            if arr.ndim == 0
            else ""
        )
        raise ConfigError(
            f"{owner} requires {name} to be a 1-D sequence of non-negative ints (one per episode), got {value!r}{hint}"
        )
    return arr.astype(np.int64)


class Dataset(_TorchDataset):
    """Episodes of flat columns, sampled as windows (see the module docstring).

    Args:
        lengths: rows of each episode ``(E,)``; subclasses may set ``lengths`` later instead.
        offsets: first row of each episode ``(E,)`` (default: episodes back to back).
        frameskip: rows between two sampled frames.
        num_steps: frames per sample (T).
        transform: optional callable applied to each item dict.
        keys_to_load: columns to put in items (default: all).
        dense_columns: columns read at every row of a window, as ``action`` always is, and
            grouped per frame into ``(T, frameskip, ...)`` (upstream's main; ``action``:
            ``(T, frameskip * A)``).
    """

    #: ``action`` and the ``dense_columns`` given (see :func:`dense_set`)
    dense_columns: frozenset[str] = frozenset({keys.ACTION})

    def __init__(
        self,
        lengths: Sequence[int] | np.ndarray | None = None,
        offsets: Sequence[int] | np.ndarray | None = None,
        frameskip: int = 1,
        num_steps: int = 1,
        transform: Callable[[dict], dict] | None = None,
        keys_to_load: Sequence[str] | None = None,
        dense_columns: Collection[str] | str | None = None,
    ):
        owner = type(self).__name__
        self.dense_columns = dense_set(dense_columns, owner)
        self.frameskip = _positive("frameskip", frameskip, owner)
        self.num_steps = _positive("num_steps", num_steps, owner)
        if transform is not None and not callable(transform):
            raise ConfigError(
                f"{owner} requires transform to be a callable (item dict -> item dict) or None, got {transform!r}"
            )
        self.transform = transform
        if keys_to_load is not None:
            if isinstance(keys_to_load, (str, bytes)):
                raise ConfigError(
                    f"{owner} requires keys_to_load to be a list of column names, "
                    f"got the string {keys_to_load!r}; write [{keys_to_load!r}]"
                )
            keys_to_load = list(keys_to_load)
            if not keys_to_load or not all(isinstance(k, str) for k in keys_to_load):
                raise ConfigError(
                    f"{owner} requires keys_to_load to be a non-empty list of column names "
                    f"(or None for all), got {keys_to_load!r}"
                )
        self._keys_to_load = keys_to_load
        self._index: tuple[np.ndarray, np.ndarray] | None = None
        self._clips: list[tuple[int, int]] | None = None  # set only through ``clip_indices = ...``
        if offsets is not None and lengths is None:
            raise ConfigError(f"{owner} requires lengths together with offsets, got offsets only")
        if lengths is not None:
            self.lengths = lengths
            self.offsets = offsets if offsets is not None else np.concatenate([[0], np.cumsum(self._lengths)[:-1]])

    def check_span(self) -> None:
        """Raise unless some episode is long enough for one sample (``num_steps * frameskip`` rows)."""
        lengths = np.asarray(self.lengths)
        if len(lengths) and int(lengths.max()) < self.span:
            raise ConfigError(
                f"{type(self).__name__} requires num_steps * frameskip <= the longest episode "
                f"({int(lengths.max())} rows), "
                f"got num_steps={self.num_steps} * frameskip={self.frameskip} = {self.span}: no sample fits; "
                "lower num_steps (history) / frameskip or record longer episodes"
            )

    # -- to implement (or set ``_columns``, ``lengths`` and ``offsets`` in ``__init__``) ------
    @property
    def stored_columns(self) -> list[str]:
        """Every column the dataset holds (``column_names`` are those loaded into items)."""
        if hasattr(self, "_columns"):
            return list(self._columns)
        if type(self).column_names is not Dataset.column_names:  # a 0.0.3-style subclass
            return list(self.column_names)
        raise NotImplementedError("stored_columns -> list[str] (or set self._columns)")

    @property
    def column_names(self) -> list[str]:
        """The columns put in items: ``keys_to_load``, by default every stored column (as 0.0.3)."""
        return list(self._keys_to_load) if self._keys_to_load is not None else self.stored_columns

    @property
    def lengths(self) -> np.ndarray:
        if not hasattr(self, "_lengths"):
            raise NotImplementedError("lengths -> (E,) int array of rows per episode (or pass lengths to __init__)")
        return self._lengths

    @lengths.setter
    def lengths(self, value: Sequence[int] | np.ndarray) -> None:
        self._lengths = _episode_array("lengths", value, type(self).__name__)
        self._index = None

    @property
    def offsets(self) -> np.ndarray:
        if not hasattr(self, "_offsets"):
            raise NotImplementedError("offsets -> (E,) int array of first rows (or pass offsets to __init__)")
        return self._offsets

    @offsets.setter
    def offsets(self, value: Sequence[int] | np.ndarray) -> None:
        arr = _episode_array("offsets", value, type(self).__name__)
        if hasattr(self, "_lengths") and len(arr) != len(self._lengths):
            raise ConfigError(
                f"{type(self).__name__} requires one offset per episode ({len(self._lengths)}), got {len(arr)} offsets"
            )
        self._offsets = arr
        self._index = None

    def _read(self, col: str, start: int, stop: int) -> np.ndarray:
        raise NotImplementedError("_read(col, start, stop) -> rows start:stop of col")

    # -- columns ------------------------------------------------------------------------------
    def check_keys(self, names: Sequence[str]) -> list[str]:
        """Raise :class:`UnknownNameError` (a KeyError) listing the stored columns for unknown names."""
        cols = self.stored_columns
        for name in names:
            if name not in cols:
                raise missing_column(type(self).__name__, name, cols)
        return list(names)

    def column_shape(self, col: str) -> tuple[tuple[int, ...], np.dtype]:
        """Per-row shape and dtype of ``col``, from its first row (a reader that knows them from
        its metadata, like :class:`~stable_worldmodel.data.HDF5Dataset`, answers without reading)."""
        self.check_keys([col])
        row = np.asarray(self._read(col, 0, 1))
        return tuple(int(v) for v in row.shape[1:]), row.dtype

    @property
    def keys_to_load(self) -> list[str]:
        return self.column_names

    @property
    def num_episodes(self) -> int:
        return len(self.lengths)

    @property
    def num_rows(self) -> int:
        return int(np.sum(self.lengths))

    @property
    def span(self) -> int:
        """Rows read per sample: ``num_steps * frameskip``."""
        return self.num_steps * self.frameskip

    # -- sample index -------------------------------------------------------------------------
    def _sample_index(self) -> tuple[np.ndarray, np.ndarray]:
        if self._index is None:
            counts = np.maximum(np.asarray(self.lengths, np.int64) - self.span + 1, 0)
            self._index = (np.concatenate([[0], np.cumsum(counts)]), np.asarray(self.offsets, np.int64))
        return self._index

    @property
    def clip_indices(self) -> list[tuple[int, int]]:
        """``(episode, start)`` of every sample, in sample order (every start whose window fits).

        Assigning a list of pairs replaces the samples (as 0.0.3 subclasses may do).
        """
        if self._clips is not None:
            return self._clips
        cum, _ = self._sample_index()
        counts = np.diff(cum)
        return [(ep, start) for ep, n in enumerate(counts.tolist()) for start in range(n)]

    @clip_indices.setter
    def clip_indices(self, pairs: Sequence[tuple[int, int]]) -> None:
        self._clips = [(int(ep), int(start)) for ep, start in pairs]

    def __len__(self) -> int:
        if self._clips is not None:
            return len(self._clips)
        return int(self._sample_index()[0][-1])

    def _check_index(self, idx: int) -> int:
        if isinstance(idx, bool) or not isinstance(idx, (int, np.integer)):
            raise ArgumentTypeError(f"{type(self).__name__} indices must be ints, got {idx!r} ({type(idx).__name__})")
        n = len(self)
        i = int(idx) + n if idx < 0 else int(idx)
        if not 0 <= i < n:
            raise IndexError(f"{type(self).__name__} index {int(idx)} out of range for {n} samples")
        return i

    def locate(self, idx: int) -> tuple[int, int]:
        """``(episode, step)`` of the first row of sample ``idx`` (``clip_indices[idx]``)."""
        i = self._check_index(idx)
        if self._clips is not None:
            return self._clips[i]
        cum, _ = self._sample_index()
        ep = int(np.searchsorted(cum, i, side="right") - 1)
        return ep, i - int(cum[ep])

    def _locate_many(self, idx: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Episodes and steps of the samples ``idx`` (int array, negatives count from the end)."""
        n = len(self)
        idx = np.where(idx < 0, idx + n, idx)
        bad = (idx < 0) | (idx >= n)
        if bad.any():
            raise IndexError(f"{type(self).__name__} index {int(idx[bad][0])} out of range for {n} samples")
        if self._clips is not None:
            pairs = np.asarray(self._clips, np.int64).reshape(-1, 2)[idx]
            return pairs[:, 0], pairs[:, 1]
        cum, _ = self._sample_index()
        eps = np.searchsorted(cum, idx, side="right") - 1
        return eps, idx - cum[eps]

    def sample_rows(self, idx: int) -> int:
        """Global row of the first row of sample ``idx``."""
        ep, step = self.locate(idx)
        return int(self._sample_index()[1][ep]) + step

    # -- items --------------------------------------------------------------------------------
    def _row_step(self, col: str) -> int:
        """A window keeps every row of ``action`` and the other dense columns (grouped later) and
        every ``frameskip``-th row of the other columns."""
        return 1 if col in self.dense_columns else self.frameskip

    def _row_offsets(self, col: str) -> np.ndarray:
        """Offsets in a window of the rows that ``col`` keeps."""
        return np.arange(0, self.span, self._row_step(col))

    def _read_strided(self, col: str, start: int, stop: int, step: int) -> np.ndarray:
        """Rows ``start:stop:step`` of ``col``; kinds that pay per row (image files) override it."""
        return self._read(col, start, stop)[::step]

    def _read_windows(self, col: str, starts: np.ndarray) -> np.ndarray:
        """Kept rows ``(B, len(_row_offsets(col)), ...)`` of ``col`` for windows starting at the
        global rows ``starts``; kinds that can gather many windows at once override it."""
        span, step = self.span, self._row_step(col)
        return np.stack([self._read_strided(col, int(s), int(s) + span, step) for s in starts])

    def _batch(self, indices: Sequence[int], group_actions: bool = True) -> dict[str, Any]:
        """Columns of the samples ``indices`` as ``(B, T, ...)`` tensors (images ``(B, T, C, H, W)``);
        ``action`` as ``(B, T, frameskip * A)`` blocks, or its raw ``(B, T * frameskip, A)`` rows
        when not ``group_actions``."""
        idx = np.asarray(indices)
        if idx.ndim != 1 or not idx.size or not np.issubdtype(idx.dtype, np.integer):
            raise ArgumentTypeError(f"{type(self).__name__} indices must be ints, got {indices!r}")
        eps, steps = self._locate_many(idx.astype(np.int64))
        starts = self._sample_index()[1][eps] + steps
        cols = {col: self._read_windows(col, starts) for col in self.keys_to_load}
        if group_actions:  # (B, span, A) -> (B, T, frameskip * A); other dense columns (B, T, frameskip, ...)
            for col in self.dense_columns.intersection(cols):
                cols[col] = group_dense(col, cols[col], self.num_steps, batched=True)
        return to_tensors(cols, batch=True, owned=True)  # gathered rows are fresh arrays

    def _transformed(self, item: dict[str, Any]) -> dict[str, Any]:
        """``transform`` applied as the original releases apply it: to the raw ``(T * frameskip, A)``
        action rows (a ``column_normalizer`` fitted on the action column fits them), which are
        grouped into ``(T, frameskip * A)`` blocks afterwards."""
        if self.transform is not None:
            item = self.transform(item)
        for col in self.dense_columns.intersection(item):
            item[col] = group_dense(col, item[col], self.num_steps)
        return item

    def _load_slice(self, ep_idx: int, start: int, end: int) -> dict[str, Any]:
        """Steps ``start:end`` of episode ``ep_idx`` as 0.0.3 returned them: every loaded column
        as tensors, strided by ``frameskip`` (``action`` kept whole), ``transform`` applied."""
        row = int(self.offsets[ep_idx]) + int(start)
        stop = row + int(end) - int(start)
        steps = to_tensors({col: self._read_strided(col, row, stop, self._row_step(col)) for col in self.keys_to_load})
        return self.transform(steps) if self.transform is not None else steps

    @property
    def _from_slices(self) -> bool:
        """A 0.0.3-style subclass: it implements ``_load_slice`` and not ``_read``."""
        cls = type(self)
        return cls._load_slice is not Dataset._load_slice and cls._read is Dataset._read

    def __getitem__(self, idx: int) -> dict[str, Any]:
        prepare_worker()
        if self._from_slices:
            ep, start = self.locate(idx)
            steps = self._load_slice(ep, start, start + self.span)
            if keys.ACTION in steps:
                steps[keys.ACTION] = steps[keys.ACTION].reshape(self.num_steps, -1)
            return steps
        start, span = self.sample_rows(idx), self.span
        item = {}
        for col in self.keys_to_load:
            item[col] = self._read_strided(col, start, start + span, self._row_step(col))
        return self._transformed(to_tensors(item))  # action (span, A) -> transform -> (T, frameskip * A)

    def __getitems__(self, indices: Sequence[int]) -> list[dict[str, Any]]:
        """``[self[i] for i in indices]``, read column by column (what a DataLoader calls per batch).

        Kinds that override ``__getitem__`` get exactly their per-item path.
        """
        prepare_worker()
        if type(self).__getitem__ is not Dataset.__getitem__ or self._from_slices:
            return [self[i] for i in indices]
        if len(indices) == 0:
            return []
        transform = self.transform is not None
        batch = self._batch(indices, group_actions=not transform)  # a transform sees the raw action rows
        per_item = (v.unbind(0) if hasattr(v, "unbind") else v for v in batch.values())  # text columns: lists
        items = [dict(zip(batch, views, strict=False)) for views in zip(*per_item, strict=False)]
        return [self._transformed(item) for item in items] if transform else items

    def load_episode(self, ep: int) -> dict[str, Any]:
        """Every loaded column of episode ``ep`` as tensors ``(L, ...)`` (images ``(L, C, H, W)``)."""
        lengths = self.lengths
        if isinstance(ep, bool) or not isinstance(ep, (int, np.integer)):
            raise ArgumentTypeError(
                f"{type(self).__name__}.load_episode requires an int episode index, got {ep!r} ({type(ep).__name__})"
            )
        if not -len(lengths) <= ep < len(lengths):
            raise IndexError(f"{type(self).__name__} episode {ep} out of range for {len(lengths)} episodes")
        if self._from_slices:
            return self._load_slice(int(ep), 0, int(lengths[ep]))
        start = int(self.offsets[ep])
        stop = start + int(lengths[ep])
        return to_tensors({col: self._read(col, start, stop) for col in self.keys_to_load})

    def load_chunk(
        self, episodes_idx: Sequence[int], start: Sequence[int] | int, end: Sequence[int] | int
    ) -> list[dict]:
        """Steps ``start[i]:end[i]`` of episode ``episodes_idx[i]`` (raw rows, as tensors) for each i.

        A 0.0.3-style subclass gets what its ``_load_slice`` returns, ``action`` grouped by
        ``frameskip`` as in 0.0.3.
        """
        episodes_idx = [int(e) for e in np.atleast_1d(episodes_idx)]
        starts = np.broadcast_to(np.asarray(start), (len(episodes_idx),))
        ends = np.broadcast_to(np.asarray(end), (len(episodes_idx),))
        out = []
        for ep, s, e in zip(episodes_idx, starts, ends, strict=False):
            length = int(self.lengths[ep])
            if not 0 <= s < e <= length:
                raise ConfigError(
                    f"{type(self).__name__}.load_chunk requires 0 <= start < end <= {length} for episode {ep}, "
                    f"got start={int(s)}, end={int(e)}"
                )
            if self._from_slices:
                steps = self._load_slice(ep, int(s), int(e))
                if keys.ACTION in steps:
                    steps[keys.ACTION] = steps[keys.ACTION].reshape((int(e) - int(s)) // self.frameskip, -1)
                out.append(steps)
                continue
            row = int(self.offsets[ep]) + int(s)
            out.append(to_tensors({col: self._read(col, row, row + int(e - s)) for col in self.keys_to_load}))
        return out

    def get_col_data(self, col: str) -> np.ndarray:
        """Every committed row of column ``col`` as a numpy array ``(N, ...)``."""
        self.check_keys([col])
        return (
            np.concatenate(
                [self._read(col, int(o), int(o) + int(n)) for o, n in zip(self.offsets, self.lengths, strict=False)]
            )
            if self.num_episodes
            else self._read(col, 0, 0)
        )

    def row_shape(self, col: str) -> tuple[int, ...]:
        """Shape of one row of column ``col``."""
        self.check_keys([col])
        if self._from_slices:
            return tuple(np.asarray(self.get_col_data(col)).shape[1:])
        return tuple(self._read(col, 0, min(1, self.num_rows)).shape[1:])

    def get_dim(self, col: str) -> int:
        """Values per row of column ``col`` (the product of its row shape; 1 for scalars)."""
        return int(np.prod(self.row_shape(col), dtype=np.int64))

    def get_row_data(self, idx: int | Sequence[int]) -> dict[str, np.ndarray]:
        """Row(s) ``idx`` (global row numbers) of every stored column, as numpy arrays."""
        rows = np.atleast_1d(np.asarray(idx, np.int64))
        n = self.num_rows
        if rows.size and (rows.min() < 0 or rows.max() >= n):
            raise IndexError(f"{type(self).__name__} row {rows.tolist()} out of range for {n} rows")
        out = {col: np.stack([self._read(col, int(r), int(r) + 1)[0] for r in rows]) for col in self.stored_columns}
        if np.ndim(idx) == 0:
            return {k: v[0] for k, v in out.items()}
        return out

    def __repr__(self) -> str:
        return (
            f"{type(self).__name__}(episodes={self.num_episodes}, rows={self.num_rows}, samples={len(self)}, "
            f"num_steps={self.num_steps}, frameskip={self.frameskip}, columns={self.column_names})"
        )


def to_tensors(item: dict[str, np.ndarray], batch: bool = False, owned: bool = False) -> dict[str, Any]:
    """numpy columns -> torch tensors; images ``(T, H, W, C)`` -> ``(T, C, H, W)`` (with a
    leading batch axis when ``batch``); a text column -> its first string (a list of them when
    ``batch``). The tensors never share memory with a reader's cache:
    arrays are copied unless ``owned`` says they are fresh."""
    import torch

    out = {}
    for k, v in item.items():
        arr = np.asarray(v)
        if arr.dtype.kind in "OUS":  # text (a Lance string column): a window gives its first value, as upstream
            first = arr[:, 0] if batch else arr.reshape(-1)[:1]
            values = [x.decode() if isinstance(x, bytes) else str(x) for x in first.tolist()]
            out[k] = values if batch else (values[0] if values else "")
            continue
        if image_like(arr[0] if batch else arr):
            arr = np.moveaxis(arr, -1, -3)
        out[k] = torch.from_numpy(np.ascontiguousarray(arr) if owned else np.array(arr, order="C"))
    return out


# 0.0.3 defined every dataset class in this module (``from stable_worldmodel.data.dataset import
# HDF5Dataset``); they are found in their own modules on first use.
from .._lazy import lazy_getattr as _lazy_getattr  # noqa: E402

_HOME = "stable_worldmodel.data."
__getattr__ = _lazy_getattr(
    __name__,
    {
        "HDF5Dataset": _HOME + "hdf5",
        "FolderDataset": _HOME + "folder",
        "ImageDataset": _HOME + "folder",
        "VideoDataset": _HOME + "video_dataset",
        "MergeDataset": _HOME + "compose",
        "ConcatDataset": _HOME + "compose",
        "GoalDataset": _HOME + "compose",
    },
)

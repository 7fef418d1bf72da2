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

Subclasses implement ``column_names``, ``lengths``, ``offsets`` and ``_read(col, start,
stop) -> np.ndarray`` (rows of one column); the rest (indexing, items, episodes, chunks)
lives here.
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from .. import keys
from ..errors import ArgumentTypeError, ConfigError, unknown_name
from ._ipc import prepare_worker

logger = logging.getLogger(__name__)

try:  # the base class of every dataset kind: a torch Dataset when torch is there
    from torch.utils.data import Dataset as _TorchDataset
except ImportError:  # pragma: no cover - torch is a base dependency
    _TorchDataset = object


def _positive(name: str, value: Any, owner: str) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 1:
        raise ConfigError(f"{owner} requires {name} to be a positive int, got {value!r}")
    return int(value)


def image_like(arr: np.ndarray) -> bool:
    """Rows ``(N, H, W, C)`` uint8 with C in 1, 3, 4."""
    return arr.dtype == np.uint8 and arr.ndim == 4 and arr.shape[-1] in (1, 3, 4)


class Dataset(_TorchDataset):
    """Episodes of flat columns, sampled as windows (see the module docstring).

    Args:
        frameskip: rows between two sampled frames.
        num_steps: frames per sample (T).
        transform: optional callable applied to each item dict.
        keys_to_load: columns to put in items (default: all).
    """

    def __init__(
        self,
        frameskip: int = 1,
        num_steps: int = 1,
        transform: Callable[[dict], dict] | None = None,
        keys_to_load: Sequence[str] | None = None,
    ):
        owner = type(self).__name__
        self.frameskip = _positive("frameskip", frameskip, owner)
        self.num_steps = _positive("num_steps", num_steps, owner)
        if transform is not None and not callable(transform):
            raise ConfigError(f"{owner} requires transform to be a callable (item dict -> item dict) or None, got {transform!r}")
        self.transform = transform
        if keys_to_load is not None:
            if isinstance(keys_to_load, (str, bytes)):
                raise ConfigError(f"{owner} requires keys_to_load to be a list of column names, got the string {keys_to_load!r}; write [{keys_to_load!r}]")
            keys_to_load = list(keys_to_load)
            if not keys_to_load or not all(isinstance(k, str) for k in keys_to_load):
                raise ConfigError(f"{owner} requires keys_to_load to be a non-empty list of column names (or None for all), got {keys_to_load!r}")
        self._keys_to_load = keys_to_load
        self._index: tuple[np.ndarray, np.ndarray] | None = None

    def check_span(self) -> None:
        """Raise unless some episode is long enough for one sample (``num_steps * frameskip`` rows)."""
        lengths = np.asarray(self.lengths)
        if len(lengths) and int(lengths.max()) < self.span:
            raise ConfigError(
                f"{type(self).__name__} requires num_steps * frameskip <= the longest episode ({int(lengths.max())} rows), "
                f"got num_steps={self.num_steps} * frameskip={self.frameskip} = {self.span}: no sample fits; "
                "lower num_steps (history) / frameskip or record longer episodes"
            )

    # -- to implement (or set ``_columns``, ``_lengths`` and ``_offsets`` in ``__init__``) -----
    @property
    def column_names(self) -> list[str]:
        if not hasattr(self, "_columns"):
            raise NotImplementedError("column_names -> list[str] (or set self._columns)")
        return list(self._columns)

    @property
    def lengths(self) -> np.ndarray:
        if not hasattr(self, "_lengths"):
            raise NotImplementedError("lengths -> (E,) int array of rows per episode (or set self._lengths)")
        return self._lengths

    @property
    def offsets(self) -> np.ndarray:
        if not hasattr(self, "_offsets"):
            raise NotImplementedError("offsets -> (E,) int array of first rows (or set self._offsets)")
        return self._offsets

    def _read(self, col: str, start: int, stop: int) -> np.ndarray:
        raise NotImplementedError("_read(col, start, stop) -> rows start:stop of col")

    # -- columns ------------------------------------------------------------------------------
    def check_keys(self, names: Sequence[str]) -> list[str]:
        """Raise :class:`UnknownNameError` (a KeyError) listing the columns for unknown names."""
        cols = self.column_names
        for name in names:
            if name not in cols:
                raise unknown_name(f"column of {type(self).__name__}", name, cols)
        return list(names)

    @property
    def keys_to_load(self) -> list[str]:
        if self._keys_to_load is None:
            return list(self.column_names)
        return self._keys_to_load

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

    def __len__(self) -> int:
        return int(self._sample_index()[0][-1])

    def locate(self, idx: int) -> tuple[int, int]:
        """``(episode, step)`` of the first row of sample ``idx``."""
        if isinstance(idx, bool) or not isinstance(idx, (int, np.integer)):
            raise ArgumentTypeError(f"{type(self).__name__} indices must be ints, got {idx!r} ({type(idx).__name__})")
        cum, _ = self._sample_index()
        n = int(cum[-1])
        i = int(idx) + n if idx < 0 else int(idx)
        if not 0 <= i < n:
            raise IndexError(f"{type(self).__name__} index {int(idx)} out of range for {n} samples")
        ep = int(np.searchsorted(cum, i, side="right") - 1)
        return ep, i - int(cum[ep])

    def _locate_many(self, idx: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Episodes and steps of the samples ``idx`` (int array, negatives count from the end)."""
        cum, _ = self._sample_index()
        n = int(cum[-1])
        idx = np.where(idx < 0, idx + n, idx)
        bad = (idx < 0) | (idx >= n)
        if bad.any():
            raise IndexError(f"{type(self).__name__} index {int(idx[bad][0])} out of range for {n} samples")
        eps = np.searchsorted(cum, idx, side="right") - 1
        return eps, idx - cum[eps]

    def sample_rows(self, idx: int) -> int:
        """Global row of the first row of sample ``idx``."""
        ep, step = self.locate(idx)
        return int(self._sample_index()[1][ep]) + step

    # -- items --------------------------------------------------------------------------------
    def _row_step(self, col: str) -> int:
        """A window keeps every row of ``action`` (grouped later) and every ``frameskip``-th row
        of the other columns."""
        return 1 if col == keys.ACTION else self.frameskip

    def _row_offsets(self, col: str) -> np.ndarray:
        """Offsets in a window of the rows that ``col`` keeps."""
        return np.arange(0, self.span, self._row_step(col))

    def _read_windows(self, col: str, starts: np.ndarray) -> np.ndarray:
        """Kept rows ``(B, len(_row_offsets(col)), ...)`` of ``col`` for windows starting at the
        global rows ``starts``; kinds that can gather many windows at once override it."""
        span, step = self.span, self._row_step(col)
        return np.stack([self._read(col, int(s), int(s) + span)[::step] for s in starts])

    def _batch(self, indices: Sequence[int]) -> dict[str, Any]:
        """Columns of the samples ``indices`` as ``(B, T, ...)`` tensors (images ``(B, T, C, H, W)``)."""
        idx = np.asarray(indices)
        if idx.ndim != 1 or not idx.size or not np.issubdtype(idx.dtype, np.integer):
            raise ArgumentTypeError(f"{type(self).__name__} indices must be ints, got {indices!r}")
        eps, steps = self._locate_many(idx.astype(np.int64))
        starts = self._sample_index()[1][eps] + steps
        cols = {col: self._read_windows(col, starts) for col in self.keys_to_load}
        if keys.ACTION in cols:  # (B, span, A) -> (B, T, frameskip * A)
            cols[keys.ACTION] = cols[keys.ACTION].reshape(len(starts), self.num_steps, -1)
        return to_tensors(cols, batch=True, owned=True)  # gathered rows are fresh arrays

    def __getitem__(self, idx: int) -> dict[str, Any]:
        prepare_worker()
        start, span = self.sample_rows(idx), self.span
        item = {}
        for col in self.keys_to_load:
            item[col] = self._read(col, start, start + span)[:: self._row_step(col)]
        if keys.ACTION in item:  # (span, A) -> (T, frameskip * A)
            item[keys.ACTION] = item[keys.ACTION].reshape(self.num_steps, -1)
        item = to_tensors(item)
        return self.transform(item) if self.transform is not None else item

    def __getitems__(self, indices: Sequence[int]) -> list[dict[str, Any]]:
        """``[self[i] for i in indices]``, read column by column (what a DataLoader calls per batch).

        Kinds that override ``__getitem__`` get exactly their per-item path.
        """
        prepare_worker()
        if type(self).__getitem__ is not Dataset.__getitem__:
            return [self[i] for i in indices]
        if len(indices) == 0:
            return []
        batch = self._batch(indices)
        items = [dict(zip(batch, views)) for views in zip(*(v.unbind(0) for v in batch.values()))]
        if self.transform is not None:
            items = [self.transform(item) for item in items]
        return items

    def load_episode(self, ep: int) -> dict[str, Any]:
        """Every loaded column of episode ``ep`` as tensors ``(L, ...)`` (images ``(L, C, H, W)``)."""
        lengths = self.lengths
        if isinstance(ep, bool) or not isinstance(ep, (int, np.integer)):
            raise ArgumentTypeError(f"{type(self).__name__}.load_episode requires an int episode index, got {ep!r} ({type(ep).__name__})")
        if not -len(lengths) <= ep < len(lengths):
            raise IndexError(f"{type(self).__name__} episode {ep} out of range for {len(lengths)} episodes")
        start = int(self.offsets[ep])
        stop = start + int(lengths[ep])
        return to_tensors({col: self._read(col, start, stop) for col in self.keys_to_load})

    def load_chunk(self, episodes_idx: Sequence[int], start: Sequence[int] | int, end: Sequence[int] | int) -> list[dict]:
        """Steps ``start[i]:end[i]`` of episode ``episodes_idx[i]`` (raw rows, as tensors) for each i."""
        episodes_idx = [int(e) for e in np.atleast_1d(episodes_idx)]
        starts = np.broadcast_to(np.asarray(start), (len(episodes_idx),))
        ends = np.broadcast_to(np.asarray(end), (len(episodes_idx),))
        out = []
        for ep, s, e in zip(episodes_idx, starts, ends):
            length = int(self.lengths[ep])
            if not 0 <= s < e <= length:
                raise ConfigError(
                    f"{type(self).__name__}.load_chunk requires 0 <= start < end <= {length} for episode {ep}, "
                    f"got start={int(s)}, end={int(e)}"
                )
            row = int(self.offsets[ep]) + int(s)
            out.append(to_tensors({col: self._read(col, row, row + int(e - s)) for col in self.keys_to_load}))
        return out

    def get_col_data(self, col: str) -> np.ndarray:
        """Every committed row of column ``col`` as a numpy array ``(N, ...)``."""
        self.check_keys([col])
        return np.concatenate(
            [self._read(col, int(o), int(o) + int(n)) for o, n in zip(self.offsets, self.lengths)]
        ) if self.num_episodes else self._read(col, 0, 0)

    def get_row_data(self, idx: int | Sequence[int]) -> dict[str, np.ndarray]:
        """Row(s) ``idx`` (global row numbers) of every column, as numpy arrays."""
        rows = np.atleast_1d(np.asarray(idx, np.int64))
        n = self.num_rows
        if rows.size and (rows.min() < 0 or rows.max() >= n):
            raise IndexError(f"{type(self).__name__} row {rows.tolist()} out of range for {n} rows")
        out = {col: np.stack([self._read(col, int(r), int(r) + 1)[0] for r in rows]) for col in self.column_names}
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
    leading batch axis when ``batch``). The tensors never share memory with a reader's cache:
    arrays are copied unless ``owned`` says they are fresh."""
    import torch

    out = {}
    for k, v in item.items():
        arr = np.asarray(v)
        if image_like(arr[0] if batch else arr):
            arr = np.moveaxis(arr, -1, -3)
        out[k] = torch.from_numpy(np.ascontiguousarray(arr) if owned else np.array(arr, order="C"))
    return out

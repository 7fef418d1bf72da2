"""Datasets built from other datasets: merged columns, concatenated episodes, added goals.

The members are used through public methods only, so any dataset-like object works (ours,
a 0.0.3 subclass, a user's class): ``len``, indexing, ``column_names``, ``lengths``,
``load_chunk``, ``get_col_data``, ``get_row_data`` (and, for :class:`GoalDataset`,
``num_steps`` / ``frameskip`` and ``clip_indices`` or ``locate``). Rows are numbered episode
after episode::

    ConcatDataset([a, b])   episodes  a0 a1 | b0 b1 b2     rows  a's rows, then b's
                            samples   a's samples, then b's (each member windows itself)
    MergeDataset([a, b])    episodes  a0 a1 (b has the same lengths)
                            item i    a[i] restricted to a's keys + b[i] restricted to b's keys
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from typing import Any

import numpy as np

from .. import keys
from ..errors import ArgumentTypeError, ConfigError, UnknownNameError
from .dataset import Dataset, _TorchDataset, missing_column, to_tensors


def _missing(owner: str, col: str, cols: Sequence[str]) -> UnknownNameError:
    return missing_column(owner, col, list(cols))


def _dim(ds: Any, col: str) -> int:
    if isinstance(ds, (Dataset, _Composite)):
        return ds.get_dim(col)
    data = np.asarray(ds.get_col_data(col))
    return int(np.prod(data.shape[1:], dtype=np.int64)) if data.ndim > 1 else 1


def _stored(ds: Any) -> list[str]:
    """Every column ``ds`` can read (ours: also those not loaded into items)."""
    return ds.stored_columns if isinstance(ds, Dataset) else list(ds.column_names)


def _clip(ds: Any, idx: int) -> tuple[int, int]:
    """``(episode, start)`` of sample ``idx`` of ``ds``."""
    if isinstance(ds, (Dataset, _Composite)):
        return ds.locate(idx)
    ep, start = ds.clip_indices[idx]
    return int(ep), int(start)


class _Composite(_TorchDataset):
    """Shared by :class:`MergeDataset` and :class:`ConcatDataset`: members, transform, rows."""

    verb = "combine"

    def __init__(self, datasets: Sequence[Any], transform: Callable[[dict], dict] | None = None):
        owner = type(self).__name__
        if isinstance(datasets, (str, bytes)) or not isinstance(datasets, Sequence):
            raise ConfigError(f"{owner} requires a list of datasets, got {type(datasets).__name__}")
        self.datasets = list(datasets)
        if not self.datasets:
            raise ConfigError(
                f"{owner} requires at least one dataset, got an empty list. Need at least one dataset to {self.verb}"
            )
        if transform is not None and not callable(transform):
            raise ConfigError(
                f"{owner} requires transform to be a callable (item dict -> item dict) or None, got {transform!r}"
            )
        self.transform = transform

    @property
    def offsets(self) -> np.ndarray:
        lengths = np.asarray(self.lengths, np.int64)
        return np.concatenate([[0], np.cumsum(lengths)[:-1]]).astype(np.int64)

    @property
    def num_episodes(self) -> int:
        return len(self.lengths)

    @property
    def num_rows(self) -> int:
        return int(np.sum(self.lengths))

    @property
    def num_steps(self) -> int:
        return self._same("num_steps")

    @property
    def frameskip(self) -> int:
        return self._same("frameskip")

    def _same(self, attr: str) -> int:
        values = {int(getattr(ds, attr)) for ds in self.datasets}
        if len(values) != 1:
            raise ConfigError(
                f"{type(self).__name__}.{attr} requires members with the same {attr}, got {sorted(values)}"
            )
        return values.pop()

    def _check_index(self, idx: int) -> int:
        if isinstance(idx, bool) or not isinstance(idx, (int, np.integer)):
            raise ArgumentTypeError(f"{type(self).__name__} indices must be ints, got {idx!r} ({type(idx).__name__})")
        n = len(self)
        i = int(idx) + n if idx < 0 else int(idx)
        if not 0 <= i < n:
            raise IndexError(f"{type(self).__name__} index {int(idx)} out of range for {n} samples")
        return i

    def _apply(self, item: dict) -> dict:
        return self.transform(item) if self.transform is not None else item

    @property
    def clip_indices(self) -> list[tuple[int, int]]:
        return [self.locate(i) for i in range(len(self))]

    def load_episode(self, ep: int) -> dict[str, Any]:
        """Every column of episode ``ep`` (through ``load_chunk``)."""
        length = int(np.asarray(self.lengths)[ep])
        return self.load_chunk([ep], [0], [length])[0]

    def get_dim(self, col: str) -> int:
        """Values per row of column ``col``."""
        for ds in self.datasets:
            if col in ds.column_names:
                return _dim(ds, col)
        raise _missing(type(self).__name__, col, self.column_names)

    def row_shape(self, col: str) -> tuple[int, ...]:
        row = self.get_row_data(0)
        if col not in row:
            raise _missing(type(self).__name__, col, self.column_names)
        return tuple(np.shape(row[col]))

    def __repr__(self) -> str:
        return (
            f"{type(self).__name__}({len(self.datasets)} datasets, episodes={self.num_episodes}, "
            f"samples={len(self)}, columns={self.column_names})"
        )


class MergeDataset(_Composite):
    """Columns of several datasets over the same episodes and samples (horizontal join).

    ``keys_from_dataset[i]`` lists the columns taken from ``datasets[i]``; by default each
    dataset gives the columns that no earlier one has.
    """

    verb = "merge"

    def __init__(
        self,
        datasets: Sequence[Any],
        keys_from_dataset: Sequence[Sequence[str]] | None = None,
        *,
        transform: Callable[[dict], dict] | None = None,
    ):
        super().__init__(datasets, transform)
        ref = np.asarray(self.datasets[0].lengths)
        for i, ds in enumerate(self.datasets[1:], start=1):
            if not np.array_equal(np.asarray(ds.lengths), ref):
                raise ConfigError(
                    f"MergeDataset requires datasets with the same episode lengths, got dataset {i} with "
                    f"{len(ds.lengths)} episodes / {int(np.sum(ds.lengths))} rows vs {len(ref)} / {int(ref.sum())}"
                )
            if len(ds) != len(self.datasets[0]):
                raise ConfigError(
                    f"MergeDataset requires datasets with the same samples, got {len(ds)} in dataset {i} vs "
                    f"{len(self.datasets[0])} in dataset 0; build them with the same num_steps and frameskip"
                )
        self.keys_map = self._keys_map(keys_from_dataset)

    def _keys_map(self, given: Sequence[Sequence[str]] | None) -> list[list[str]]:
        if not given:
            seen: set[str] = set()
            out = []
            for ds in self.datasets:
                out.append([c for c in ds.column_names if c not in seen])
                seen.update(out[-1])
            return out
        if len(given) != len(self.datasets) or any(isinstance(k, (str, bytes)) for k in given):
            raise ConfigError(
                "MergeDataset requires keys_from_dataset to hold one list of columns per dataset "
                f"({len(self.datasets)}), got {given!r}"
            )
        for i, (ds, cols) in enumerate(zip(self.datasets, given, strict=False)):
            for col in cols:
                if col not in ds.column_names:
                    raise _missing(f"MergeDataset (dataset {i})", col, ds.column_names)
        return [list(cols) for cols in given]

    @property
    def column_names(self) -> list[str]:
        return [c for cols in self.keys_map for c in cols]

    @property
    def lengths(self) -> np.ndarray:
        return self.datasets[0].lengths

    def __len__(self) -> int:
        return len(self.datasets[0])

    def locate(self, idx: int) -> tuple[int, int]:
        return _clip(self.datasets[0], self._check_index(idx))

    def _merge(self, parts: Sequence[Mapping[str, Any]]) -> dict[str, Any]:
        return {k: part[k] for part, cols in zip(parts, self.keys_map, strict=False) for k in cols if k in part}

    def __getitem__(self, idx: int) -> dict[str, Any]:
        i = self._check_index(idx)
        return self._apply(self._merge([ds[i] for ds in self.datasets]))

    def load_chunk(self, episodes_idx: Sequence[int], start: Sequence[int], end: Sequence[int]) -> list[dict]:
        chunks = [ds.load_chunk(episodes_idx, start, end) for ds in self.datasets]
        return [self._merge(parts) for parts in zip(*chunks, strict=False)]

    def get_col_data(self, col: str) -> np.ndarray:
        for ds, cols in zip(self.datasets, self.keys_map, strict=False):
            if col in cols:
                return ds.get_col_data(col)
        raise _missing("MergeDataset", col, self.column_names)

    def get_row_data(self, row_idx: int | Sequence[int]) -> dict[str, Any]:
        return self._merge(
            [ds.get_row_data(row_idx) if cols else {} for ds, cols in zip(self.datasets, self.keys_map, strict=False)]
        )


class ConcatDataset(_Composite):
    """Episodes and samples of several datasets one after the other (vertical join); its
    columns are the union of theirs."""

    verb = "concatenate"

    def __init__(self, datasets: Sequence[Any], *, transform: Callable[[dict], dict] | None = None):
        super().__init__(datasets, transform)
        self._cum = np.cumsum([0] + [len(ds) for ds in self.datasets])  # samples
        self._ep_cum = np.cumsum([0] + [len(ds.lengths) for ds in self.datasets])  # episodes
        self._row_cum = np.cumsum([0] + [int(np.sum(ds.lengths)) for ds in self.datasets])  # rows

    @property
    def column_names(self) -> list[str]:
        return list(dict.fromkeys(c for ds in self.datasets for c in ds.column_names))

    @property
    def lengths(self) -> np.ndarray:
        return np.concatenate([np.asarray(ds.lengths, np.int64) for ds in self.datasets])

    def __len__(self) -> int:
        return int(self._cum[-1])

    def _member(self, idx: int) -> tuple[int, int]:
        """``(dataset, local sample)`` of sample ``idx``."""
        i = self._check_index(idx)
        d = int(np.searchsorted(self._cum, i, side="right") - 1)
        return d, i - int(self._cum[d])

    def locate(self, idx: int) -> tuple[int, int]:
        d, local = self._member(idx)
        ep, start = _clip(self.datasets[d], local)
        return int(self._ep_cum[d]) + ep, start

    def __getitem__(self, idx: int) -> dict[str, Any]:
        d, local = self._member(idx)
        return self._apply(self.datasets[d][local])

    def load_chunk(self, episodes_idx: Sequence[int], start: Sequence[int], end: Sequence[int]) -> list[dict]:
        eps = np.atleast_1d(np.asarray(episodes_idx, np.int64))
        starts = np.broadcast_to(np.asarray(start), eps.shape)
        ends = np.broadcast_to(np.asarray(end), eps.shape)
        if eps.size and (eps.min() < 0 or eps.max() >= self._ep_cum[-1]):
            raise IndexError(f"ConcatDataset episode {eps.tolist()} out of range for {int(self._ep_cum[-1])} episodes")
        members = np.searchsorted(self._ep_cum, eps, side="right") - 1
        out: list[dict | None] = [None] * len(eps)
        for d in np.unique(members):
            mask = members == d
            chunks = self.datasets[d].load_chunk(eps[mask] - self._ep_cum[d], starts[mask], ends[mask])
            for i, chunk in zip(np.flatnonzero(mask), chunks, strict=False):
                out[i] = chunk
        return out  # type: ignore[return-value]

    def get_col_data(self, col: str) -> np.ndarray:
        lacking = [i for i, ds in enumerate(self.datasets) if col not in ds.column_names]
        if len(lacking) == len(self.datasets):
            raise _missing("ConcatDataset", col, self.column_names)
        if lacking:
            raise UnknownNameError(
                f"ConcatDataset column {col!r} not found in datasets {lacking}: "
                "its rows would not line up with the episodes"
            )
        return np.concatenate([np.asarray(ds.get_col_data(col)) for ds in self.datasets])

    def get_row_data(self, row_idx: int | Sequence[int]) -> dict[str, Any]:
        rows = np.atleast_1d(np.asarray(row_idx, np.int64))
        n = int(self._row_cum[-1])
        rows = np.where(rows < 0, rows + n, rows)
        if rows.size and (rows.min() < 0 or rows.max() >= n):
            raise IndexError(f"ConcatDataset row {np.asarray(row_idx).tolist()} out of range for {n} rows")
        members = np.searchsorted(self._row_cum, rows, side="right") - 1
        found = [self.datasets[d].get_row_data(int(r - self._row_cum[d])) for d, r in zip(members, rows, strict=False)]
        if np.ndim(row_idx) == 0:
            return found[0]
        common = [k for k in found[0] if all(k in f for f in found)] if found else []
        return {k: np.stack([np.asarray(f[k]) for f in found]) for k in common}


class GoalDataset(_TorchDataset):
    """Samples of ``dataset`` with a goal frame added under ``goal_keys``.

    The goal row is, with probabilities ``goal_probabilities = (p_random, p_future, p_current)``:
    a random row of the dataset, a future row of the same episode (offset ``k >= 1`` drawn
    from a geometric law of parameter ``1 - gamma``, clipped to the episode end), or the
    sample's last frame. ``goal_keys`` maps a column to the item key of its goal
    (default: ``pixels``/``proprio``/``state`` -> ``goal_pixels``/``goal_proprio``/
    ``goal_state`` for those present). Goal entries are ``(1, ...)`` tensors (images
    ``(1, C, H, W)``). ``seed`` seeds the goal draws (per index when given).
    """

    def __init__(
        self,
        dataset: Any,
        goal_probabilities: Sequence[float] = (0.3, 0.5, 0.2),
        gamma: float = 0.99,
        goal_keys: Mapping[str, str] | None = None,
        seed: int | None = None,
    ):
        probs = np.asarray(goal_probabilities, np.float64)
        if probs.shape != (3,) or np.any(probs < 0) or not np.isclose(probs.sum(), 1.0):
            raise ConfigError(
                "GoalDataset requires goal_probabilities to be a 3-tuple of non-negative numbers "
                "(p_random, p_future, p_current) "
                f"that sum to 1.0, got {goal_probabilities}"
            )
        if not 0.0 <= float(gamma) < 1.0:
            raise ConfigError(f"GoalDataset requires 0 <= gamma < 1, got {gamma}")
        self.dataset = dataset
        self.goal_probabilities = goal_probabilities  # as given (0.0.3); draws use self._probs
        self._probs = probs
        self.gamma = float(gamma)
        self.episode_lengths = dataset.lengths
        self.episode_offsets = getattr(dataset, "offsets", None)
        if self.episode_offsets is None:  # a dataset-like without offsets: episodes back to back
            self.episode_offsets = np.concatenate([[0], np.cumsum(self.episode_lengths)[:-1]]).astype(np.int64)
        if goal_keys is None:
            goal_keys = {
                c: keys.goal_key(c) for c in (keys.PIXELS, keys.PROPRIO, keys.STATE) if c in dataset.column_names
            }
        self.goal_keys = dict(goal_keys)
        for col in self.goal_keys:
            if col not in _stored(dataset):
                raise _missing("GoalDataset goal", col, _stored(dataset))
        self.seed = seed
        self.rng = np.random.default_rng(seed)
        self._row_cum = np.cumsum(np.asarray(self.episode_lengths, np.int64))  # rows up to each episode's end

    @property
    def column_names(self) -> list[str]:
        return self.dataset.column_names

    @property
    def lengths(self) -> np.ndarray:
        return self.episode_lengths

    @property
    def offsets(self) -> np.ndarray:
        return self.episode_offsets

    @property
    def clip_indices(self) -> list[tuple[int, int]]:
        return self.dataset.clip_indices

    def __len__(self) -> int:
        return len(self.dataset)

    def goal_step(self, idx: int, rng: np.random.Generator | None = None) -> tuple[int, int, int]:
        """``(kind, episode, step)`` of the goal of sample ``idx``; kind 0 random, 1 future, 2 current."""
        rng = rng if rng is not None else self.rng
        lengths = np.asarray(self.episode_lengths)
        ep, start = _clip(self.dataset, idx)
        current = start + (int(self.dataset.num_steps) - 1) * int(self.dataset.frameskip)
        kind = int(rng.choice(3, p=self._probs))
        if kind == 0:
            row = int(rng.integers(int(self._row_cum[-1])))
            e = int(np.searchsorted(self._row_cum, row, side="right"))
            return kind, e, row - (int(self._row_cum[e - 1]) if e else 0)
        if kind == 1:
            k = int(rng.geometric(1.0 - self.gamma)) if self.gamma > 0 else 1
            return kind, ep, min(current + k, int(lengths[ep]) - 1)
        return kind, ep, current

    # -- release 0.0.3's goal-sampling helpers (subclasses in research code call them) ------------------
    @property
    def _total_steps(self) -> int:
        return int(self._row_cum[-1]) if len(self._row_cum) else 0

    @property
    def _episode_cumlen(self) -> np.ndarray:
        return self._row_cum

    def _sample_goal_kind(self) -> str:
        """``"random"``, ``"future"`` or ``"current"``, drawn from :attr:`rng` by ``goal_probabilities``."""
        return ("random", "future", "current")[int(self.rng.choice(3, p=self._probs))]

    def _sample_random_step(self) -> tuple[int, int]:
        """A uniformly drawn ``(episode, step)`` of the whole dataset."""
        if self._total_steps == 0:
            return 0, 0
        row = int(self.rng.integers(self._total_steps))
        ep = int(np.searchsorted(self._row_cum, row, side="right"))
        return ep, row - (int(self._row_cum[ep - 1]) if ep else 0)

    def _sample_future_step(self, ep_idx: int, local_start: int) -> tuple[int, int]:
        """``(ep_idx, local_start + k * frameskip)`` with ``k >= 1`` geometric (parameter ``1 - gamma``),
        clipped to the episode's last step (``local_start`` itself when none is left)."""
        frameskip = int(getattr(self.dataset, "frameskip", 1))
        left = (int(self.episode_lengths[ep_idx]) - 1 - int(local_start)) // frameskip
        if left <= 0:
            return ep_idx, int(local_start)
        k = min(int(self.rng.geometric(max(1.0 - self.gamma, 1e-6))), left)
        return ep_idx, int(local_start) + k * frameskip

    def _get_clip_info(self, idx: int) -> tuple[int, int]:
        """``(episode, first step)`` of sample ``idx``."""
        return _clip(self.dataset, idx)

    def _load_single_step(self, ep_idx: int, local_idx: int) -> dict[str, Any]:
        """Row ``local_idx`` of episode ``ep_idx``, every loaded column, as the dataset gives rows."""
        return self.dataset.load_chunk([ep_idx], [local_idx], [local_idx + 1])[0]

    def _goal(self, ep: int, step: int) -> dict[str, Any]:
        if isinstance(self.dataset, Dataset) and not self.dataset._from_slices:  # ours: any column, loaded or not
            row = int(self.dataset.offsets[ep]) + step
            return to_tensors({dst: self.dataset._read(src, row, row + 1) for src, dst in self.goal_keys.items()})
        steps = self.dataset.load_chunk([ep], [step], [step + 1])[0]
        for src in self.goal_keys:
            if src not in steps:
                raise _missing("GoalDataset goal (in the rows load_chunk returns)", src, list(steps))
        return {dst: steps[src] for src, dst in self.goal_keys.items()}

    def __getitem__(self, idx: int) -> dict[str, Any]:
        item = self.dataset[idx]
        i = int(idx) % len(self)
        rng = self.rng if self.seed is None else np.random.default_rng((self.seed, i))
        _, ep, step = self.goal_step(i, rng)
        item.update(self._goal(ep, step))
        return item

    # -- the rest of the dataset surface, passed through -------------------------------------
    def load_chunk(self, episodes_idx: Sequence[int], start: Sequence[int], end: Sequence[int]) -> list[dict]:
        return self.dataset.load_chunk(episodes_idx, start, end)

    def load_episode(self, ep: int) -> dict[str, Any]:
        return self.dataset.load_episode(ep)

    def get_col_data(self, col: str) -> np.ndarray:
        return self.dataset.get_col_data(col)

    def get_row_data(self, row_idx: int | Sequence[int]) -> dict[str, Any]:
        return self.dataset.get_row_data(row_idx)

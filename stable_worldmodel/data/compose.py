"""Datasets built from other datasets: merged columns, concatenated episodes, added goals."""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from typing import Any

import numpy as np

from .. import keys
from ..errors import ConfigError
from .dataset import Dataset, to_tensors


class _CompositeDataset(Dataset):
    """A dataset built from others: keeps them in ``datasets`` (at least one) and lets
    :meth:`_combine` set up the columns, then checks ``keys_to_load``."""

    def __init__(
        self,
        datasets: Sequence[Dataset],
        frameskip: int = 1,
        num_steps: int = 1,
        transform: Callable[[dict], dict] | None = None,
        keys_to_load: Sequence[str] | None = None,
    ):
        super().__init__(frameskip=frameskip, num_steps=num_steps, transform=transform, keys_to_load=keys_to_load)
        self.datasets = list(datasets)
        if not self.datasets:
            raise ConfigError(f"{type(self).__name__} requires at least one dataset, got none")
        self._combine()
        if keys_to_load is not None:
            self.check_keys(keys_to_load)

    def _combine(self) -> None:
        raise NotImplementedError("_combine() -> None: set up the columns of self.datasets")


class MergeDataset(_CompositeDataset):
    """Columns of several datasets over the same steps (same episode lengths).

    A column present in several datasets is taken from the first one that has it.
    """

    def _combine(self) -> None:
        ref = np.asarray(self.datasets[0].lengths)
        for i, ds in enumerate(self.datasets[1:], start=1):
            if not np.array_equal(np.asarray(ds.lengths), ref):
                raise ConfigError(
                    f"MergeDataset requires datasets with the same episode lengths, got dataset {i} with "
                    f"{len(ds.lengths)} episodes / {int(np.sum(ds.lengths))} rows vs {len(ref)} / {int(ref.sum())}"
                )
        self._owner: dict[str, Dataset] = {}
        for ds in self.datasets:
            for col in ds.column_names:
                self._owner.setdefault(col, ds)

    @property
    def column_names(self) -> list[str]:
        return list(self._owner)

    @property
    def lengths(self) -> np.ndarray:
        return np.asarray(self.datasets[0].lengths)

    @property
    def offsets(self) -> np.ndarray:
        return np.asarray(self.datasets[0].offsets)

    def _read(self, col: str, start: int, stop: int) -> np.ndarray:
        owner = self._owner[col]
        shift = int(owner.offsets[0]) - int(self.offsets[0]) if len(self.offsets) else 0
        return owner._read(col, start + shift, stop + shift)


class ConcatDataset(_CompositeDataset):
    """Episodes of several datasets one after the other (columns: those common to all)."""

    def _combine(self) -> None:
        common = [c for c in self.datasets[0].column_names if all(c in d.column_names for d in self.datasets[1:])]
        self._columns = common
        self._lengths = np.concatenate([np.asarray(d.lengths, np.int64) for d in self.datasets])
        self._offsets = np.concatenate([[0], np.cumsum(self._lengths)[:-1]]).astype(np.int64)
        self._first_ep = np.cumsum([0] + [d.num_episodes for d in self.datasets])

    def _read(self, col: str, start: int, stop: int) -> np.ndarray:
        ep = int(np.searchsorted(self._offsets, start, side="right") - 1)
        d = int(np.searchsorted(self._first_ep, ep, side="right") - 1)
        ds = self.datasets[d]
        local_ep = ep - int(self._first_ep[d])
        if stop > int(self._offsets[ep] + self._lengths[ep]):
            parts = []  # a range over several episodes: read episode by episode
            while start < stop:
                ep_end = int(np.searchsorted(self._offsets, start, side="right") - 1)
                end = min(stop, int(self._offsets[ep_end] + self._lengths[ep_end]))
                parts.append(self._read(col, start, end))
                start = end
            return np.concatenate(parts)
        shift = int(ds.offsets[local_ep]) - int(self._offsets[ep])
        return ds._read(col, start + shift, stop + shift)


class GoalDataset(Dataset):
    """Samples of ``dataset`` with a goal frame added under ``goal_keys``.

    The goal row is, with probabilities ``goal_probabilities = (p_random, p_future, p_current)``:
    a random row of the dataset, a future row of the same episode (offset ``k >= 1`` drawn
    from a geometric law of parameter ``1 - gamma``, clipped to the episode end), or the
    sample's last frame. ``goal_keys`` maps a column to the item key of its goal
    (default: ``pixels``/``proprio``/``state`` -> ``goal_pixels``/``goal_proprio``/
    ``goal_state`` for those present). Goal entries are ``(1, ...)`` tensors (images
    ``(1, C, H, W)``). ``seed`` seeds the goal draws (per worker process and index).
    """

    def __init__(
        self,
        dataset: Dataset,
        goal_probabilities: Sequence[float] = (0.3, 0.5, 0.2),
        gamma: float = 0.99,
        goal_keys: Mapping[str, str] | None = None,
        seed: int | None = None,
    ):
        super().__init__(frameskip=dataset.frameskip, num_steps=dataset.num_steps, keys_to_load=None)
        probs = np.asarray(goal_probabilities, np.float64)
        if probs.shape != (3,) or np.any(probs < 0) or not np.isclose(probs.sum(), 1.0):
            raise ConfigError(
                f"GoalDataset requires goal_probabilities of 3 non-negative numbers summing to 1, got {goal_probabilities}"
            )
        if not 0.0 <= float(gamma) < 1.0:
            raise ConfigError(f"GoalDataset requires 0 <= gamma < 1, got {gamma}")
        self.dataset = dataset
        self.goal_probabilities = probs
        self.gamma = float(gamma)
        if goal_keys is None:
            goal_keys = {c: keys.goal_key(c) for c in (keys.PIXELS, keys.PROPRIO, keys.STATE) if c in dataset.column_names}
        self.goal_keys = dict(goal_keys)
        dataset.check_keys(list(self.goal_keys))
        self.seed = seed
        self._rng = np.random.default_rng(seed)

    @property
    def column_names(self) -> list[str]:
        return self.dataset.column_names

    @property
    def lengths(self) -> np.ndarray:
        return self.dataset.lengths

    @property
    def offsets(self) -> np.ndarray:
        return self.dataset.offsets

    def _read(self, col: str, start: int, stop: int) -> np.ndarray:
        return self.dataset._read(col, start, stop)

    def __len__(self) -> int:
        return len(self.dataset)

    def goal_row(self, idx: int, rng: np.random.Generator | None = None) -> tuple[int, int]:
        """``(kind, row)`` of the goal of sample ``idx``; kind 0 random, 1 future, 2 current."""
        rng = rng if rng is not None else self._rng
        ep, step = self.dataset.locate(idx)
        first = int(self.dataset.offsets[ep])
        end = first + int(self.dataset.lengths[ep])
        current = first + step + (self.dataset.num_steps - 1) * self.dataset.frameskip
        kind = int(rng.choice(3, p=self.goal_probabilities))
        if kind == 0:
            e = int(rng.integers(self.dataset.num_episodes))
            return kind, int(self.dataset.offsets[e]) + int(rng.integers(int(self.dataset.lengths[e])))
        if kind == 1:
            k = int(rng.geometric(1.0 - self.gamma)) if self.gamma > 0 else 1
            return kind, min(current + k, end - 1)
        return kind, current

    def __getitem__(self, idx: int) -> dict[str, Any]:
        item = self.dataset[idx]
        rng = self._rng if self.seed is None else np.random.default_rng((self.seed, int(idx) % len(self)))
        _, row = self.goal_row(int(idx) % len(self), rng)
        goal = to_tensors({dst: self.dataset._read(src, row, row + 1) for src, dst in self.goal_keys.items()})
        item.update(goal)
        return item

"""An in-memory replay buffer that is a :class:`~.dataset.Dataset` and a ``Writer`` at once
(upstream main's ``stable_worldmodel.data.ReplayBuffer``), for online learning.

Give it to anything that takes a writer (``World.collect(writer=buffer, episodes=...)``,
:func:`~stable_worldmodel.data.convert`) and the episodes land in it; hand it to a
``torch.utils.data.DataLoader`` (or call :meth:`ReplayBuffer.sample`) and it gives windows of
``history_len`` frames, spaced by ``frameskip``, never across two episodes; :meth:`ReplayBuffer.dump`
writes what it holds through any registered format, which :func:`~stable_worldmodel.data.load_dataset`
then opens.

Storage: one ring array ``(max_steps, ...)`` per column, allocated from the first episode's
columns. Episodes sit back to back in the ring, oldest first; an episode that does not fit
evicts whole episodes from the oldest end (FIFO) until it does. So the live rows are always one
contiguous stretch of the ring (modulo its length), and row ``r`` of the dataset (episodes
concatenated, oldest first) lives at ring position ``(oldest + r) % max_steps``.

Items are upstream's: numpy arrays as stored (images ``(T, H, W, C)``; a DataLoader collates
them into tensors); ``transform`` sees the gathered rows, which are then grouped per frame
(``action`` ``(T, frameskip * A)``, the other ``dense_columns`` ``(T, frameskip, ...)``);
:meth:`ReplayBuffer.sample` returns the same, ``(B, T, ...)``, untransformed.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Callable, Collection, Iterable, Iterator, Mapping
from pathlib import Path
from typing import Any

import numpy as np

from .. import keys
from ..errors import ConfigError, DatasetFormatError, NotEnoughDataError, check_int
from .dataset import Dataset, group_dense
from .format import per_step_columns

__all__ = ["ReplayBuffer", "Sampler", "classic_filter", "uniform_sampler"]

#: ``sampler(step, buffer, batch_size, history_len) -> (batch_size,) ints`` in
#: ``[0, buffer.num_valid_ends(history_len))``: which windows :meth:`ReplayBuffer.sample` returns
Sampler = Callable[[int, "ReplayBuffer", int, int], Any]

#: the columns :func:`classic_filter` keeps
CLASSIC_COLUMNS = (keys.PIXELS, keys.ACTION, keys.REWARD, "terminated", "truncated")


def uniform_sampler(step: int, buffer: ReplayBuffer, batch_size: int, history_len: int) -> np.ndarray:
    """Every window equally likely, drawn from ``buffer.rng`` (seeded by ``ReplayBuffer(seed=...)``)."""
    n = buffer.num_valid_ends(history_len)
    if n == 0:
        raise NotEnoughDataError(
            f"ReplayBuffer.sample requires a window of history_len={history_len} * frameskip={buffer.frameskip} steps "
            f"inside one episode, got none: {buffer.num_episodes} episodes, {buffer.num_steps_stored} steps stored "
            f"(longest {int(buffer.lengths.max()) if buffer.num_episodes else 0}); write more episodes first"
        )
    return buffer.rng.integers(0, n, size=batch_size)


def classic_filter(episode: Mapping[str, Any]) -> dict[str, Any]:
    """A ``key_filter`` keeping the classic replay-buffer columns (``pixels``, ``action``,
    ``reward``, ``terminated``, ``truncated``): ``ReplayBuffer(..., key_filter=classic_filter)``."""
    return {k: v for k, v in episode.items() if k in CLASSIC_COLUMNS}


class ReplayBuffer(Dataset):
    """Ring storage of the last ``max_steps`` steps of whole episodes (see the module docstring).

    Args:
        max_steps: capacity in steps; an episode longer than that is refused.
        history_len: frames per window (``num_steps`` of the other datasets).
        frameskip: rows between two frames of a window.
        sampler: which windows :meth:`sample` draws (:data:`Sampler`; default :func:`uniform_sampler`).
        transform: applied to each item (``buffer[i]``, the DataLoader path; it sees the raw
            rows, before grouping, as upstream main's guide says), not by :meth:`sample`.
        key_filter: ``episode -> episode`` applied to every written episode (e.g. :func:`classic_filter`).
        dense_columns: columns read at every row and grouped, as ``action`` always is.
        seed: of :attr:`rng`, which the default sampler draws from.
    """

    def __init__(
        self,
        max_steps: int,
        history_len: int = 1,
        frameskip: int = 1,
        sampler: Sampler | None = None,
        transform: Callable[[dict], dict] | None = None,
        key_filter: Callable[[dict], dict] | None = None,
        dense_columns: Collection[str] | str | None = None,
        *,
        seed: int | None = None,
    ):
        owner = type(self).__name__
        self.max_steps = check_int(owner, "max_steps", max_steps)
        self.history_len = check_int(owner, "history_len", history_len)
        super().__init__(
            frameskip=frameskip, num_steps=self.history_len, transform=transform, dense_columns=dense_columns
        )
        for name, fn in (("sampler", sampler), ("key_filter", key_filter)):
            if fn is not None and not callable(fn):
                raise ConfigError(f"{owner} requires {name} to be a callable or None, got {fn!r}")
        self.sampler: Sampler = sampler if sampler is not None else uniform_sampler
        self.key_filter = key_filter
        self.rng = np.random.default_rng(seed)
        self._ring: dict[str, np.ndarray] = {}
        self._episodes: deque[tuple[int, int]] = deque()  # (ring position of its first row, length), oldest first
        self._head = 0  # ring position of the next row written
        self._size = 0
        self._sample_step = 0
        self._columns: list[str] = []
        self._sync()

    # -- Writer ---------------------------------------------------------------------------------
    def __enter__(self) -> ReplayBuffer:
        return self

    def __exit__(self, *exc: Any) -> None:
        return None

    def close(self) -> None:
        """Nothing to release (the buffer lives in memory); kept for the writer protocol."""

    def write_episode(self, episode: Mapping[str, Any]) -> None:
        """Append one finished episode (column -> rows ``(L, ...)`` or a list of per-step values),
        evicting the oldest episodes until it fits."""
        episode = per_step_columns(episode, type(self).__name__)
        if self.key_filter is not None:
            episode = self.key_filter(dict(episode))
        if not episode:
            return
        rows, length = self._check(episode)
        if length == 0:
            return
        if not self._ring:
            self._ring = {c: np.empty((self.max_steps, *a.shape[1:]), a.dtype) for c, a in rows.items()}
            self._columns = list(self._ring)
        while self._size + length > self.max_steps:  # whole episodes, oldest first
            self._size -= self._episodes.popleft()[1]
        positions = self._positions(self._head, 0, length)
        for col, arr in rows.items():
            self._ring[col][positions] = arr
        self._episodes.append((self._head, length))
        self._head = (self._head + length) % self.max_steps
        self._size += length
        self._sync()

    def write_episodes(self, episodes: Iterable[Mapping[str, Any]], next_seed: int | None = None) -> None:
        """:meth:`write_episode` for each episode (``next_seed``: accepted, as HDF5Writer takes it)."""
        for episode in episodes:
            self.write_episode(episode)

    def _check(self, episode: Mapping[str, Any]) -> tuple[dict[str, np.ndarray], int]:
        owner = f"{type(self).__name__}.write_episode"
        rows = {str(c): np.asarray(v) for c, v in episode.items()}
        lengths = {c: (a.shape[0] if a.ndim else None) for c, a in rows.items()}
        if None in lengths.values():
            scalar = next(c for c, n in lengths.items() if n is None)
            raise DatasetFormatError(f"{owner} requires per-step rows in every column, got a scalar in {scalar!r}")
        if len(set(lengths.values())) > 1:
            raise DatasetFormatError(
                f"{owner} requires every column of an episode to have the same length, got {lengths}"
            )
        length = next(iter(lengths.values()))
        if length > self.max_steps:
            raise ConfigError(
                f"{owner} requires episodes of at most max_steps={self.max_steps} steps, got one of {length}; "
                "make the buffer larger"
            )
        if self._ring:
            if set(rows) != set(self._ring):
                missing, extra = sorted(set(self._ring) - set(rows)), sorted(set(rows) - set(self._ring))
                raise DatasetFormatError(
                    f"{owner} requires the columns of the first episode, got missing={missing}, extra={extra}"
                )
            for col, arr in rows.items():
                ring = self._ring[col]
                if arr.shape[1:] != ring.shape[1:] or not np.can_cast(arr.dtype, ring.dtype, "same_kind"):
                    raise DatasetFormatError(
                        f"{owner} requires column {col!r} rows of shape {ring.shape[1:]} and dtype {ring.dtype}, "
                        f"got {arr.shape[1:]} {arr.dtype}"
                    )
        return rows, int(length)

    # -- Dataset ------------------------------------------------------------------------------
    def _positions(self, ring_start: int, start: int, stop: int) -> np.ndarray:
        return (ring_start + np.arange(start, stop)) % self.max_steps

    @property
    def _oldest(self) -> int:
        return self._episodes[0][0] if self._episodes else self._head

    def _sync(self) -> None:
        """Episode lengths and offsets (episodes back to back, oldest first) for the Dataset base."""
        lengths = np.fromiter((n for _, n in self._episodes), np.int64, len(self._episodes))
        self.lengths = lengths
        self.offsets = np.concatenate([[0], np.cumsum(lengths)[:-1]]).astype(np.int64) if len(lengths) else lengths

    def _read(self, col: str, start: int, stop: int) -> np.ndarray:
        if not self._ring:
            raise NotEnoughDataError(f"ReplayBuffer column {col!r} holds nothing yet: write an episode first")
        return self._ring[col][self._positions(self._oldest, start, stop)]  # a copy: the ring moves on

    def _read_windows(self, col: str, starts: np.ndarray) -> np.ndarray:
        offsets = np.arange(0, self.span, self._row_step(col))
        return self._ring[col][(self._oldest + starts[:, None] + offsets) % self.max_steps]

    def __getitem__(self, idx: int) -> dict[str, Any]:
        """Window ``idx`` as upstream's buffer gives it: numpy arrays as stored (images
        ``(T, H, W, C)``); ``transform`` sees the gathered rows (dense columns ``T * frameskip``
        of them), which are then grouped (``action`` ``(T, frameskip * A)``, other dense columns
        ``(T, frameskip, ...)``), as upstream main's guide describes."""
        eps, steps = self._locate_many(np.asarray([idx], np.int64))  # IndexError out of range
        start = self.offsets[eps] + steps
        clip = {col: self._read_windows(col, start)[0] for col in self.keys_to_load}
        if self.transform is not None:
            clip = dict(self.transform(clip))  # grouped in a new dict: the transform's stays as it returned it
        for col in self.dense_columns.intersection(clip):
            clip[col] = group_dense(col, np.asarray(clip[col]), self.num_steps)
        return clip

    @property
    def num_steps_stored(self) -> int:
        """Steps held now (at most ``max_steps``)."""
        return self._size

    def num_valid_ends(self, history_len: int | None = None) -> int:
        """Windows of ``history_len`` frames (default: the buffer's) that fit inside one episode:
        what a :data:`Sampler` picks indices among."""
        h = self.history_len if history_len is None else check_int("ReplayBuffer", "history_len", history_len)
        return int(np.maximum(self.lengths - h * self.frameskip + 1, 0).sum())

    def sample(self, batch_size: int, history_len: int | None = None, step: int | None = None) -> dict[str, np.ndarray]:
        """``batch_size`` windows drawn by the sampler: ``{column: (batch_size, history_len, ...)}``
        numpy arrays as stored (dense columns ``(batch_size, history_len, frameskip * ...)``), no
        transform. ``step`` is passed to the sampler (default: a counter of calls)."""
        owner = "ReplayBuffer.sample"
        batch_size = check_int(owner, "batch_size", batch_size)
        h = self.history_len if history_len is None else check_int(owner, "history_len", history_len)
        if step is None:
            step, self._sample_step = self._sample_step, self._sample_step + 1
        flat = np.asarray(self.sampler(int(step), self, batch_size, h))
        if flat.shape != (batch_size,) or not np.issubdtype(flat.dtype, np.integer):
            raise DatasetFormatError(
                f"{owner} requires the sampler to return {batch_size} ints, got shape {flat.shape} of {flat.dtype}"
            )
        span = h * self.frameskip
        counts = np.maximum(self.lengths - span + 1, 0)
        cum = np.concatenate([[0], np.cumsum(counts)])
        if flat.size and (flat.min() < 0 or flat.max() >= cum[-1]):
            raise IndexError(f"{owner}: the sampler returned a window index outside [0, {int(cum[-1])})")
        eps = np.searchsorted(cum, flat, side="right") - 1
        starts = self.offsets[eps] + (flat - cum[eps])
        out = {}
        for col, ring in self._ring.items():
            dense = col in self.dense_columns
            offsets = np.arange(0, span, 1 if dense else self.frameskip)
            rows = ring[(self._oldest + starts[:, None] + offsets) % self.max_steps]
            out[col] = group_dense(col, rows, h, batched=True) if dense else rows
        return out

    # -- contents -----------------------------------------------------------------------------
    def episodes(self) -> Iterator[dict[str, np.ndarray]]:
        """Each stored episode, oldest first, as column -> rows ``(L, ...)`` (what writers take)."""
        for ring_start, length in list(self._episodes):
            positions = self._positions(ring_start, 0, length)
            yield {col: ring[positions] for col, ring in self._ring.items()}

    def dump(self, path: str | Path, format: str, mode: str = "overwrite", **kwargs: Any) -> Path:  # noqa: A002 - upstream's name
        """Write every stored episode to ``path`` through the registered ``format``'s writer
        (``mode`` as :data:`~.format.WRITE_MODES`; ``kwargs`` go to the writer); returns ``path``."""
        from .format import get_format

        with get_format(format).open_writer(path, mode=mode, **kwargs) as writer:
            writer.write_episodes(self.episodes())
        return Path(path)

    def clear(self) -> None:
        """Drop every episode (the ring arrays are kept for the next ones)."""
        self._episodes.clear()
        self._head = self._size = 0
        self._sync()

    def __repr__(self) -> str:
        return (
            f"ReplayBuffer(episodes={self.num_episodes}, steps={self._size}/{self.max_steps}, "
            f"history_len={self.history_len}, frameskip={self.frameskip}, columns=[{', '.join(self._columns)}])"
        )

"""Factories for small datasets written by the tests themselves."""

from __future__ import annotations

import numpy as np
import pytest

from stable_worldmodel import keys


def synthetic_episode(ep: int, length: int, image: tuple[int, int] = (8, 8)) -> dict[str, np.ndarray]:
    """An episode whose values encode (episode, step), so every read can be checked exactly."""
    steps = np.arange(length)
    action = np.stack([ep * 1000 + steps, -steps], axis=1).astype(np.float32)
    action[-1] = np.nan
    pixels = np.zeros((length, *image, 3), np.uint8)
    pixels[..., 0] = (ep * 10 + steps[:, None, None]) % 256
    pixels[..., 1] = 7
    return {
        keys.PIXELS: pixels,
        keys.ACTION: action,
        keys.STATE: np.stack([np.full(length, ep), steps], axis=1).astype(np.float64),
        keys.STEP_IDX: steps.astype(np.int64),
        keys.TERMINATED: steps == length - 1,
    }


@pytest.fixture
def make_h5(tmp_path):
    """``make_h5(lengths, name, image, **writer_options)`` writes synthetic episodes with those lengths;
    returns the path."""
    from stable_worldmodel.data.writer import HDF5Writer

    def make(lengths=(5, 7, 4), name="synth", image=(8, 8), **writer_options):
        path = tmp_path / f"{name}.h5"
        with HDF5Writer(path, **writer_options) as writer:
            writer.write_episodes(
                [synthetic_episode(e, n, image) for e, n in enumerate(lengths)], next_seed=len(lengths)
            )
        return path

    return make


@pytest.fixture
def synth():
    """The :func:`synthetic_episode` factory."""
    return synthetic_episode


@pytest.fixture
def cut_writes(monkeypatch):
    """``cut_writes(path, first_only=False)``: from then on, before each write of the HDF5 writers
    over bytes of ``path`` already written that spans pages, record what a kill inside it can leave
    (the kernel stops at a page boundary): ``(file bytes, redo record bytes)`` for each boundary,
    appended to the returned list (only the first such state with ``first_only``)."""
    import os

    from stable_worldmodel.data import _redo, _superblock

    def start(path, first_only=False):
        states = []

        class Cutting(_superblock.SealedFile):
            def _pwrite(self, view, pos):
                if path.exists() and pos < self._written and _redo.spans_pages(pos, len(view)):
                    if not (first_only and states):
                        now = os.pread(self._fd, 1 << 30, 0)
                        record = _redo.record_path(path).read_bytes()
                        cuts = range(_redo.PAGE - pos % _redo.PAGE, len(view), _redo.PAGE)
                        for cut in cuts[:1] if first_only else cuts:
                            states.append((now[:pos] + bytes(view[:cut]) + now[pos + cut :], record))
                super()._pwrite(view, pos)

        monkeypatch.setattr(_superblock, "SealedFile", Cutting)
        return states

    return start

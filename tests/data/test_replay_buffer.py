"""``data.ReplayBuffer`` and the writer protocol pieces of upstream's main branch (Aug 2026):
``WRITE_MODES`` / ``validate_write_mode``, ``HDF5Writer(mode=)`` and ``write_episode``,
``dense_columns``. Behaviour follows upstream main's ``data/buffer.py`` and ``data/format.py``."""

from __future__ import annotations

import numpy as np
import pytest
import torch

from stable_worldmodel import data, keys
from stable_worldmodel.data import HDF5Dataset, ReplayBuffer, classic_filter
from stable_worldmodel.data.format import WRITE_MODES, Writer, validate_write_mode
from stable_worldmodel.data.writer import HDF5Writer
from stable_worldmodel.errors import ConfigError, DatasetFormatError, NotEnoughDataError


def episode(ep: int, length: int, image: bool = False) -> dict[str, np.ndarray]:
    """Rows that name themselves: ``ep`` (the episode), ``step`` (the row), a 2-d action."""
    out = {
        "ep": np.full(length, ep, np.int64),
        "step": np.arange(length, dtype=np.int64),
        keys.ACTION: np.stack([np.full(length, ep), np.arange(length)], axis=1).astype(np.float32),
    }
    if image:
        out[keys.PIXELS] = np.full((length, 4, 4, 3), ep, np.uint8)
    return out


def stored(buffer: ReplayBuffer) -> list[tuple[int, int]]:
    """(episode id, length) of what the buffer holds, oldest first."""
    return [(int(e["ep"][0]), len(e["ep"])) for e in buffer.episodes()]


def test_fifo_eviction_of_whole_episodes_and_ring_wraparound():
    buf = ReplayBuffer(max_steps=10)
    for ep, n in enumerate((4, 4)):
        buf.write_episode(episode(ep, n))
    assert stored(buf) == [(0, 4), (1, 4)] and buf.num_steps_stored == 8
    buf.write_episode(episode(2, 5))  # 13 > 10: the oldest goes
    assert stored(buf) == [(1, 4), (2, 5)] and buf.num_steps_stored == 9
    for ep in range(3, 40):  # many laps of the ring, lengths 1..6
        buf.write_episode(episode(ep, 1 + ep % 6))
    kept = stored(buf)
    assert sum(n for _, n in kept) <= 10 and [e for e, _ in kept] == list(range(kept[0][0], 40))
    assert sum(n for _, n in kept) + (1 + (kept[0][0] - 1) % 6) > 10  # nothing evicted that would have fitted
    for got in buf.episodes():  # every row intact after the wrap-around
        ep = int(got["ep"][0])
        np.testing.assert_array_equal(got["step"], np.arange(1 + ep % 6))
        np.testing.assert_array_equal(got[keys.ACTION][:, 0], ep)
    # the Dataset side reads the same rows: columns, items, windows and samples
    rows = [(int(e), int(t)) for got in buf.episodes() for e, t in zip(got["ep"], got["step"], strict=True)]
    assert list(zip(buf.get_col_data("ep").tolist(), buf.get_col_data("step").tolist(), strict=True)) == rows
    wide = ReplayBuffer(max_steps=10, history_len=2, seed=0)
    for ep in range(25):
        wide.write_episode(episode(ep, 3))
    windows = [(item["ep"].tolist(), item["step"].tolist()) for item in wide]
    assert windows == [([e, e], [s, s + 1]) for e in (22, 23, 24) for s in (0, 1)]
    assert wide[5]["ep"].tolist() == [24, 24] and wide[5]["step"].tolist() == [1, 2]
    drawn = wide.sample(50)
    assert set(drawn["ep"][:, 0].tolist()) == {22, 23, 24} and (drawn["ep"][:, 0] == drawn["ep"][:, 1]).all()
    assert (np.diff(drawn["step"], axis=1) == 1).all()


def test_windows_never_cross_episodes_and_follow_frameskip():
    buf = ReplayBuffer(max_steps=50, history_len=2, frameskip=2)
    for ep, n in enumerate((5, 3, 7)):
        buf.write_episode(episode(ep, n))
    assert len(buf) == buf.num_valid_ends() == (5 - 3) + 0 + (7 - 3)  # span 4 fits in 5 (2 starts) and 7 (4)
    assert buf.num_valid_ends(history_len=1) == 4 + 2 + 6
    seen = []
    for item in buf:
        ep, steps = item["ep"].tolist(), item["step"].tolist()
        assert len(set(ep)) == 1 and steps[1] - steps[0] == 2  # one episode, frames frameskip apart
        action = item[keys.ACTION]  # dense: every row, grouped (T, frameskip * A)
        assert action.shape == (2, 4) and action[:, 1::2].flatten().tolist() == list(range(steps[0], steps[0] + 4))
        seen.append((ep[0], steps[0]))
    assert seen == [(0, 0), (0, 1), (2, 0), (2, 1), (2, 2), (2, 3)]


def test_items_are_numpy_as_stored_and_collate_in_a_dataloader():
    """As 0.1.1's buffer (observed): ``buf[i]`` is numpy, images (T, H, W, C) as stored."""
    buf = ReplayBuffer(max_steps=40, history_len=3)
    for ep in range(4):
        buf.write_episode(episode(ep, 6, image=True))
    item = buf[0]
    assert isinstance(item[keys.PIXELS], np.ndarray) and item[keys.PIXELS].shape == (3, 4, 4, 3)
    batch = next(iter(torch.utils.data.DataLoader(buf, batch_size=5, shuffle=False)))
    assert batch[keys.PIXELS].shape == (5, 3, 4, 4, 3) and batch[keys.PIXELS].dtype == torch.uint8
    assert batch[keys.ACTION].shape == (5, 3, 2) and batch["ep"].shape == (5, 3)
    with pytest.raises(IndexError):
        buf[len(buf)]
    doubled = ReplayBuffer(max_steps=40, history_len=3, transform=lambda item: {**item, "ep": item["ep"] * 2})
    doubled.write_episode(episode(3, 6))
    assert doubled[0]["ep"].tolist() == [6, 6, 6]


def test_sample_is_seeded_numpy_and_takes_a_custom_sampler():
    def fill(buf):
        for ep in range(5):
            buf.write_episode(episode(ep, 8, image=True))
        return buf

    a, b = (
        fill(ReplayBuffer(max_steps=100, history_len=2, seed=3)),
        fill(ReplayBuffer(max_steps=100, history_len=2, seed=3)),
    )
    x, y = a.sample(16), b.sample(16)
    assert x.keys() == y.keys() == {"ep", "step", keys.ACTION, keys.PIXELS}
    for col in x:
        np.testing.assert_array_equal(x[col], y[col])
    assert isinstance(x["ep"], np.ndarray) and x[keys.PIXELS].shape == (16, 2, 4, 4, 3)  # as stored
    assert x[keys.ACTION].shape == (16, 2, 2) and (np.diff(x["step"], axis=1) == 1).all()
    assert (x["ep"][:, 0] == x["ep"][:, 1]).all()
    assert a.sample(4, history_len=5)["step"].shape == (4, 5)

    calls = []

    def first_windows(step, buffer, batch_size, history_len):
        calls.append((step, batch_size, history_len, buffer.num_valid_ends(history_len)))
        return np.arange(batch_size)

    buf = fill(ReplayBuffer(max_steps=100, history_len=3, sampler=first_windows))
    buf.sample(2)
    buf.sample(2, history_len=4, step=40)
    buf.sample(2)
    assert calls == [(0, 2, 3, 30), (40, 2, 4, 25), (1, 2, 3, 30)]
    assert buf.sample(3)["step"][:, 0].tolist() == [0, 1, 2]


def test_bad_sampler_output_and_empty_buffers_are_typed_errors():
    bad = ReplayBuffer(100, sampler=lambda *a: np.zeros(2, int))
    bad.write_episode(episode(0, 3))
    with pytest.raises(DatasetFormatError, match=r"requires the sampler to return 4 ints, got shape \(2,\)"):
        bad.sample(4)
    far = ReplayBuffer(100, sampler=lambda step, buf, n, h: np.full(n, 99))
    far.write_episode(episode(0, 3))
    with pytest.raises(IndexError, match=r"outside \[0, 3\)"):
        far.sample(2)
    empty = ReplayBuffer(100, history_len=4)
    with pytest.raises(NotEnoughDataError, match="history_len=4.*0 episodes") as err:
        empty.sample(2)
    assert isinstance(err.value, RuntimeError)  # as upstream
    empty.write_episode(episode(0, 3))  # shorter than a window
    with pytest.raises(NotEnoughDataError, match="longest 3"):
        empty.sample(2)
    assert len(empty) == 0


def test_bad_episodes_and_arguments_are_typed_errors():
    buf = ReplayBuffer(max_steps=5)
    with pytest.raises(ConfigError, match="at most max_steps=5 steps, got one of 6"):
        buf.write_episode(episode(0, 6))
    buf.write_episode(episode(0, 3))
    with pytest.raises(DatasetFormatError, match=r"missing=\['step'\], extra=\['other'\]"):
        buf.write_episode({**{k: v for k, v in episode(1, 2).items() if k != "step"}, "other": np.zeros(2)})
    with pytest.raises(DatasetFormatError, match="same length"):
        buf.write_episode({**episode(1, 2), "step": np.arange(3)})
    with pytest.raises(DatasetFormatError, match=r"column 'action' rows of shape \(2,\)"):
        buf.write_episode({**episode(1, 2), keys.ACTION: np.zeros((2, 3), np.float32)})
    assert stored(buf) == [(0, 3)]  # nothing half-written
    for kwargs, needle in (
        (dict(max_steps=0), "max_steps to be an integer >= 1, got 0"),
        (dict(max_steps=5, history_len=True), "history_len"),
        (dict(max_steps=5, sampler="uniform"), "sampler to be a callable"),
    ):
        with pytest.raises(ConfigError, match=needle):
            ReplayBuffer(**kwargs)


def test_key_filter_and_clear():
    buf = ReplayBuffer(max_steps=20, key_filter=classic_filter)
    buf.write_episode({**episode(0, 4, image=True), keys.REWARD: np.ones(4), "terminated": np.zeros(4, bool)})
    assert sorted(buf.column_names) == sorted([keys.ACTION, keys.PIXELS, keys.REWARD, "terminated"])
    buf.clear()
    assert buf.num_episodes == 0 and len(buf) == 0 and buf.num_steps_stored == 0
    buf.write_episode({**episode(5, 2, image=True), keys.REWARD: np.ones(2), "terminated": np.zeros(2, bool)})
    assert buf.num_episodes == 1 and "ReplayBuffer(episodes=1, steps=2/20" in repr(buf)


def test_collect_into_the_buffer_then_dump_to_any_format(tmp_path):
    import stable_worldmodel as swm

    buf = ReplayBuffer(max_steps=500, history_len=2)
    assert isinstance(buf, Writer)
    with swm.World("swm/Toy-v0", 2, (8, 8), max_episode_steps=6, verbose=0) as world:
        world.set_policy(swm.policy.RandomPolicy(seed=0))
        world.collect(writer=buf, episodes=3, seed=0)
    assert buf.num_episodes == 3 and keys.PIXELS in buf.column_names
    for fmt in ("hdf5", "folder"):
        path = buf.dump(tmp_path / f"out-{fmt}" if fmt == "folder" else tmp_path / "out.h5", format=fmt)
        back = data.load_dataset(path)
        assert back.num_episodes == 3 and list(back.lengths) == list(buf.lengths)
        np.testing.assert_array_equal(back.get_col_data(keys.ACTION), buf.get_col_data(keys.ACTION))
        if fmt == "hdf5":
            np.testing.assert_array_equal(back.get_col_data(keys.PIXELS), buf.get_col_data(keys.PIXELS))
    buf.dump(tmp_path / "out.h5", format="hdf5")  # overwrite, the default
    assert data.load_dataset(tmp_path / "out.h5").num_episodes == 3
    buf.dump(tmp_path / "out.h5", format="hdf5", mode="append")
    assert data.load_dataset(tmp_path / "out.h5").num_episodes == 6


def test_write_modes_of_upstream():
    assert WRITE_MODES == ("append", "overwrite", "error")
    assert validate_write_mode("error") == "error"
    with pytest.raises(ValueError, match="mode to be one of 'append', 'overwrite', 'error', got 'apend'.*'append'"):
        validate_write_mode("apend")


def test_hdf5_writer_modes_write_episode_and_generators(tmp_path):
    path = tmp_path / "w.h5"
    with HDF5Writer(path, mode="error") as w:
        w.write_episode(episode(0, 3))
        w.write_episodes(episode(ep, 2) for ep in range(1, 40))  # a generator: committed 32 episodes at a time
    assert HDF5Dataset(path=path).num_episodes == 40
    with pytest.raises(FileExistsError, match="mode='error'.*exists"):
        HDF5Writer(path, mode="error")
    with HDF5Writer(path) as w:  # append, the default
        w.write_episode(episode(40, 2))
    assert HDF5Dataset(path=path).num_episodes == 41
    with HDF5Writer(path, mode="overwrite") as w:
        w.write_episode({k: list(v) for k, v in episode(7, 4).items()})  # per-step lists, as World.collect gives
    back = HDF5Dataset(path=path)
    assert back.num_episodes == 1 and back.get_col_data("ep").tolist() == [7] * 4
    with pytest.raises(ConfigError, match="mode"):
        HDF5Writer(path, mode="truncate")


def test_episode_scoped_data_is_dropped_with_a_warning(tmp_path, caplog):
    with HDF5Writer(tmp_path / "e.h5") as w:
        w.write_episode({**episode(0, 2), "_episode_data": {"scene": "<xml/>"}})
    assert "stores no episode-scoped data: dropped scene" in caplog.text
    assert "_episode_data" not in HDF5Dataset(path=tmp_path / "e.h5").column_names


def test_dense_columns_of_a_dataset(tmp_path):
    with HDF5Writer(tmp_path / "d.h5") as w:
        w.write_episodes([episode(0, 6)])
    ds = HDF5Dataset(path=tmp_path / "d.h5", num_steps=2, frameskip=3, dense_columns=["step"])
    item = ds[0]
    assert item["step"].tolist() == [[0, 1, 2], [3, 4, 5]]  # every row, grouped like the action
    assert item["ep"].tolist() == [0, 0] and item[keys.ACTION].shape == (2, 6)
    assert ds.__getitems__([0])[0]["step"].tolist() == [[0, 1, 2], [3, 4, 5]]


# -- upstream main's docs/guides/online_learning.md, its snippets as written --------------------------------
def test_guide_quick_tour_runs_unchanged(tmp_path, monkeypatch):
    """The guide's Quick Tour (``train_step`` is the reader's: here it counts batches)."""
    monkeypatch.chdir(tmp_path)
    batches = []

    def train_step(batch):
        batches.append(batch)

    from torch.utils.data import DataLoader

    import stable_worldmodel as swm
    from stable_worldmodel.data import ReplayBuffer

    # 1) Create a buffer. max_steps caps total in-RAM transitions.
    buf = ReplayBuffer(max_steps=100_000, history_len=4)

    # 2) Fill it. World.collect accepts the buffer directly as a writer.
    world = swm.World("swm/PushT-v1", num_envs=4, image_shape=(64, 64))
    world.set_policy(swm.policy.RandomPolicy(seed=0))
    world.collect(writer=buf, episodes=20, seed=0)

    # 3) Train on it via a DataLoader (Dataset path).
    loader = DataLoader(buf, batch_size=64, shuffle=True)
    for batch in loader:
        train_step(batch)  # batch[col] shape: (64, history_len, ...)

    # 4) Or sample directly (custom-sampler path).
    batch = buf.sample(batch_size=64)  # {col: (64, history_len, ...)} numpy arrays

    # 5) Dump to disk at any point — picks any registered Format.
    buf.dump("runs/replay.h5", format="hdf5")

    assert buf.num_episodes == 20 and len(batches) == -(-len(buf) // 64)
    assert batches[0]["pixels"].shape == (64, 4, 64, 64, 3) and batch["pixels"].shape == (64, 4, 64, 64, 3)
    assert swm.data.load_dataset("runs/replay.h5").num_episodes == 20


def test_guide_eviction_and_frameskip_semantics():
    def _ep(n, a=2):
        return {
            "pixels": np.zeros((n, 4, 4, 3), np.uint8),
            "action": np.ones((n, a), np.float32),
            "reward": np.arange(n, dtype=np.float32),
            "terminated": np.arange(n) == n - 1,
        }

    buf = ReplayBuffer(max_steps=50, history_len=2)
    buf.write_episode(_ep(30))  # buf: [30 steps]
    buf.write_episode(_ep(15))  # buf: [30, 15] — 45 steps used
    buf.write_episode(_ep(20))  # buf: [15, 20] — oldest episode evicted to fit
    assert buf.lengths.tolist() == [15, 20]

    buf = ReplayBuffer(max_steps=10_000, history_len=4, frameskip=2, dense_columns=["reward", "terminated"])
    buf.write_episode(_ep(12))
    clip = buf[0]
    assert clip["pixels"].shape == (4, 4, 4, 3)  # strided observations
    assert clip["action"].shape == (4, 2 * 2)  # action chunks
    assert clip["reward"].shape == (4, 2) and clip["terminated"].shape == (4, 2)
    assert clip["reward"].tolist() == [[0, 1], [2, 3], [4, 5], [6, 7]]
    seen = []
    raw = ReplayBuffer(
        1000, history_len=4, frameskip=2, dense_columns=["reward"], transform=lambda c: seen.append(c) or c
    )
    raw.write_episode(_ep(12))
    raw[0]
    assert seen[0]["reward"].shape == (8,) and seen[0]["pixels"].shape == (4, 4, 4, 3)  # rows before grouping
    sampled = buf.sample(3)
    assert sampled["reward"].shape == (3, 4, 2) and sampled["action"].shape == (3, 4, 4)
    vec = ReplayBuffer(1000, history_len=2, frameskip=3, dense_columns=["state"])
    vec.write_episode({"state": np.arange(24, dtype=np.float32).reshape(12, 2), "action": np.zeros((12, 1))})
    assert vec[0]["state"].shape == (2, 3, 2)  # (H, K, ...) for a vector column

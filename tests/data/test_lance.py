"""The ``lance`` format (upstream 0.1.1's default collect format): our writer and reader, and a
dataset written by the original (``fixtures/upstream011.lance``, made by
``fixtures/make_upstream011_lance.py`` with stable-worldmodel 0.1.1's LanceWriter). Behaviour
follows 0.1.1's ``data/formats/lance.py`` as observed running it."""

from __future__ import annotations

import shutil
import sys
from pathlib import Path

import numpy as np
import pytest
import torch

from stable_worldmodel import data, keys
from stable_worldmodel.errors import ConfigError, DatasetFormatError, DependencyNotInstalled

pytest.importorskip("lance")
from stable_worldmodel.data.lance import LanceDataset, LanceWriter  # noqa: E402 - after the skip

UPSTREAM = Path(__file__).parent / "fixtures" / "upstream011.lance"


def episode(e: int, n: int) -> dict[str, np.ndarray]:
    """The episodes of make_upstream011_lance.py, with a bool column."""
    rng = np.random.default_rng(e)
    return {
        keys.PIXELS: (np.arange(n * 8 * 8 * 3).reshape(n, 8, 8, 3) * (e + 1) % 251).astype(np.uint8),
        keys.ACTION: rng.standard_normal((n, 2)).astype(np.float32),
        keys.STATE: np.arange(n * 3, dtype=np.float64).reshape(n, 3) + 100 * e,
        keys.REWARD: np.linspace(0, 1, n),
        "terminated": np.arange(n) == n - 1,
        "variation.color": np.tile([e, 1.0, 2.0], (n, 1)),
        "note": np.array([f"ep{e}"] * n),
        "step_idx": np.arange(n),
    }


def write(path, lengths=(4, 3, 5), **kwargs) -> Path:
    with LanceWriter(path, **kwargs) as w:
        w.write_episode(episode(0, lengths[0]))
        w.write_episodes([episode(e, n) for e, n in enumerate(lengths[1:], start=1)])
    return path


def test_round_trip_keeps_names_shapes_and_dtypes(tmp_path):
    path = write(tmp_path / "x.lance")
    ds = data.load_dataset(path, num_steps=2)
    assert isinstance(ds, LanceDataset) and ds.lengths.tolist() == [4, 3, 5] and len(ds) == 3 + 2 + 4
    assert set(ds.column_names) == set(episode(0, 1))  # the dotted name and step_idx come back as written
    want = {e: episode(e, n) for e, n in enumerate((4, 3, 5))}
    for col in (keys.STATE, keys.ACTION, keys.REWARD, "terminated", "variation.color", "step_idx"):
        got = ds.get_col_data(col)
        expected = np.concatenate([want[e][col] for e in range(3)])
        assert got.dtype == expected.dtype and got.shape == expected.shape, col
        np.testing.assert_array_equal(got, expected)
    frames = ds.get_col_data(keys.PIXELS)  # JPEG, quality 95, as upstream stores them
    assert frames.shape == (12, 8, 8, 3) and frames.dtype == np.uint8
    assert np.abs(frames.astype(int) - np.concatenate([want[e][keys.PIXELS] for e in range(3)])).mean() < 8
    assert ds.column_shape(keys.STATE) == ((3,), np.dtype(np.float64))
    item = ds[3]  # the first window of episode 1
    assert item["step_idx"].tolist() == [0, 1] and item[keys.STATE][0].tolist() == [100.0, 101.0, 102.0]
    assert item[keys.PIXELS].shape == (2, 3, 8, 8) and item["note"] == "ep1"
    batch = next(iter(torch.utils.data.DataLoader(ds, batch_size=4)))
    assert batch[keys.ACTION].shape == (4, 2, 2) and batch["note"] == ["ep0", "ep0", "ep0", "ep1"]


def test_a_dataset_written_by_upstream_011_reads_as_upstream_reads_it():
    ds = data.load_dataset(UPSTREAM, num_steps=2)
    assert isinstance(ds, LanceDataset) and ds.lengths.tolist() == [4, 3, 5]
    # what 0.1.1's reader gives: float32 fixed-size lists as (N, d), the dotted name renamed, text kept,
    # step_idx dropped by its writer (the name of its index column)
    assert ds.column_names == [keys.PIXELS, keys.ACTION, keys.STATE, keys.REWARD, "variation_color", "note"]
    state = ds.get_col_data(keys.STATE)
    assert state.dtype == np.float32 and state[:5].tolist() == [
        [0, 1, 2],
        [3, 4, 5],
        [6, 7, 8],
        [9, 10, 11],
        [100, 101, 102],
    ]
    assert ds.get_col_data(keys.REWARD).shape == (12, 1)
    item = ds[0]
    assert item[keys.PIXELS].shape == (2, 3, 8, 8) and item["note"] == "ep0" and item[keys.ACTION].shape == (2, 2)


def test_our_files_have_the_schema_upstream_reads(tmp_path):
    """0.1.1's reader needs: int32 episode_idx / step_idx, binary frames, fixed-size lists (any
    dtype: it reshapes them to (N, d)), strings, and no dots in names. Ours keep the dtype."""
    import lance
    import pyarrow as pa

    ours = lance.dataset(str(write(tmp_path / "ours.lance"))).schema
    theirs = lance.dataset(str(UPSTREAM)).schema
    assert [f.name for f in ours if f.name != "terminated"] == theirs.names
    for field in theirs:
        mine = ours.field(field.name)
        assert type(mine.type) is type(field.type), field.name  # same Arrow type family
        if pa.types.is_fixed_size_list(field.type):
            assert mine.type.list_size == field.type.list_size
    assert ours.field(keys.STATE).type.value_type == pa.float64()  # upstream: float32


def test_write_modes_and_appending_to_upstreams_file(tmp_path):
    path = write(tmp_path / "m.lance")
    with pytest.raises(FileExistsError, match="mode='error'.*exists"):
        LanceWriter(path, mode="error")
    write(path, lengths=(2, 2))  # append, the default: episode numbers continue
    ds = LanceDataset(path)
    assert ds.lengths.tolist() == [4, 3, 5, 2, 2] and ds.get_col_data("variation.color")[-1, 0] == 1.0
    write(path, lengths=(6,), mode="overwrite")
    assert LanceDataset(path).lengths.tolist() == [6]
    with pytest.raises(ConfigError, match="mode to be one of"):
        LanceWriter(path, mode="replace")
    with LanceWriter(path, overwrite=True) as w:  # 0.1.1's older keyword
        w.write_episode(episode(0, 2))
    assert LanceDataset(path).lengths.tolist() == [2]

    copy = tmp_path / "upstream.lance"
    shutil.copytree(UPSTREAM, copy)
    with LanceWriter(copy) as w:  # its columns, by their renamed names; step_idx is its index
        w.write_episode({k: v for k, v in episode(3, 2).items() if k != "terminated"})
    ds = LanceDataset(copy)
    assert ds.lengths.tolist() == [4, 3, 5, 2] and ds.get_col_data(keys.STATE)[-1].tolist() == [303.0, 304.0, 305.0]


def test_a_commit_that_fails_leaves_the_earlier_ones_readable(tmp_path):
    def episodes():
        for e in range(40):
            yield episode(e % 3, 3)
        raise RuntimeError("the collector died")

    with pytest.raises(RuntimeError, match="collector died"), LanceWriter(tmp_path / "c.lance") as w:
        w.write_episodes(episodes())
    assert LanceDataset(tmp_path / "c.lance").num_episodes == 32  # the first commit of 32 episodes


def test_bad_input_is_a_typed_error(tmp_path):
    with pytest.raises(ConfigError, match="path ending in .lance, or table_name="):
        LanceWriter(tmp_path / "plain")
    with LanceWriter(tmp_path / "t", table_name="tab") as w:  # a LanceDB folder and a table, as upstream
        w.write_episode(episode(0, 2))
    assert LanceDataset(tmp_path / "t", table_name="tab").num_episodes == 1
    assert LanceDataset(tmp_path / "t").num_episodes == 1  # the one table in the folder
    with LanceWriter(tmp_path / "s.lance") as w:
        w.write_episode(episode(0, 3))
        with pytest.raises(DatasetFormatError, match=r"missing=\['note'\]"):
            w.write_episode({k: v for k, v in episode(1, 3).items() if k != "note"})
        with pytest.raises(DatasetFormatError, match="step_idx.*index column.*0, 1, ..., L-1"):
            w.write_episode({**episode(1, 3), "step_idx": np.array([5, 6, 7])})
    assert LanceDataset(tmp_path / "s.lance").num_episodes == 1


def test_missing_pylance_names_the_extra(tmp_path, monkeypatch):
    monkeypatch.setitem(sys.modules, "lance", None)  # import lance -> ImportError
    with pytest.raises(DependencyNotInstalled, match=r"stable-worldmodel\[lance\]"):
        LanceWriter(tmp_path / "x.lance")


def test_a_dataloader_with_workers_reads_a_lance_dataset(tmp_path):
    """lance is not fork-safe (a forked worker that reads crashes): opening a dataset makes workers
    spawn, as upstream does. Run in a fresh interpreter, as a user's script."""
    import subprocess

    write(tmp_path / "w.lance")
    script = tmp_path / "load.py"
    script.write_text(
        "import multiprocessing as mp, torch\n"
        "from stable_worldmodel.data import load_dataset\n"
        "if __name__ == '__main__':\n"
        f"    ds = load_dataset({str(tmp_path / 'w.lance')!r}, num_steps=2)\n"
        "    ds[0]  # the parent reads first\n"
        "    loader = torch.utils.data.DataLoader(ds, batch_size=2, num_workers=2)\n"
        "    print(mp.get_start_method(), sum(len(b['action']) for b in loader), len(ds))\n"
    )
    out = subprocess.run([sys.executable, str(script)], capture_output=True, text=True, timeout=120)
    assert out.stdout.split() == ["spawn", "9", "9"], out.stderr[-2000:]


def test_upstream_main_dataset_docs_lance_tab_runs_unchanged(tmp_path, monkeypatch):
    """upstream main's docs/api/dataset.md, tab "LanceDB Format", with its local-path ``uri``
    (object stores need credentials and a network: ``connect_kwargs`` is refused with a typed error)."""
    monkeypatch.chdir(tmp_path)
    with LanceWriter("./lewm_lance/lewm_pusht.lance") as w:
        for e in range(2):
            ep = episode(e, 12)
            w.write_episode({**ep, keys.PROPRIO: ep[keys.STATE][:, :2].astype(np.float32)})
    from stable_worldmodel.data import LanceDataset

    dataset = LanceDataset(
        uri="./lewm_lance/lewm_pusht.lance",
        num_steps=4,
        frameskip=5,
        keys_to_load=["pixels", "action", "proprio"],
    )
    shared = LanceDataset(uri="./lewm_lance", table_name="lewm_pusht", num_steps=4, frameskip=5)
    assert len(dataset) == len(shared) == 0  # 12 steps hold no 4-step clip at frameskip 5
    dataset = LanceDataset(uri="./lewm_lance/lewm_pusht.lance", num_steps=2, frameskip=5, keys_to_load=["pixels"])
    item = dataset[0]
    assert len(dataset) == 2 * 3 and set(item) == {"pixels"} and item["pixels"].shape == (2, 3, 8, 8)
    with pytest.raises(ConfigError, match="local Lance directories only.*aws_region"):
        LanceDataset(uri="./lewm_lance/lewm_pusht.lance", connect_kwargs={"aws_region": "us-east-2"})

"""0.0.3 recordings (Blosc-compressed HDF5) and the 0.1.1 loading surface: load_dataset,
get_cache_dir(cache_dir, sub_folder), column_normalizer."""

from __future__ import annotations

import pickle
import subprocess
import sys

import numpy as np
import pytest

from stable_worldmodel import data, keys
from stable_worldmodel.data import HDF5Dataset
from stable_worldmodel.errors import ConfigError, DatasetFormatError


def write_like_003(path, lengths=(4, 6)):
    """An HDF5 file laid out and compressed as 0.0.3's World.record_dataset writes it."""
    h5py = pytest.importorskip("h5py")
    hdf5plugin = pytest.importorskip("hdf5plugin")

    n = int(sum(lengths))
    pixels = (np.arange(n)[:, None, None, None] * np.ones((1, 8, 8, 3))).astype(np.uint8)
    with h5py.File(path, "w", libver="latest") as f:
        blosc = hdf5plugin.Blosc(cname="lz4", clevel=5, shuffle=hdf5plugin.Blosc.SHUFFLE)
        f.create_dataset(keys.PIXELS, data=pixels, chunks=(100, 8, 8, 3), maxshape=(None, 8, 8, 3), **blosc)
        f.create_dataset(
            keys.ACTION, data=np.arange(2 * n, dtype=np.float32).reshape(n, 2), chunks=(1000, 2), maxshape=(None, 2)
        )
        f.create_dataset(keys.EP_OFFSET, data=np.concatenate([[0], np.cumsum(lengths)[:-1]]).astype(np.int64))
        f.create_dataset(keys.EP_LEN, data=np.asarray(lengths, np.int32))
    return pixels


def test_blosc_compressed_003_files_open_with_no_extra_step(tmp_path):
    pixels = write_like_003(tmp_path / "old.h5")
    code = (
        "import sys; from stable_worldmodel.data import HDF5Dataset; "
        f"ds = HDF5Dataset({str(tmp_path / 'old.h5')!r}, num_steps=2, preload=False); "
        "print(ds[5]['pixels'][:, 0, 0, 0].tolist(), ds.get_col_data('pixels').shape)"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr[-2000:]
    assert out.stdout.split("\n")[0] == "[6, 7] (10, 8, 8, 3)"  # sample 5 = episode 1, steps 2-3 = rows 6-7
    ds = HDF5Dataset(tmp_path / "old.h5")
    np.testing.assert_array_equal(ds.get_col_data(keys.PIXELS), pixels)


def test_hdf5plugin_is_a_dependency():
    from pathlib import Path

    import tomllib

    pyproject = Path(__file__).resolve().parents[2] / "pyproject.toml"
    deps = tomllib.loads(pyproject.read_text())["project"]["dependencies"]
    assert any(d.replace(" ", "").startswith("hdf5plugin") for d in deps)


def test_load_dataset_as_in_011(make_h5, tmp_path):
    home = data.get_cache_dir()
    make_h5((3, 4), name="a")
    sub = data.get_cache_dir(sub_folder="datasets")  # where 0.1.1 keeps datasets
    (sub / "b.h5").write_bytes((tmp_path / "a.h5").read_bytes())
    ds = data.load_dataset("b", num_steps=2, frameskip=1, keys_to_load=[keys.STATE], keys_to_cache=[keys.STATE])
    assert isinstance(ds, HDF5Dataset) and ds.path == sub / "b.h5" and len(ds) == 2 + 3
    assert ds.column_names == [keys.STATE] and ds.num_steps == 2
    default = data.load_dataset(tmp_path / "a.h5")
    assert default.num_steps == 1 and default.frameskip == 1 and default.transform is None and len(default) == 7
    assert data.load_dataset("a", tmp_path).path == tmp_path / "a.h5"  # 0.1.1's positional cache_dir
    assert isinstance(data.load_dataset(tmp_path / "a.h5", format="hdf5"), HDF5Dataset)
    with pytest.raises(FileNotFoundError, match="does not exist"):
        data.load_dataset("nope")
    with pytest.raises(ValueError, match="Did you mean 'hdf5'"):
        data.load_dataset(tmp_path / "a.h5", format="hdf6")
    (home / "junk").mkdir()
    with pytest.raises(DatasetFormatError, match="registered format"):
        data.load_dataset("junk")


def test_get_cache_dir_signature_of_011(tmp_path, monkeypatch):
    assert data.get_cache_dir() == tmp_path / "stablewm_home"
    assert data.get_cache_dir(tmp_path / "root") == tmp_path / "root"
    assert data.get_cache_dir(tmp_path / "root", sub_folder="datasets") == tmp_path / "root" / "datasets"
    assert (tmp_path / "root" / "datasets").is_dir()
    assert data.get_cache_dir(None, "datasets") == tmp_path / "stablewm_home" / "datasets"
    assert data.get_cache_dir(override_root=tmp_path / "o") == tmp_path / "o"
    (tmp_path / "file").write_text("")
    with pytest.raises(ConfigError, match="file"):
        data.get_cache_dir(tmp_path / "file")
    monkeypatch.setenv("STABLEWM_HOME", str(tmp_path / "file"))
    with pytest.raises(ConfigError, match="file"):
        data.get_cache_dir(sub_folder="datasets")
    with pytest.raises(ConfigError, match="sub_folder"):
        data.get_cache_dir(tmp_path, sub_folder="../out")


def test_column_normalizer(make_h5):
    ds = HDF5Dataset(make_h5((5, 7)), num_steps=2)
    state = ds.get_col_data(keys.STATE)
    norm = data.column_normalizer(ds, keys.STATE, "state_norm")
    item = pickle.loads(pickle.dumps(norm))(ds[3])
    assert item["state_norm"].dtype.is_floating_point and item["state_norm"].shape == item[keys.STATE].shape
    want = (item[keys.STATE].numpy() - state.mean(0)) / state.std(0)
    np.testing.assert_allclose(item["state_norm"].numpy(), want, rtol=1e-5)
    ds_t = HDF5Dataset(
        ds.path, num_steps=2, transform=data.column_normalizer(ds, keys.STATE, keys.STATE, method="percentile")
    )
    assert float(ds_t[0][keys.STATE].abs().max()) <= 1.0
    first = ds[0]
    assert data.column_normalizer(ds, keys.ACTION, "a", method="none")(first)["a"] is first[keys.ACTION]
    with pytest.raises(ValueError, match="zscore"):
        data.column_normalizer(ds, keys.STATE, "s", method="minmax")


def test_convert_copies_every_episode_to_another_format(tmp_path, make_h5):
    from stable_worldmodel.data import HDF5Dataset, convert, load_dataset

    src = make_h5((3, 4), image=(8, 8))
    out = convert(str(src), tmp_path / "copy", progress=False)  # HDF5 by default: .h5 added
    assert out == tmp_path / "copy.h5"
    a, b = HDF5Dataset(src), HDF5Dataset(out)
    assert b.lengths.tolist() == [3, 4]
    for col in a.stored_columns:
        np.testing.assert_array_equal(np.asarray(b.get_col_data(col)), np.asarray(a.get_col_data(col)), err_msg=col)
    folder = convert(str(src), tmp_path / "folder", dest_format="folder", progress=False)
    assert load_dataset(str(folder)).num_episodes == 2


def test_one_lookup_of_datasets_by_name(make_h5, tmp_path):
    """load_dataset, dataset_info, HDF5Dataset(name), the trainer and delete_dataset find a name
    in the same places, in the same order: ``<name>.h5``, ``<name>.lance``, ``<name>/``, then the same
    in ``datasets/``."""
    from stable_worldmodel.data.utils import convert, dataset_candidates, resolve_dataset, resolve_dataset_path
    from stable_worldmodel.errors import DatasetNotFoundError

    home = data.get_cache_dir()
    source = make_h5((3, 4), name="src")
    assert [p.relative_to(home).as_posix() for p in dataset_candidates("x")] == [
        "x.h5",
        "x.lance",
        "x",
        "datasets/x.h5",
        "datasets/x.lance",
        "datasets/x",
    ]
    sub = data.get_cache_dir(sub_folder="datasets")
    convert(source, sub / "x", dest_format="folder", progress=False)
    for found in (resolve_dataset("x"), data.load_dataset("x").path, resolve_dataset(data.dataset_info("x")["path"])):
        assert found == sub / "x"
    (sub / "x.h5").write_bytes(source.read_bytes())  # datasets/x.h5 comes before datasets/x/
    assert resolve_dataset("x") == resolve_dataset_path("x") == data.load_dataset("x").path == sub / "x.h5"
    (home / "x.h5").write_bytes(source.read_bytes())  # and the cache root before datasets/
    assert resolve_dataset("x") == resolve_dataset_path("x") == HDF5Dataset("x").path == home / "x.h5"
    assert data.delete_dataset("x") == home / "x.h5" and data.delete_dataset("x") == sub / "x.h5"
    assert data.delete_dataset("x") == sub / "x" and not (sub / "x").exists()
    for call in (lambda: data.load_dataset("x"), lambda: data.dataset_info("x"), lambda: resolve_dataset("x")):
        with pytest.raises(
            DatasetNotFoundError,
            match=r"looked for x\.h5, x\.lance, x, datasets/x\.h5, datasets/x\.lance, datasets/x\)",
        ) as err:
            call()
        assert isinstance(err.value, FileNotFoundError) and isinstance(err.value, ValueError)  # 0.1.1 and 0.0.3

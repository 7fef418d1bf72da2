"""Folder, image and video datasets in the released (0.0.3) on-disk layout, and the format registry."""

from __future__ import annotations

import json
import sys
import types

import numpy as np
import pytest

from stable_worldmodel import data, keys
from stable_worldmodel.data import FolderDataset, FolderWriter, HDF5Dataset, ImageDataset, VideoDataset, VideoWriter
from stable_worldmodel.errors import ConfigError, DatasetFormatError


def episode(ep: int, length: int, image=(16, 16), key=keys.PIXELS) -> dict[str, np.ndarray]:
    frames = np.zeros((length, *image, 3), np.uint8)
    frames[..., 0] = (40 * np.arange(length) + 10 * ep)[:, None, None]
    frames[..., 2] = 200
    return {
        key: frames,
        keys.ACTION: np.stack([np.arange(length), np.full(length, ep)], 1).astype(np.float32),
        keys.STATE: np.stack([np.full(length, ep), np.arange(length)], 1).astype(np.float64),
    }


def write_released_by_hand(root, lengths=(3, 4), suffix=".jpeg"):
    """What 0.0.3 reads: ep_len.npz, ep_offset.npz, <col>.npz, <key>/ep_{e}_step_{s}<suffix>."""
    from PIL import Image

    root.mkdir(parents=True)
    eps = [episode(e, n) for e, n in enumerate(lengths)]
    np.savez(root / "ep_len.npz", np.asarray(lengths, np.int32))
    np.savez(root / "ep_offset.npz", np.concatenate([[0], np.cumsum(lengths)[:-1]]).astype(np.int64))
    for col in (keys.ACTION, keys.STATE):
        np.savez(root / f"{col}.npz", np.concatenate([ep[col] for ep in eps]))
    (root / keys.PIXELS).mkdir()
    for e, ep in enumerate(eps):
        for s, frame in enumerate(ep[keys.PIXELS]):
            Image.fromarray(frame).save(root / keys.PIXELS / f"ep_{e}_step_{s}{suffix}", quality=95)
    return eps


def test_folder_writer_writes_the_released_layout(tmp_path):
    with FolderWriter(tmp_path / "ds") as writer:
        writer.write_episodes([episode(0, 3), episode(1, 2)])
    root = tmp_path / "ds"
    assert sorted(p.name for p in root.iterdir()) == [
        "action.npz",
        "ep_len.npz",
        "ep_offset.npz",
        "pixels",
        "state.npz",
    ]
    assert sorted(p.name for p in (root / "pixels").iterdir()) == [
        f"ep_{e}_step_{s}.jpeg" for e, n in ((0, 3), (1, 2)) for s in range(n)
    ]
    assert np.load(root / "ep_len.npz")["arr_0"].tolist() == [3, 2]
    assert np.load(root / "ep_offset.npz")["arr_0"].tolist() == [0, 3]
    assert np.load(root / "state.npz")["arr_0"].shape == (5, 2)
    with FolderWriter(root) as writer:  # append
        writer.write_episode(episode(2, 4))
    assert np.load(root / "ep_len.npz")["arr_0"].tolist() == [3, 2, 4]
    with pytest.raises(FileExistsError):
        FolderWriter(root, mode="error")
    with pytest.raises(DatasetFormatError, match="columns"):
        with FolderWriter(root) as writer:
            writer.write_episode({keys.ACTION: np.zeros((2, 2), np.float32)})


@pytest.mark.parametrize("suffix", [".jpeg", ".jpg"])
def test_files_in_the_003_layout_read_as_they_are(tmp_path, suffix):
    eps = write_released_by_hand(tmp_path / "handmade", suffix=suffix)
    ds = ImageDataset("handmade", ["pixels"], cache_dir=tmp_path, num_steps=2)  # 0.0.3's positional form
    assert ds.column_names == [keys.ACTION, keys.PIXELS, keys.STATE] and ds.folder_keys == [keys.PIXELS]
    assert len(ds) == 2 + 3 and ds.clip_indices[2] == (1, 0)
    item = ds[2]
    assert item[keys.PIXELS].shape == (2, 3, 16, 16)
    want = eps[1][keys.PIXELS][:2].transpose(0, 3, 1, 2).astype(int)
    assert np.abs(item[keys.PIXELS].numpy().astype(int) - want).max() <= 8  # JPEG
    np.testing.assert_array_equal(item[keys.STATE].numpy(), eps[1][keys.STATE][:2])
    folder = FolderDataset("handmade", 1, 1, None, None, [keys.PIXELS], tmp_path)  # every 0.0.3 argument positionally
    assert folder.get_col_data(keys.ACTION).shape == (7, 2) and folder.row_shape(keys.PIXELS) == (16, 16, 3)


def test_video_dataset_reads_one_mp4_per_episode(tmp_path):
    pytest.importorskip("av")
    with VideoWriter(tmp_path / "vid", fps=10) as writer:
        writer.write_episodes([episode(e, n, image=(15, 16), key="video") for e, n in enumerate((3, 4))])
    root = tmp_path / "vid"
    assert sorted(p.name for p in (root / "video").glob("*.mp4")) == ["ep_0.mp4", "ep_1.mp4"]
    assert sorted(p.name for p in root.iterdir()) == ["action.npz", "ep_len.npz", "ep_offset.npz", "state.npz", "video"]
    ds = VideoDataset("vid", ["video"], cache_dir=tmp_path, num_steps=2, frameskip=2)  # 0.0.3's positional form
    assert ds.column_names == [keys.ACTION, keys.STATE, "video"] and len(ds) == 1
    frames = ds[0]["video"]
    assert frames.shape == (2, 3, 15, 16)  # the odd height padded for H.264 is cropped back
    want = episode(1, 4, image=(15, 16))[keys.PIXELS][::2].transpose(0, 3, 1, 2).astype(int)
    assert np.abs(frames.numpy().astype(int) - want).mean() < 6
    assert ds[0][keys.ACTION].shape == (2, 4)
    with pytest.raises(DatasetFormatError, match="FolderDataset"):
        write_released_by_hand(tmp_path / "images")
        VideoDataset(tmp_path / "images")


def test_video_dataset_uses_decord_when_asked(tmp_path, monkeypatch):
    pytest.importorskip("av")
    with VideoWriter(tmp_path / "vid") as writer:
        writer.write_episodes([episode(0, 3, image=(16, 16), key="video")])
    calls = []

    class Reader:
        def __init__(self, path, num_threads=1):
            calls.append(path)

        def __len__(self):
            return 3

        def get_batch(self, idx):
            return types.SimpleNamespace(asnumpy=lambda: np.full((len(idx), 16, 16, 3), 7, np.uint8))

    monkeypatch.setitem(sys.modules, "decord", types.SimpleNamespace(VideoReader=Reader))
    ds = VideoDataset(tmp_path / "vid", decoder="decord")
    assert ds[1]["video"].unique().tolist() == [7] and calls[0].endswith("ep_0.mp4")
    with pytest.raises(ConfigError, match="decoder"):
        VideoDataset(tmp_path / "vid", decoder="cv2")


def test_our_earlier_meta_layout_is_still_readable(tmp_path):
    from PIL import Image

    root = tmp_path / "old"
    (root / keys.PIXELS).mkdir(parents=True)
    eps = [episode(0, 2), episode(1, 3)]
    numeric = {c: np.concatenate([ep[c] for ep in eps]) for c in (keys.ACTION, keys.STATE)}
    np.savez(root / "columns.npz", **numeric, ep_len=np.array([2, 3]), ep_offset=np.array([0, 2]))
    (root / "meta.json").write_text(json.dumps({"format": "folder", "images": {keys.PIXELS: [16, 16, 3]}}))
    for row, frame in enumerate(np.concatenate([ep[keys.PIXELS] for ep in eps])):
        Image.fromarray(frame).save(root / keys.PIXELS / f"{row:09d}.jpg", quality=95)
    assert data.detect_format(root).name == "folder-meta"
    ds = data.load_dataset(root, num_steps=2)
    assert isinstance(ds, FolderDataset) and len(ds) == 3 and ds[2][keys.PIXELS].shape == (2, 3, 16, 16)


def test_registry_detects_every_layout_and_dataset_info_uses_it(make_h5, tmp_path):
    home = data.get_cache_dir()
    make_h5((3, 4), name="h")
    (home / "h.h5").write_bytes((tmp_path / "h.h5").read_bytes())
    write_released_by_hand(home / "imgs")
    assert data.list_formats()[:3] == ["hdf5", "video", "folder"]
    assert {data.detect_format(home / n).name for n in ("h.h5", "imgs")} == {"hdf5", "folder"}
    assert data.detect_format(tmp_path) is None
    assert data.list_datasets() == ["h", "imgs"]
    info = data.dataset_info("imgs")
    assert info["format"] == "folder" and info["num_episodes"] == 2 and info["num_steps"] == 7
    assert info["obs_shape"] == (16, 16, 3) and info["action_shape"] == (2,) and info["name"] == "imgs"
    assert data.dataset_info("h")["format"] == "hdf5"

    @data.register_format
    class Marker(data.Format):  # a user format: one class, no change anywhere else
        name = "marker-test"

        @classmethod
        def detect(cls, path):
            return (path / "MARKER").is_file()

        @classmethod
        def summary(cls, path):
            return {"format": cls.name, "path": str(path), "columns": ["x"], "num_episodes": 0, "num_steps": 0}

    try:
        (home / "mine").mkdir()
        (home / "mine" / "MARKER").write_text("")
        assert "mine" in data.list_datasets() and data.dataset_info("mine")["format"] == "marker-test"
        with pytest.raises(ConfigError, match="already registered"):
            data.register_format(type("Other", (data.Format,), {"name": "marker-test"}))
    finally:
        data.FORMATS.pop("marker-test")
    with pytest.raises(ValueError, match="Did you mean .*'folder'"):
        data.get_format("foldr")


def test_swm_show_dataset_on_a_folder_dataset(swm):
    write_released_by_hand(data.get_cache_dir() / "imgs")
    result = swm("show", "dataset", "imgs")
    assert result.exit_code == 0, result.output
    assert "folder" in result.output and "pixels" in result.output


def test_conversion_from_hdf5_round_trips(make_h5, tmp_path):
    h5 = HDF5Dataset(make_h5((4, 5), image=(16, 16)), num_steps=2)
    data.write_folder_dataset(h5, tmp_path / "f")
    ds = data.load_dataset(tmp_path / "f", num_steps=2)
    assert sorted(ds.column_names) == sorted(h5.column_names) and len(ds) == len(h5)
    np.testing.assert_array_equal(ds[4][keys.STATE].numpy(), h5[4][keys.STATE].numpy())
    with pytest.raises(FileExistsError):
        data.write_folder_dataset(h5, tmp_path / "f")


def test_video_writer_takes_011_positional_fps_and_codec(tmp_path):
    """0.1.1: ``VideoWriter(path, fps=25, codec="libx264", *, mode="append")``."""
    av = pytest.importorskip("av")
    with VideoWriter(tmp_path / "v", 12, "mpeg4") as writer:
        writer.write_episodes([episode(0, 3, image=(16, 16), key="video")])
    with av.open(str(tmp_path / "v" / "video" / "ep_0.mp4")) as container:
        stream = container.streams.video[0]
        assert stream.codec_context.name == "mpeg4" and float(stream.average_rate) == 12
    assert VideoWriter(tmp_path / "w").fps == 25  # 0.1.1's default
    with pytest.raises(ConfigError, match="codec"):
        VideoWriter(tmp_path / "x", 10, "")

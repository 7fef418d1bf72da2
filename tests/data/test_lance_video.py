"""The ``lance_video`` format (upstream main's): a Lance frames table beside a videos table holding
one MP4 blob per (episode, image column). Written and read with pylance and PyAV; H.264 is lossy,
so frames are compared with a tolerance (each frame differs from its neighbours by far more)."""

from __future__ import annotations

import pickle

import numpy as np
import pytest
import torch

from stable_worldmodel import data, keys
from stable_worldmodel.errors import ConfigError, DatasetFormatError, DatasetNotFoundError, UnknownNameError

pytest.importorskip("lance")
pytest.importorskip("av")
from stable_worldmodel.data.lance_video import LanceVideoDataset, LanceVideoWriter  # noqa: E402 - after the skips

LENGTHS = (5, 7, 8)
ODD = "cam.side"  # an odd-sized image column, with a dotted name
TOLERANCE = 6  # mean absolute error per frame, in grey levels


def episode(e: int, n: int) -> dict[str, np.ndarray]:
    """Smooth frames (what video codecs keep well) that change a lot from step to step."""
    t = np.arange(n)[:, None, None]
    yy, xx = np.mgrid[0:16, 0:16]
    pixels = np.stack([yy * 4 + t * 25 + e * 10, xx * 4 + 40 + t * 12, np.full((n, 16, 16), 80 + 40 * e)], -1)
    yy, xx = np.mgrid[0:15, 0:17]
    side = np.stack([xx * 6 + t * 20, np.full((n, 15, 17), 200 - 50 * e), yy * 6 + 30 + t * 15], -1)
    return {
        keys.PIXELS: pixels.clip(0, 255).astype(np.uint8),
        ODD: side.clip(0, 255).astype(np.uint8),
        keys.ACTION: np.arange(n * 2, dtype=np.float32).reshape(n, 2) + 100 * e,
        keys.STATE: np.arange(n * 3, dtype=np.float64).reshape(n, 3) - e,
    }


def write(path, lengths=LENGTHS, start=0, **kwargs):
    with LanceVideoWriter(path, **kwargs) as w:
        w.write_episode(episode(start, lengths[0]))
        w.write_episodes([episode(e, n) for e, n in enumerate(lengths[1:], start=start + 1)])
    return path


def close_to(got, want) -> bool:
    got, want = np.asarray(got).astype(int), np.asarray(want).astype(int)
    return got.shape == want.shape and all(np.abs(g - w).mean() < TOLERANCE for g, w in zip(got, want, strict=True))


def test_round_trip_detects_the_format_and_reads_frames_back(tmp_path):
    path = write(tmp_path / "x.lance")
    assert data.detect_format(path).name == "lance_video" and data.detect_format(tmp_path).name == "lance_video"
    ds = data.load_dataset(path, num_steps=2)
    assert isinstance(ds, LanceVideoDataset) and ds.lengths.tolist() == list(LENGTHS) and len(ds) == 4 + 6 + 7
    assert set(ds.column_names) == set(episode(0, 1)) and ds.video_keys == [keys.PIXELS, ODD]
    assert ds.column_shape(ODD) == ((15, 17, 3), np.dtype(np.uint8))
    for col in (keys.ACTION, keys.STATE):  # exactly as the lance format stores them
        want = np.concatenate([episode(e, n)[col] for e, n in enumerate(LENGTHS)])
        got = ds.get_col_data(col)
        assert got.dtype == want.dtype and np.array_equal(got, want)
    for col in (keys.PIXELS, ODD):
        got = ds.get_col_data(col)
        assert got.dtype == np.uint8 and close_to(
            got, np.concatenate([episode(e, n)[col] for e, n in enumerate(LENGTHS)])
        )
    item = ds[4]  # the first window of episode 1
    assert item[keys.PIXELS].shape == (2, 3, 16, 16) and item[ODD].shape == (2, 3, 15, 17)
    assert close_to(item[ODD].permute(0, 2, 3, 1), episode(1, 2)[ODD]) and item[keys.STATE][0, 0] == -1
    assert data.load_dataset(tmp_path, format="lance_video").lengths.tolist() == list(LENGTHS)  # the folder


def test_windows_with_frameskip_decode_the_right_frames(tmp_path):
    ds = LanceVideoDataset(write(tmp_path / "x.lance"), num_steps=2, frameskip=3, decoder_cache_size=1)
    assert len(ds) == 0 + 2 + 3
    eps = {e: episode(e, n) for e, n in enumerate(LENGTHS)}
    for e in eps.values():  # the tolerance tells a frame from its neighbours
        assert not any(close_to(e[c][1:], e[c][:-1]) or close_to(e[c][:1], e[c][1:2]) for c in (keys.PIXELS, ODD))
    windows = [ds.locate(i) for i in range(len(ds))]
    for i, (e, s) in enumerate(windows):  # item by item, the decoders of two columns evicting each other
        item = ds[i]
        assert close_to(item[keys.PIXELS].permute(0, 2, 3, 1), eps[e][keys.PIXELS][s : s + 6 : 3])
        assert (
            item[keys.ACTION].shape == (2, 6) and item[keys.ACTION][0, :2].tolist() == eps[e][keys.ACTION][s].tolist()
        )
    batch = ds.__getitems__([4, 0, 2, 4])  # out of order, repeated, two episodes
    for item, i in zip(batch, [4, 0, 2, 4], strict=True):
        e, s = windows[i]
        assert close_to(item[ODD].permute(0, 2, 3, 1), eps[e][ODD][s : s + 6 : 3])
    # the same frames read one by one (item) and as a batch
    assert torch.equal(batch[0][keys.PIXELS], ds[4][keys.PIXELS]) and torch.equal(batch[3][ODD], batch[0][ODD])


def test_a_dataloader_and_a_pickled_copy_read_it(tmp_path):
    ds = data.load_dataset(write(tmp_path / "x.lance"), num_steps=2, keys_to_load=[keys.PIXELS, keys.ACTION])
    batches = list(torch.utils.data.DataLoader(ds, batch_size=8))
    assert [len(b[keys.ACTION]) for b in batches] == [8, 8, 1] and set(batches[0]) == {keys.PIXELS, keys.ACTION}
    assert batches[0][keys.PIXELS].shape == (8, 2, 3, 16, 16)
    copy = pickle.loads(pickle.dumps(ds))  # what a worker gets: it opens the tables and decoders itself
    assert copy._videos_ds is None and not copy._decoders
    assert torch.equal(copy[16][keys.PIXELS], batches[2][keys.PIXELS][0])
    cached = LanceVideoDataset(tmp_path / "x.lance", keys_to_cache=[keys.PIXELS, keys.STATE], video_keys=[keys.PIXELS])
    assert cached.column_names == [keys.ACTION, keys.STATE, keys.PIXELS] and keys.PIXELS in cached._cache
    assert np.array_equal(cached.get_col_data(keys.PIXELS), ds.get_col_data(keys.PIXELS))


def test_write_modes(tmp_path):
    path = write(tmp_path / "m.lance")
    with pytest.raises(FileExistsError, match="mode='error'.*exists"):
        LanceVideoWriter(path, mode="error")
    write(path, lengths=(2, 3), start=5)  # append, the default: episode numbers continue
    ds = LanceVideoDataset(path)
    assert ds.lengths.tolist() == [*LENGTHS, 2, 3]
    assert close_to(ds.load_episode(4)[ODD].permute(0, 2, 3, 1), episode(6, 3)[ODD])
    import lance

    assert lance.dataset(str(tmp_path / "m_videos.lance")).to_table(columns=["episode_idx"]).column(0).to_pylist() == [
        e for e in range(5) for _ in range(2)
    ]
    write(path, lengths=(6,), mode="overwrite")
    assert LanceVideoDataset(path).lengths.tolist() == [6]
    with pytest.raises(ConfigError, match="mode to be one of"):
        LanceVideoWriter(path, mode="replace")
    with pytest.raises(ConfigError, match="fps > 0"):
        LanceVideoWriter(path, fps=0)
    with LanceVideoWriter(path) as w:  # a batch the frames table refuses leaves no videos behind
        with pytest.raises(DatasetFormatError, match=r"missing=\['state'\]"):
            w.write_episode({k: v for k, v in episode(1, 3).items() if k != keys.STATE})
        with pytest.raises(DatasetFormatError, match="image columns"):
            w.write_episode({k: v for k, v in episode(1, 3).items() if k != ODD})
        w.write_episode(episode(1, 3))
    assert lance.dataset(str(tmp_path / "m_videos.lance")).to_table(columns=["episode_idx"]).column(0).to_pylist() == [
        0,
        0,
        1,
        1,
    ]
    assert LanceVideoDataset(path).lengths.tolist() == [6, 3]


def test_convert_from_hdf5(tmp_path):
    from stable_worldmodel.data.writer import HDF5Writer

    with HDF5Writer(tmp_path / "src.h5") as w:
        for e, n in enumerate(LENGTHS):
            w.write_episode(episode(e, n))
    out = data.convert(tmp_path / "src.h5", tmp_path / "dest.lance", dest_format="lance_video", progress=False)
    ds = data.load_dataset(out)
    assert isinstance(ds, LanceVideoDataset) and ds.lengths.tolist() == list(LENGTHS)
    assert close_to(ds.get_col_data(ODD), data.load_dataset(tmp_path / "src.h5").get_col_data(ODD))
    # a folder (upstream's writer names the table after it)
    folder = data.convert(tmp_path / "src.h5", tmp_path / "vids", dest_format="lance_video", progress=False)
    assert (folder / "vids.lance").is_dir() and (folder / "vids_videos.lance").is_dir()
    assert data.load_dataset(folder).num_episodes == 3


def test_the_layout_on_disk(tmp_path):
    import lance
    import pyarrow as pa

    write(tmp_path / "x.lance")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["x.lance", "x_videos.lance"]
    frames = lance.dataset(str(tmp_path / "x.lance"))
    assert frames.schema.names == ["episode_idx", "step_idx", keys.ACTION, keys.STATE]
    assert frames.schema.field("episode_idx").type == pa.int32() and frames.schema.field("step_idx").type == pa.int32()
    videos = lance.dataset(str(tmp_path / "x_videos.lance"))
    assert videos.schema.names == ["episode_idx", "video_key", "video_bytes"]
    assert (
        videos.schema.field("episode_idx").type == pa.int32() and videos.schema.field("video_key").type == pa.string()
    )
    assert videos.schema.field("video_bytes").type == pa.large_binary()
    assert videos.schema.field("video_bytes").metadata == {b"lance-encoding:blob": b"true"}
    rows = videos.to_table(columns=["episode_idx", "video_key"]).to_pylist()
    assert [(r["episode_idx"], r["video_key"]) for r in rows] == [
        (e, k) for e in range(3) for k in ("pixels", "cam_side")
    ]
    blob = videos.take_blobs(blob_column="video_bytes", indices=[3])[0]
    mp4 = blob.readall()
    blob.close()
    assert mp4[4:8] == b"ftyp"
    import io

    import av

    with av.open(io.BytesIO(mp4)) as container:  # episode 1's cam.side: padded to even, 7 frames at 10 fps
        stream = container.streams.video[0]
        assert (stream.codec_context.name, stream.codec_context.pix_fmt) == ("h264", "yuv420p")
        assert (stream.height, stream.width, int(stream.average_rate)) == (16, 18, 10)
        assert len(list(container.decode(stream))) == 7


def test_missing_videos_table_and_other_bad_input_are_typed_errors(tmp_path):
    import shutil

    from stable_worldmodel.data.lance import LanceWriter

    path = write(tmp_path / "x.lance")
    videos = tmp_path / "x_videos.lance"
    assert data.detect_format(videos) is None  # a videos table is a sidecar, not a dataset of its own
    with pytest.raises(DatasetNotFoundError, match="requires the videos table .*x_videos_videos.lance.*frames table"):
        LanceVideoDataset(videos)
    shutil.rmtree(videos)
    assert data.detect_format(path).name == "lance"
    with pytest.raises(DatasetNotFoundError, match="requires the videos table x_videos.lance beside x.lance"):
        LanceVideoDataset(path)
    with pytest.raises(DatasetNotFoundError, match="x_videos.lance"):
        data.load_dataset(path, format="lance_video")
    with pytest.raises(DatasetFormatError, match="both tables"):
        LanceVideoWriter(path)
    with LanceWriter(tmp_path / "plain.lance") as w:  # the plain lance format still detects its own
        w.write_episode(episode(0, 2))
    assert data.detect_format(tmp_path / "plain.lance").name == "lance"
    write(tmp_path / "y.lance")
    with pytest.raises(UnknownNameError, match="goal"):
        LanceVideoDataset(tmp_path / "y.lance", video_keys=["goal"])
    with pytest.raises(DatasetFormatError, match="besides the image columns"):
        LanceVideoWriter(tmp_path / "z.lance").write_episode({keys.PIXELS: episode(0, 2)[keys.PIXELS]})


def test_grey_and_rgba_columns(tmp_path):
    """Grey frames go through the video as RGB and come back with one channel; H.264 has no alpha,
    so 4-channel frames stay in the frames table (PNG, lossless), as the lance format stores them."""
    import lance

    n = 6
    grey = np.broadcast_to((np.arange(n) * 30 + 20).astype(np.uint8)[:, None, None, None], (n, 9, 7, 1)).copy()
    rgba = np.random.default_rng(0).integers(0, 256, (n, 4, 4, 4), dtype=np.uint8)
    with LanceVideoWriter(tmp_path / "g.lance") as w:
        w.write_episode({"grey": grey, "rgba": rgba, keys.ACTION: np.zeros((n, 1), np.float32)})
    ds = data.load_dataset(tmp_path / "g.lance", num_steps=2, frameskip=2)
    assert ds.video_keys == ["grey"] and ds.column_shape("grey") == ((9, 7, 1), np.dtype(np.uint8))
    assert close_to(ds.get_col_data("grey"), grey) and np.array_equal(ds.get_col_data("rgba"), rgba)
    assert ds[1]["grey"].shape == (2, 1, 9, 7) and ds[1]["rgba"].shape == (2, 4, 4, 4)
    assert "rgba" in lance.dataset(str(tmp_path / "g.lance")).schema.names


def test_videos_a_crash_left_behind_are_ignored_then_removed(tmp_path, caplog):
    """The videos of a batch are committed before its rows: a crash in between leaves videos of
    episodes the frames table does not have. The reader ignores them; the next writer removes them."""
    import lance
    import pyarrow as pa

    path = write(tmp_path / "x.lance", lengths=(3, 4))
    where = str(tmp_path / "x_videos.lance")
    videos = lance.dataset(where)
    blobs = [b.readall() for b in videos.take_blobs(blob_column="video_bytes", indices=[0, 1])]
    orphans = pa.table(
        [pa.array([2, 2], pa.int32()), pa.array(["pixels", "cam_side"]), pa.array(blobs, pa.large_binary())],
        schema=videos.schema,
    )
    lance.write_dataset(orphans, where, schema=videos.schema, mode="append")
    assert LanceVideoDataset(path).lengths.tolist() == [3, 4]
    with caplog.at_level("WARNING"), LanceVideoWriter(path) as w:
        w.write_episode(episode(5, 2))
    assert "uncommitted episodes" in caplog.text
    assert lance.dataset(where).to_table(columns=["episode_idx"]).column(0).to_pylist() == [0, 0, 1, 1, 2, 2]
    ds = LanceVideoDataset(path)
    assert ds.lengths.tolist() == [3, 4, 2]
    assert close_to(ds.load_episode(2)[keys.PIXELS].permute(0, 2, 3, 1), episode(5, 2)[keys.PIXELS])

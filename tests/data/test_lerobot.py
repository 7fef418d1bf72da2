"""The read-only ``lerobot`` format (upstream 0.1.1's ``lerobot://<repo_id>``), on tiny LeRobot v2.1
and v3.0 datasets written here: parquet rows, H.264 videos (lossy: frames compared with a tolerance)."""

from __future__ import annotations

import json
import pickle
from pathlib import Path

import numpy as np
import pytest

pa = pytest.importorskip("pyarrow")
pq = pytest.importorskip("pyarrow.parquet")
av = pytest.importorskip("av")
torch = pytest.importorskip("torch")

from stable_worldmodel.data import load_dataset  # noqa: E402
from stable_worldmodel.data.format import detect_format, get_format  # noqa: E402
from stable_worldmodel.data.lerobot import LeRobotAdapter  # noqa: E402
from stable_worldmodel.errors import (  # noqa: E402
    ConfigError,
    DatasetFormatError,
    DatasetNotFoundError,
    UnknownNameError,
)

FPS = 10
SIZE = 16
LENGTHS = (5, 7, 6)
CAMERA = "observation.images.top"
WRIST = "observation.images.wrist"
TOLERANCE = 12  # H.264 of flat colours: a few grey levels off


def frame(ep: int, step: int, shift: int = 0) -> np.ndarray:
    """A flat colour that encodes (episode, step)."""
    value = 30 + 25 * step + 8 * ep + shift
    out = np.empty((SIZE, SIZE, 3), np.uint8)
    out[...] = (value, 255 - value, 60 + 40 * ep)
    return out


def state(ep: int, steps: np.ndarray) -> np.ndarray:
    return np.stack([np.full(len(steps), ep), steps, ep * 100 + steps], axis=1).astype(np.float32)


def action(ep: int, steps: np.ndarray) -> np.ndarray:
    return np.stack([ep * 10 + steps, -steps], axis=1).astype(np.float32)


def write_mp4(path: Path, frames: list[np.ndarray]) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    with av.open(str(path), "w") as container:
        stream = container.add_stream("libx264", rate=FPS)
        stream.width = stream.height = SIZE
        stream.pix_fmt = "yuv420p"
        stream.options = {"crf": "1", "g": "4"}  # small GOPs: seeking lands inside the video
        for image in frames:
            container.mux(stream.encode(av.VideoFrame.from_ndarray(image, format="rgb24")))
        container.mux(stream.encode())


def features(cameras: dict[str, str]) -> dict:
    out = {
        name: {"dtype": kind, "shape": [SIZE, SIZE, 3], "names": ["height", "width", "channels"]}
        for name, kind in cameras.items()
    }
    out.update(
        {
            "observation.state": {"dtype": "float32", "shape": [3], "names": ["a", "b", "c"]},
            "action": {"dtype": "float32", "shape": [2], "names": ["x", "y"]},
            "next.reward": {"dtype": "float32", "shape": [1], "names": None},
            "timestamp": {"dtype": "float32", "shape": [1], "names": None},
            "frame_index": {"dtype": "int64", "shape": [1], "names": None},
            "episode_index": {"dtype": "int64", "shape": [1], "names": None},
            "index": {"dtype": "int64", "shape": [1], "names": None},
            "task_index": {"dtype": "int64", "shape": [1], "names": None},
        }
    )
    return out


def rows(ep: int, length: int, first: int, cameras: dict[str, str], fixed: bool) -> pa.Table:
    steps = np.arange(length)
    vector = (lambda a: pa.FixedSizeListArray.from_arrays(pa.array(a.ravel()), a.shape[1])) if fixed else pa.array
    cols = {
        "observation.state": vector(state(ep, steps)) if fixed else pa.array(list(state(ep, steps))),
        "action": vector(action(ep, steps)) if fixed else pa.array(list(action(ep, steps))),
        "next.reward": pa.array((steps == length - 1).astype(np.float32)),
        "timestamp": pa.array((steps / FPS).astype(np.float32)),
        "frame_index": pa.array(steps.astype(np.int64)),
        "episode_index": pa.array(np.full(length, ep, np.int64)),
        "index": pa.array(first + steps.astype(np.int64)),
        "task_index": pa.array(np.full(length, ep % 2, np.int64)),
    }
    for name, kind in cameras.items():
        if kind == "image":
            import io

            from PIL import Image

            def png(image: np.ndarray) -> bytes:
                buffer = io.BytesIO()
                Image.fromarray(image).save(buffer, format="PNG")
                return buffer.getvalue()

            cells = [{"bytes": png(frame(ep, s, shift=3)), "path": f"frame_{s:06d}.png"} for s in steps]
            cols[name] = pa.array(cells, pa.struct([("bytes", pa.binary()), ("path", pa.string())]))
    return pa.table(cols)


def info(version: str, cameras: dict[str, str], lengths) -> dict:
    return {
        "codebase_version": version,
        "robot_type": "toy",
        "total_episodes": len(lengths),
        "total_frames": int(sum(lengths)),
        "total_tasks": 2,
        "chunks_size": 1000,
        "fps": FPS,
        "splits": {"train": f"0:{len(lengths)}"},
        "features": features(cameras),
    }


def write_v2(root: Path, lengths=LENGTHS, cameras=None) -> Path:
    """A LeRobot v2.1 dataset: one parquet file and one MP4 per episode."""
    cameras = {CAMERA: "video"} if cameras is None else cameras
    meta = info("v2.1", cameras, lengths)
    meta["data_path"] = "data/chunk-{episode_chunk:03d}/episode_{episode_index:06d}.parquet"
    meta["video_path"] = "videos/chunk-{episode_chunk:03d}/{video_key}/episode_{episode_index:06d}.mp4"
    (root / "meta").mkdir(parents=True)
    (root / "meta" / "info.json").write_text(json.dumps(meta))
    episodes = [{"episode_index": e, "tasks": [f"task {e % 2}"], "length": n} for e, n in enumerate(lengths)]
    (root / "meta" / "episodes.jsonl").write_text("".join(json.dumps(e) + "\n" for e in episodes))
    tasks = [{"task_index": t, "task": f"task {t}"} for t in range(2)]
    (root / "meta" / "tasks.jsonl").write_text("".join(json.dumps(t) + "\n" for t in tasks))
    first = 0
    for ep, n in enumerate(lengths):
        path = root / f"data/chunk-000/episode_{ep:06d}.parquet"
        path.parent.mkdir(parents=True, exist_ok=True)
        pq.write_table(rows(ep, n, first, cameras, fixed=False), path)
        for name, kind in cameras.items():
            if kind == "video":
                shift = 0 if name == CAMERA else 40
                write_mp4(
                    root / f"videos/chunk-000/{name}/episode_{ep:06d}.mp4", [frame(ep, s, shift) for s in range(n)]
                )
        first += n
    return root


def write_v3(root: Path, lengths=LENGTHS, files=((0, 1), (2,))) -> Path:
    """A LeRobot v3.0 dataset: episodes grouped in data files and videos (``files``: episodes per file)."""
    cameras = {CAMERA: "video"}
    (root / "meta").mkdir(parents=True)
    (root / "meta" / "info.json").write_text(json.dumps(info("v3.0", cameras, lengths)))
    pq.write_table(
        pa.table({"task_index": [0, 1], "__index_level_0__": ["task 0", "task 1"]}), root / "meta" / "tasks.parquet"
    )
    episodes: dict[str, list] = {
        k: []
        for k in (
            "episode_index",
            "tasks",
            "length",
            "data/chunk_index",
            "data/file_index",
            "dataset_from_index",
            "dataset_to_index",
            f"videos/{CAMERA}/chunk_index",
            f"videos/{CAMERA}/file_index",
            f"videos/{CAMERA}/from_timestamp",
            f"videos/{CAMERA}/to_timestamp",
            "stats/action/mean",
        )
    }
    first = 0
    for file_index, group in enumerate(files):
        tables, images, clock = [], [], 0.0
        for ep in group:
            n = lengths[ep]
            tables.append(rows(ep, n, first, cameras, fixed=True))
            images += [frame(ep, s) for s in range(n)]
            values = {
                "episode_index": ep,
                "tasks": [f"task {ep % 2}"],
                "length": n,
                "data/chunk_index": 0,
                "data/file_index": file_index,
                "dataset_from_index": first,
                "dataset_to_index": first + n,
                f"videos/{CAMERA}/chunk_index": 0,
                f"videos/{CAMERA}/file_index": file_index,
                f"videos/{CAMERA}/from_timestamp": clock,
                f"videos/{CAMERA}/to_timestamp": clock + n / FPS,
                "stats/action/mean": [0.0, 0.0],
            }
            for k, v in values.items():
                episodes[k].append(v)
            first, clock = first + n, clock + n / FPS
        path = root / f"data/chunk-000/file-{file_index:03d}.parquet"
        path.parent.mkdir(parents=True, exist_ok=True)
        pq.write_table(pa.concat_tables(tables), path)
        write_mp4(root / f"videos/{CAMERA}/chunk-000/file-{file_index:03d}.mp4", images)
    path = root / "meta/episodes/chunk-000/file-000.parquet"
    path.parent.mkdir(parents=True)
    pq.write_table(pa.table(episodes), path)
    return root


@pytest.fixture(scope="module")
def v2(tmp_path_factory) -> Path:
    return write_v2(tmp_path_factory.mktemp("lerobot") / "v2")


@pytest.fixture(scope="module")
def v3(tmp_path_factory) -> Path:
    return write_v3(tmp_path_factory.mktemp("lerobot") / "v3")


def close_to(pixels, expected: np.ndarray) -> bool:
    got = np.asarray(pixels, np.int64)
    return bool(np.abs(got - expected.astype(np.int64)).max() <= TOLERANCE)


def chw(frames: list[np.ndarray]) -> np.ndarray:
    return np.stack(frames).transpose(0, 3, 1, 2)


# -- loading ---------------------------------------------------------------------------------------
@pytest.mark.parametrize("layout", ["v2", "v3"])
def test_load_folder(layout, request):
    root = request.getfixturevalue(layout)
    assert detect_format(root) is get_format("lerobot")
    ds = load_dataset(root)
    assert isinstance(ds, LeRobotAdapter)
    assert ds.lengths.tolist() == list(LENGTHS) and ds.offsets.tolist() == [0, 5, 12]
    assert ds.column_names == ["pixels", "action", "proprio", "ep_idx", "step_idx"]  # upstream's defaults
    assert {"next.reward", "timestamp", "frame_index", "task"} <= set(ds.stored_columns)
    assert CAMERA not in ds.stored_columns and "observation.state" not in ds.stored_columns  # under their aliases
    assert len(ds) == sum(LENGTHS)
    item = ds[6]  # episode 1, step 1
    assert item["pixels"].shape == (1, 3, SIZE, SIZE) and item["pixels"].dtype == torch.uint8
    assert close_to(item["pixels"], chw([frame(1, 1)]))
    assert item["action"].tolist() == [[11.0, -1.0]] and item["action"].dtype == torch.float32
    assert item["proprio"].tolist() == [[1.0, 1.0, 101.0]]
    assert item["ep_idx"].tolist() == [1] and item["step_idx"].tolist() == [1]
    assert item["ep_idx"].dtype == torch.int64


@pytest.mark.parametrize("layout", ["v2", "v3"])
def test_windows_stay_in_episodes(layout, request):
    ds = load_dataset(request.getfixturevalue(layout), num_steps=2, frameskip=2)
    assert len(ds) == sum(n - 4 + 1 for n in LENGTHS)
    for i in range(len(ds)):
        ep, start = ds.locate(i)
        item = ds[i]
        assert item["ep_idx"].tolist() == [ep, ep]
        assert item["step_idx"].tolist() == [start, start + 2]
        assert item["pixels"].shape == (2, 3, SIZE, SIZE)
        assert close_to(item["pixels"], chw([frame(ep, start), frame(ep, start + 2)]))
        steps = np.arange(start, start + 4)
        assert item["action"].shape == (2, 4)  # (T, frameskip * A)
        np.testing.assert_array_equal(item["action"].numpy(), action(ep, steps).reshape(2, 4))
        np.testing.assert_array_equal(item["proprio"].numpy(), state(ep, steps[::2]))


def test_episodes_load_and_columns(v3):
    ds = LeRobotAdapter(root=v3, keys_to_load=["pixels", "next.reward", "task", "timestamp"])
    episode = ds.load_episode(2)
    assert episode["pixels"].shape == (6, 3, SIZE, SIZE)
    assert close_to(episode["pixels"], chw([frame(2, s) for s in range(6)]))  # from its from_timestamp on
    assert episode["next.reward"].tolist() == [0, 0, 0, 0, 0, 1]
    assert ds[0]["task"] == "task 0" and ds[len(ds) - 1]["task"] == "task 0"
    assert ds.load_episode(1)["timestamp"].shape == (7,)
    assert ds.get_col_data("next.reward").shape == (18,)
    assert ds.get_row_data(5)["task"] == "task 1"
    one = LeRobotAdapter(root=v3, episodes=[1])  # the middle episode of a file shared with episode 0
    assert one.lengths.tolist() == [7] and one.load_episode(0)["action"][:, 0].tolist() == list(range(10, 17))
    assert close_to(one[3]["pixels"], chw([frame(1, 3)]))


def test_episode_subset_and_aliases(v2):
    ds = LeRobotAdapter(root=v2, episodes=[2, 0], key_aliases={"next.reward": "reward"})
    assert ds.lengths.tolist() == [5, 6]  # index order, as lerobot reads them
    assert ds.column_names == ["pixels", "action", "proprio", "reward", "ep_idx", "step_idx"]
    last = ds[len(ds) - 1]
    assert last["ep_idx"].tolist() == [1] and last["reward"].tolist() == [1.0]
    assert close_to(last["pixels"], chw([frame(2, 5)]))
    with pytest.raises(ConfigError, match=r"\[7\]"):
        LeRobotAdapter(root=v2, episodes=[0, 7])
    with pytest.raises(UnknownNameError, match="next.rewards"):
        LeRobotAdapter(root=v2, key_aliases={"next.rewards": "reward"})
    with pytest.raises(UnknownNameError, match="Did you mean 'proprio'"):
        LeRobotAdapter(root=v2, keys_to_load=["propio"])


def test_cameras_images_and_cache(tmp_path):
    root = write_v2(tmp_path / "two", lengths=(4, 5), cameras={CAMERA: "video", WRIST: "image"})
    with pytest.raises(ConfigError, match="primary_camera_key") as err:
        LeRobotAdapter(root=root)
    assert WRIST in str(err.value)
    ds = LeRobotAdapter(root=root, primary_camera_key=WRIST, keys_to_load=["pixels", CAMERA], keys_to_cache=["pixels"])
    item = ds[5]  # episode 1, step 1
    np.testing.assert_array_equal(item["pixels"].numpy(), chw([frame(1, 1, shift=3)]))  # PNG: lossless
    assert close_to(item[CAMERA], chw([frame(1, 1)]))


# -- paths -----------------------------------------------------------------------------------------
def test_lerobot_url_from_hf_home(tmp_path, monkeypatch):
    home = tmp_path / "hf"
    monkeypatch.setenv("HF_HOME", str(home))
    monkeypatch.delenv("HF_LEROBOT_HOME", raising=False)
    monkeypatch.delenv("HF_HUB_CACHE", raising=False)
    monkeypatch.delenv("HUGGINGFACE_HUB_CACHE", raising=False)
    with pytest.raises(DatasetNotFoundError) as err:
        load_dataset("lerobot://org/toy")
    message = str(err.value)
    assert str(home / "lerobot" / "org" / "toy") in message and str(home / "hub" / "datasets--org--toy") in message
    assert isinstance(err.value, FileNotFoundError)

    write_v2(home / "lerobot" / "org" / "toy", lengths=(3, 4))
    ds = load_dataset("lerobot://org/toy", num_steps=2)
    assert isinstance(ds, LeRobotAdapter) and ds.repo_id == "org/toy" and ds.lengths.tolist() == [3, 4]
    assert len(ds) == 2 + 3

    monkeypatch.setenv("HF_LEROBOT_HOME", str(tmp_path / "elsewhere"))  # lerobot's own variable wins
    with pytest.raises(DatasetNotFoundError, match="elsewhere"):
        LeRobotAdapter("org/toy")


def test_lerobot_url_from_hub_cache(tmp_path, monkeypatch):
    home = tmp_path / "hf"
    monkeypatch.setenv("HF_HOME", str(home))
    for var in ("HF_LEROBOT_HOME", "HF_HUB_CACHE", "HUGGINGFACE_HUB_CACHE"):
        monkeypatch.delenv(var, raising=False)
    repo = home / "hub" / "datasets--org--cached"
    write_v3(repo / "snapshots" / "abc123", lengths=(3, 4, 2), files=((0, 1, 2),))
    (repo / "refs").mkdir()
    (repo / "refs" / "main").write_text("abc123")
    ds = load_dataset("lerobot://org/cached")
    assert ds.root == repo / "snapshots" / "abc123" and ds.lengths.tolist() == [3, 4, 2]
    assert close_to(ds[4]["pixels"], chw([frame(1, 1)]))
    with pytest.raises(DatasetNotFoundError, match="v9"):
        load_dataset("lerobot://org/cached", revision="v9")


def test_bad_arguments(v2):
    with pytest.raises(ConfigError, match="repo_id"):
        LeRobotAdapter()
    with pytest.raises(ConfigError, match="delta_timestamps"):
        LeRobotAdapter(root=v2, delta_timestamps={"action": [0.0]})
    with pytest.raises(ConfigError, match="tolerance_s"):
        LeRobotAdapter(root=v2, tolerance_s=0)
    with pytest.raises(DatasetNotFoundError, match="meta/info.json"):
        LeRobotAdapter(root=v2 / "data")
    with pytest.raises(ConfigError, match="num_steps"):
        LeRobotAdapter(root=v2, num_steps=8)  # no episode holds 8 rows
    with pytest.raises(ConfigError, match="format 'hdf5' does not read lerobot://"):
        load_dataset("lerobot://org/toy", format="hdf5")
    LeRobotAdapter(root=v2, video_backend="pyav", force_cache_sync=False)  # lerobot's, accepted


# -- malformed datasets ----------------------------------------------------------------------------
def test_malformed_metadata(tmp_path):
    root = write_v2(tmp_path / "bad", lengths=(3, 4))
    info_path = root / "meta" / "info.json"
    meta = json.loads(info_path.read_text())

    info_path.write_text(json.dumps({**meta, "codebase_version": "v1.6"}))
    with pytest.raises(DatasetFormatError, match="v1.6"):
        LeRobotAdapter(root=root)
    info_path.write_text("{not json")
    with pytest.raises(DatasetFormatError, match="valid JSON"):
        LeRobotAdapter(root=root)
    info_path.write_text(json.dumps(meta))

    episodes = root / "meta" / "episodes.jsonl"
    good = episodes.read_text()
    episodes.write_text(good.replace('"length": 4', '"length": 9'))
    with pytest.raises(DatasetFormatError, match="episode 1 to hold 9 rows"):
        LeRobotAdapter(root=root)
    episodes.write_text(good.replace('"length": 4', '"length": "four"'))
    with pytest.raises(DatasetFormatError, match="length"):
        LeRobotAdapter(root=root)
    episodes.write_text(good)

    (root / "videos/chunk-000" / CAMERA / "episode_000001.mp4").unlink()
    ds = LeRobotAdapter(root=root)  # videos are opened on first read
    with pytest.raises(DatasetFormatError, match="episode_000001.mp4"):
        ds[3]


def test_malformed_v3_episodes(tmp_path):
    root = write_v3(tmp_path / "bad3")
    path = root / "meta/episodes/chunk-000/file-000.parquet"
    pq.write_table(pq.read_table(path).drop_columns(["data/file_index"]), path)
    with pytest.raises(DatasetFormatError, match="data/file_index"):
        LeRobotAdapter(root=root)


def test_video_shorter_than_rows(tmp_path):
    root = write_v2(tmp_path / "short", lengths=(3,))
    write_mp4(root / "videos/chunk-000" / CAMERA / "episode_000000.mp4", [frame(0, 0), frame(0, 1)])
    ds = LeRobotAdapter(root=root)
    assert close_to(ds[1]["pixels"], chw([frame(0, 1)]))
    with pytest.raises(DatasetFormatError, match="tolerance_s"):
        ds[2]


# -- loaders ---------------------------------------------------------------------------------------
def test_dataloader_with_workers(v3):
    ds = load_dataset(v3, num_steps=2)
    assert close_to(ds[0]["pixels"], chw([frame(0, 0), frame(0, 1)]))  # a video open here: workers open their own
    copy = pickle.loads(pickle.dumps(ds))  # what a spawned worker gets
    assert close_to(copy[len(ds) - 1]["pixels"], chw([frame(2, 4), frame(2, 5)]))
    loader = torch.utils.data.DataLoader(ds, batch_size=4, shuffle=False, num_workers=2)
    batches = list(loader)
    assert sum(len(b["pixels"]) for b in batches) == len(ds)
    first = batches[0]
    assert first["pixels"].shape == (4, 2, 3, SIZE, SIZE) and first["action"].shape == (4, 2, 2)
    assert close_to(first["pixels"][1], chw([frame(0, 1), frame(0, 2)]))
    ds.close()


def test_summary(v2):
    summary = get_format("lerobot").summary(v2)
    assert summary["format"] == "lerobot" and summary["num_episodes"] == 3 and summary["num_steps"] == 18
    assert summary["obs_shape"] == (SIZE, SIZE, 3) and summary["action_shape"] == (2,)


def test_videos_are_closed_before_a_fork(v3):
    import os

    ds = load_dataset(v3, num_steps=2)
    first = ds[0]["pixels"]
    assert ds._videos._open  # a video open in this process
    pid = os.fork()
    if pid == 0:  # the child: nothing to do
        os._exit(0)
    os.waitpid(pid, 0)
    assert not ds._videos._open  # closed before the fork (FFmpeg's decoder threads joined)
    assert torch.equal(ds[0]["pixels"], first)  # and reopened when read
    ds.close()

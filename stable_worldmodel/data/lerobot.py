"""LeRobot datasets, read only: a LeRobot v2.x or v3.0 dataset folder as a :class:`~.dataset.Dataset`.

Behaviour follows upstream stable-worldmodel 0.1.1's ``LeRobotAdapter`` (format ``lerobot``,
``load_dataset("lerobot://<repo_id>")``). Upstream wraps the ``lerobot`` package (Python 3.12+,
downloads from the Hub); this reader needs neither ``lerobot`` nor the network: it reads the files
with pyarrow (parquet) and PyAV (video). LeRobot's layouts::

    v2.x  meta/info.json  meta/episodes.jsonl  meta/tasks.jsonl
          data/chunk-XXX/episode_XXXXXX.parquet               one file per episode
          videos/chunk-XXX/<video_key>/episode_XXXXXX.mp4     one video per episode and camera
    v3.0  meta/info.json  meta/episodes/chunk-XXX/file-XXX.parquet  meta/tasks.parquet
          data/chunk-XXX/file-XXX.parquet                     many episodes per file
          videos/<video_key>/chunk-XXX/file-XXX.mp4           many episodes per file, each from its
                                                              ``videos/<key>/from_timestamp`` on

(``data_path`` / ``video_path`` in ``info.json`` override those paths). Columns, named as upstream
names them::

    pixels     the primary camera (``primary_camera_key``, required when there are several)
    action     ``action``
    proprio    ``observation.state``
    <alias>    each ``key_aliases`` entry ``{feature: alias}``
    ep_idx     the episode's position among the episodes read (0, 1, ...)
    step_idx   the row's step in its episode

are loaded by default (upstream's ``keys_to_load``). Every other feature of ``info.json`` (other
cameras, ``timestamp``, ``next.reward`` ...) is a column under its own name, and so is ``task``
(each row's task string) when the dataset lists its tasks: name them in ``keys_to_load``. Camera
features (``video``, ``image``) are decoded to uint8 ``(H, W, C)`` rows (items: ``(T, C, H, W)``),
video frames matched to each row's ``timestamp`` within ``tolerance_s`` (lerobot's rule).

A Hub id ``"org/name"`` is found where lerobot and huggingface_hub keep it, OFFLINE:
``$HF_LEROBOT_HOME/org/name`` (default ``$HF_HOME/lerobot/org/name``; ``HF_HOME`` default
``$XDG_CACHE_HOME/huggingface``, i.e. ``~/.cache/huggingface``), then the hub cache
``$HF_HUB_CACHE/datasets--org--name/snapshots/<revision>`` (default ``$HF_HOME/hub``). Nothing is
downloaded: a missing dataset is a :class:`~stable_worldmodel.errors.DatasetNotFoundError` naming
those folders.
"""

from __future__ import annotations

import io
import json
import logging
import os
import weakref
from collections import OrderedDict
from collections.abc import Callable, Collection, Mapping, Sequence
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np

from .. import keys
from .._optional import require
from ..errors import ConfigError, DatasetFormatError, UnknownNameError, did_you_mean
from .dataset import Dataset, missing_column
from .formats.lerobot import INFO, find_dataset, hub_cache, lerobot_home, parse_url

__all__ = ["LeRobotAdapter", "find_dataset", "hub_cache", "lerobot_home", "parse_url"]

logger = logging.getLogger(__name__)

TASK = "task"
CAMERA_DTYPES = ("video", "image")
#: lerobot's default: a video frame is a row's when their times differ by at most this (seconds)
TOLERANCE_S = 1e-4
#: video files each process keeps open
OPEN_VIDEOS = 8
V2_DATA = "data/chunk-{episode_chunk:03d}/episode_{episode_index:06d}.parquet"
V2_VIDEO = "videos/chunk-{episode_chunk:03d}/{video_key}/episode_{episode_index:06d}.mp4"
V3_DATA = "data/chunk-{chunk_index:03d}/file-{file_index:03d}.parquet"
V3_VIDEO = "videos/{video_key}/chunk-{chunk_index:03d}/file-{file_index:03d}.mp4"
#: lerobot ``LeRobotDataset`` arguments upstream forwards that mean nothing offline: accepted, unused
IGNORED_ARGUMENTS = ("force_cache_sync", "download_videos", "video_backend", "batch_encoding_size")


class Episode(NamedTuple):
    """One episode of the metadata: its index, rows, data file and ``{video_key: (file, from_timestamp)}``."""

    index: int
    length: int
    data: str
    videos: dict[str, tuple[str, float]]


# -- metadata -------------------------------------------------------------------------------------
def _json(path: Path, owner: str) -> Any:
    try:
        return json.loads(path.read_text())
    except FileNotFoundError:
        raise DatasetFormatError(f"{owner} requires {path}, which does not exist") from None
    except (OSError, ValueError) as exc:
        raise DatasetFormatError(f"{owner} requires valid JSON in {path}, got: {exc}") from None


def _jsonl(path: Path, owner: str) -> list[dict[str, Any]]:
    if not path.is_file():
        raise DatasetFormatError(f"{owner} requires {path} (a LeRobot v2 dataset's episode list), which does not exist")
    rows = []
    for n, line in enumerate(path.read_text().splitlines(), 1):
        if not line.strip():
            continue
        try:
            row = json.loads(line)
        except ValueError as exc:
            raise DatasetFormatError(f"{owner} requires one JSON object per line of {path}, line {n}: {exc}") from None
        if not isinstance(row, dict):
            raise DatasetFormatError(f"{owner} requires one JSON object per line of {path}, got {row!r} on line {n}")
        rows.append(row)
    return rows


def read_info(root: Path, owner: str) -> dict[str, Any]:
    """``meta/info.json``, checked: a v2/v3 ``codebase_version``, ``fps`` and ``features``."""
    path = root / INFO
    info = _json(path, owner)
    if not isinstance(info, dict):
        raise DatasetFormatError(f"{owner} requires a JSON object in {path}, got {type(info).__name__}")
    version = info.get("codebase_version")
    if not isinstance(version, str) or not version.startswith(("v2.", "v3.")):
        raise DatasetFormatError(
            f"{owner} reads LeRobot datasets of codebase_version v2.x and v3.x, got {version!r} in {path}"
        )
    fps = info.get("fps")
    if isinstance(fps, bool) or not isinstance(fps, (int, float)) or fps <= 0:
        raise DatasetFormatError(f"{owner} requires a positive fps in {path}, got {fps!r}")
    features = info.get("features")
    if not isinstance(features, dict) or not features:
        raise DatasetFormatError(f"{owner} requires a non-empty 'features' object in {path}, got {features!r}")
    for name, ft in features.items():
        shape = ft.get("shape") if isinstance(ft, dict) else None
        if not isinstance(ft, dict) or not isinstance(ft.get("dtype"), str) or not isinstance(shape, list):
            raise DatasetFormatError(
                f"{owner} requires each feature of {path} to give dtype and shape, got {name!r}: {ft!r}"
            )
    return info


def _int(value: Any, what: str, where: Path, owner: str) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 0:
        raise DatasetFormatError(f"{owner} requires {what} to be a non-negative int in {where}, got {value!r}")
    return int(value)


def _template(info: Mapping[str, Any], key: str, default: str, where: Path, owner: str, **fields: Any) -> str:
    try:
        return (info.get(key) or default).format(**fields)
    except (KeyError, IndexError, ValueError, AttributeError) as exc:
        raise DatasetFormatError(f"{owner} cannot fill {key} {info.get(key)!r} of {where}: {exc!r}") from None


def read_episodes(root: Path, info: Mapping[str, Any], owner: str) -> list[Episode]:
    """Every episode of the metadata, by index (v2: ``episodes.jsonl``; v3: ``meta/episodes/``)."""
    videos = [k for k, ft in info["features"].items() if ft["dtype"] == "video"]
    where = root / INFO
    out = []
    if info["codebase_version"].startswith("v2."):
        path = root / "meta" / "episodes.jsonl"
        chunks = _int(info.get("chunks_size", 1000), "chunks_size", where, owner) or 1000
        for row in _jsonl(path, owner):
            ep = _int(row.get("episode_index"), "episode_index", path, owner)
            fields = {"episode_chunk": ep // chunks, "episode_index": ep}
            out.append(
                Episode(
                    ep,
                    _int(row.get("length"), "length", path, owner),
                    _template(info, "data_path", V2_DATA, where, owner, **fields),
                    {
                        k: (_template(info, "video_path", V2_VIDEO, where, owner, video_key=k, **fields), 0.0)
                        for k in videos
                    },
                )
            )
    else:
        pq = _parquet()
        files = sorted((root / "meta" / "episodes").glob("*/*.parquet"))
        if not files:
            raise DatasetFormatError(
                f"{owner} requires {root / 'meta' / 'episodes'}/chunk-XXX/file-XXX.parquet, none found"
            )
        wanted = ["episode_index", "length", "data/chunk_index", "data/file_index"]
        wanted += [f"videos/{k}/{f}" for k in videos for f in ("chunk_index", "file_index", "from_timestamp")]
        for file in files:
            missing = [c for c in wanted if c not in pq.read_schema(file).names]
            if missing:
                raise DatasetFormatError(f"{owner} requires the columns {missing} in {file} (LeRobot v3 episodes)")
            rows = pq.read_table(file, columns=wanted).to_pylist()
            for row in rows:
                data = {"chunk_index": row["data/chunk_index"], "file_index": row["data/file_index"]}
                vids = {}
                for k in videos:
                    at = {"chunk_index": row[f"videos/{k}/chunk_index"], "file_index": row[f"videos/{k}/file_index"]}
                    start = row[f"videos/{k}/from_timestamp"]
                    if not isinstance(start, (int, float)):
                        raise DatasetFormatError(
                            f"{owner} requires videos/{k}/from_timestamp numbers in {file}, got {start!r}"
                        )
                    vids[k] = (_template(info, "video_path", V3_VIDEO, where, owner, video_key=k, **at), float(start))
                out.append(
                    Episode(
                        _int(row["episode_index"], "episode_index", file, owner),
                        _int(row["length"], "length", file, owner),
                        _template(info, "data_path", V3_DATA, where, owner, **data),
                        vids,
                    )
                )
    out.sort(key=lambda e: e.index)
    seen = [e.index for e in out]
    if len(set(seen)) != len(seen):
        raise DatasetFormatError(f"{owner} requires each episode listed once in {root / 'meta'}, got indices {seen}")
    return out


def read_tasks(root: Path) -> dict[int, str]:
    """``task_index -> task`` (v2 ``tasks.jsonl``, v3 ``tasks.parquet``); empty when not readable."""
    try:
        if (root / "meta" / "tasks.jsonl").is_file():
            rows = [
                json.loads(line) for line in (root / "meta" / "tasks.jsonl").read_text().splitlines() if line.strip()
            ]
            return {int(r["task_index"]): str(r["task"]) for r in rows}
        if (root / "meta" / "tasks.parquet").is_file():
            table = _parquet().read_table(root / "meta" / "tasks.parquet").to_pydict()
            text = "task" if "task" in table else next(k for k, v in table.items() if v and isinstance(v[0], str))
            return {int(i): str(t) for i, t in zip(table["task_index"], table[text], strict=True)}
    except (OSError, ValueError, KeyError, TypeError, StopIteration) as exc:
        logger.warning("LeRobot tasks of %s not readable (no task column): %s", root, exc)
    return {}


def _is_list(kind: Any) -> bool:
    import pyarrow as pa

    return pa.types.is_list(kind) or pa.types.is_large_list(kind) or pa.types.is_fixed_size_list(kind)


def _parquet() -> Any:
    require("pyarrow", extra="lance", purpose="LeRobot datasets")
    import pyarrow.parquet as pq

    return pq


# -- frames ---------------------------------------------------------------------------------------
def _channels(feature: Mapping[str, Any]) -> int:
    """1 for a grey camera feature, else 3 (frames are decoded to RGB)."""
    shape, names = list(feature.get("shape") or []), feature.get("names")
    if isinstance(names, list) and len(names) == len(shape):
        for name, size in zip(names, shape, strict=True):
            if str(name).startswith("channel"):
                return 1 if size == 1 else 3
    return 1 if shape and shape[-1] == 1 else 3


def decode_image(value: Any, root: Path, channels: int) -> np.ndarray:
    """An ``image`` feature's cell (``{"bytes", "path"}`` or bytes) as ``(H, W, C)`` uint8."""
    from PIL import Image

    data, path = (value.get("bytes"), value.get("path")) if isinstance(value, dict) else (value, None)
    source = io.BytesIO(data) if data else (root / path if path and (root / path).is_file() else path)
    with Image.open(source) as img:
        frame = np.asarray(img.convert("L" if channels == 1 else "RGB"))
    return frame[..., None] if channels == 1 else frame


_INHERITED: list[Any] = []  # video containers a forked process inherited: kept, unused
_LIVE: weakref.WeakSet[VideoFrames] = weakref.WeakSet()  # every VideoFrames of this process


def _close_before_fork() -> None:
    """Close this process's open videos before it forks (a DataLoader starting its workers): FFmpeg's
    decoder threads are joined, so no child starts from a copy of a decoder some thread was inside
    (a worker then crashed with SIGSEGV, now and then, on a loaded machine). They reopen when read."""
    for frames in list(_LIVE):
        if frames._pid == os.getpid():  # inherited ones stay untouched (module docstring of _INHERITED)
            frames.close()


if hasattr(os, "register_at_fork"):
    os.register_at_fork(before=_close_before_fork)


class VideoFrames:
    """The video files open in this process (a forked or spawned DataLoader worker opens its own)."""

    def __init__(self) -> None:
        self._open: OrderedDict[Path, Any] = OrderedDict()
        self._pid = os.getpid()
        _LIVE.add(self)

    def _container(self, path: Path, owner: str) -> Any:
        if self._pid != os.getpid():  # forked: the parent's handles stay the parent's, never freed here
            _INHERITED.extend(self._open.values())  # (freeing them could wait on the parent's decoder threads)
            self._open, self._pid = OrderedDict(), os.getpid()
        container = self._open.get(path)
        if container is not None:
            self._open.move_to_end(path)
            return container
        av = require("av", extra="video", purpose="LeRobot video features")
        if not path.is_file():
            raise DatasetFormatError(f"{owner} requires the video {path}, which does not exist")
        try:
            container = av.open(str(path))
        except av.error.FFmpegError as exc:
            raise DatasetFormatError(f"{owner} cannot read the video {path}: {exc}") from None
        if not container.streams.video:
            container.close()
            raise DatasetFormatError(f"{owner} requires a video stream in {path}, got none")
        self._open[path] = container
        if len(self._open) > OPEN_VIDEOS:
            self._open.popitem(last=False)[1].close()
        return container

    def frames(self, path: Path, times: np.ndarray, tolerance: float, channels: int, owner: str) -> np.ndarray:
        """Frames ``(len(times), H, W, C)`` uint8 of the video at ``path`` shown at ``times``
        (seconds, each within ``tolerance`` of a frame): decoded from the keyframe before the first."""
        container = self._container(path, owner)
        stream = container.streams.video[0]
        wanted, inverse = np.unique(np.asarray(times, np.float64), return_inverse=True)
        got: list[np.ndarray | None] = [None] * len(wanted)
        gap = np.full(len(wanted), np.inf)
        fmt = "gray" if channels == 1 else "rgb24"
        first = max(float(wanted[0]) - tolerance, 0.0)
        av = require("av", extra="video", purpose="LeRobot video features")
        for start in dict.fromkeys((first, 0.0)):  # again from the start when the seek landed too late
            try:
                container.seek(int(start / stream.time_base), stream=stream, backward=True, any_frame=False)
                for frame in container.decode(stream):
                    t = frame.time
                    if t is None:
                        continue
                    i = int(np.searchsorted(wanted, t))
                    for j in (i - 1, i):
                        if 0 <= j < len(wanted) and abs(wanted[j] - t) <= tolerance and abs(wanted[j] - t) < gap[j]:
                            gap[j], got[j] = abs(wanted[j] - t), frame.to_ndarray(format=fmt)
                    if t > wanted[-1] + tolerance:
                        break
            except av.error.FFmpegError as exc:
                raise DatasetFormatError(f"{owner} cannot decode the video {path}: {exc}") from None
            if all(g is not None for g in got):
                break
        missing = [float(t) for t, g in zip(wanted, got, strict=True) if g is None]
        if missing:
            raise DatasetFormatError(
                f"{owner} found no frame of {path} within tolerance_s={tolerance} of t={missing[0]:.6f}s "
                f"({len(missing)} times missed); the video is shorter than the rows or off their timestamps "
                "(a larger tolerance_s accepts frames further off)"
            )
        frames = np.stack(got)[inverse]
        return frames[..., None] if channels == 1 else frames

    def close(self) -> None:
        for container in self._open.values():
            container.close()
        self._open.clear()


# -- the reader -----------------------------------------------------------------------------------
class LeRobotAdapter(Dataset):
    """A LeRobot dataset (module docstring) as a :class:`~.dataset.Dataset`; upstream 0.1.1's arguments.

    Args:
        repo_id: a Hub id ``"org/name"`` found on disk (or a dataset folder); ``root`` wins when given.
        root: the dataset folder (holding ``meta/info.json``).
        episodes: indices of the episodes to read (default: all), in index order.
        frameskip, num_steps, transform, keys_to_load, dense_columns: as every dataset's.
        keys_to_cache: columns read into memory once (camera columns: every frame decoded).
        primary_camera_key: the camera read as ``pixels`` (required when there are several).
        key_aliases: ``{feature: column name}`` for more features under names of your choice.
        revision: the hub-cache snapshot (branch, tag or commit) to read a Hub id from.
        tolerance_s: seconds between a row's timestamp and its video frame, at most.
        **lerobot_kwargs: lerobot's ``force_cache_sync``, ``download_videos``, ``video_backend``,
            ``batch_encoding_size`` (accepted, unused: nothing is downloaded, PyAV decodes).
    """

    def __init__(
        self,
        repo_id: str | None = None,
        root: str | os.PathLike | None = None,
        episodes: Sequence[int] | None = None,
        frameskip: int = 1,
        num_steps: int = 1,
        transform: Callable[[dict], dict] | None = None,
        keys_to_load: Sequence[str] | None = None,
        keys_to_cache: Sequence[str] | None = None,
        primary_camera_key: str | None = None,
        key_aliases: Mapping[str, str] | None = None,
        *,
        dense_columns: Collection[str] | str | None = None,
        revision: str | None = None,
        tolerance_s: float = TOLERANCE_S,
        **lerobot_kwargs: Any,
    ):
        owner = type(self).__name__
        unknown = sorted(set(lerobot_kwargs) - set(IGNORED_ARGUMENTS))
        if unknown:
            raise ConfigError(
                f"{owner} got unexpected arguments {unknown}; besides its own it accepts lerobot's "
                f"{', '.join(IGNORED_ARGUMENTS)} (unused offline).{did_you_mean(unknown[0], IGNORED_ARGUMENTS)}"
            )
        super().__init__(
            frameskip=frameskip,
            num_steps=num_steps,
            transform=transform,
            keys_to_load=keys_to_load,
            dense_columns=dense_columns,
        )
        if isinstance(tolerance_s, bool) or not isinstance(tolerance_s, (int, float)) or not tolerance_s > 0:
            raise ConfigError(f"{owner} requires tolerance_s to be a positive number of seconds, got {tolerance_s!r}")
        self.tolerance_s = float(tolerance_s)
        if repo_id is None and root is None:
            raise ConfigError(f"{owner} requires repo_id (a Hub id such as 'lerobot/pusht') or root (a dataset folder)")
        self.root = find_dataset(repo_id, root, revision, owner)
        self.repo_id = repo_id if repo_id is not None else self.root.name
        self.info = read_info(self.root, owner)
        self.features: dict[str, dict[str, Any]] = self.info["features"]
        self.fps = float(self.info["fps"])
        self.camera_keys = [k for k, ft in self.features.items() if ft["dtype"] in CAMERA_DTYPES]
        self.video_keys = [k for k, ft in self.features.items() if ft["dtype"] == "video"]
        self._episodes = self._select(read_episodes(self.root, self.info, owner), episodes)
        self.episodes = list(episodes) if episodes is not None else None  # as given (upstream's attribute)
        self._tasks = read_tasks(self.root)
        self._source, self._default = self._name_columns(primary_camera_key, key_aliases)
        self._columns = [*self._default, *(c for c in self._source if c not in self._default)]
        self._files, rows = self._scan()
        self.lengths = np.array([e.length for e in self._episodes], np.int64)
        self.offsets = np.concatenate([[0], np.cumsum(self.lengths)[:-1]]).astype(np.int64)
        self._rows = rows  # row r of this dataset is row _rows[r] of the data files put end to end
        self._ep_of_row = np.repeat(np.arange(len(self._episodes)), self.lengths)
        self._step_of_row = np.arange(len(rows), dtype=np.int64) - np.repeat(self.offsets, self.lengths)
        self._arrays: dict[str, Any] = {}  # feature -> Arrow column of our rows
        self._values: dict[str, np.ndarray] = {}  # feature -> numpy rows
        self._cache: dict[str, np.ndarray] = {}  # keys_to_cache: column -> every row
        self._videos = VideoFrames()
        self.check_span()
        if keys_to_load is not None:
            self.check_keys(self.column_names)
        for col in keys_to_cache or ():
            self.check_keys([col])
            self._cache[col] = self._take(col, np.arange(self.num_rows))

    # -- construction ---------------------------------------------------------------------------
    def _select(self, listed: list[Episode], episodes: Sequence[int] | None) -> list[Episode]:
        if episodes is None:
            return listed
        owner, known = type(self).__name__, {e.index: e for e in listed}
        wanted = list(episodes) if isinstance(episodes, Collection) and not isinstance(episodes, (str, bytes)) else None
        if not wanted or not all(isinstance(e, (int, np.integer)) and not isinstance(e, bool) for e in wanted):
            raise ConfigError(f"{owner} requires episodes to be a non-empty list of episode indices, got {episodes!r}")
        missing = sorted({int(e) for e in wanted} - set(known))
        if missing:
            span = f"{min(known)}..{max(known)}" if known else "none"
            raise ConfigError(f"{owner} requires episodes of the dataset (indices {span}), got {missing}, not in it")
        return [known[e] for e in sorted({int(e) for e in wanted})]

    def _name_columns(
        self, primary: str | None, aliases: Mapping[str, str] | None
    ) -> tuple[dict[str, str | None], list[str]]:
        """``{column: feature}`` (None for ep_idx / step_idx / task) and the default columns (upstream's)."""
        owner = type(self).__name__
        if primary is None and len(self.camera_keys) > 1:
            raise ConfigError(
                f"{owner} requires primary_camera_key (the camera read as {keys.PIXELS!r}) when the dataset has "
                f"several cameras, got None; pass one of {self.camera_keys}"
            )
        if primary is not None and primary not in self.features:
            raise UnknownNameError(
                f"{owner} primary_camera_key {primary!r} is not a feature of {self.root}."
                f"{did_you_mean(primary, self.camera_keys)} Cameras: {', '.join(self.camera_keys) or '(none)'}"
            )
        if aliases is not None and not isinstance(aliases, Mapping):
            raise ConfigError(f"{owner} requires key_aliases to be a mapping {{feature: column name}}, got {aliases!r}")
        named: dict[str, str] = {}  # feature -> column
        primary = primary if primary is not None else next(iter(self.camera_keys), None)
        if primary is not None:
            named[primary] = keys.PIXELS
        for feature, column in ((keys.ACTION, keys.ACTION), ("observation.state", keys.PROPRIO)):
            if feature in self.features:
                named[feature] = column
        for feature, column in (aliases or {}).items():
            if feature not in self.features:
                raise UnknownNameError(
                    f"{owner} key_aliases names {feature!r}, not a feature of {self.root}."
                    f"{did_you_mean(str(feature), self.features)} Features: {', '.join(self.features)}"
                )
            if not isinstance(column, str) or not column:
                raise ConfigError(
                    f"{owner} requires key_aliases values to be column names, got {feature!r}: {column!r}"
                )
            named[feature] = column
        source: dict[str, str | None] = {column: feature for feature, column in named.items()}
        default = [*source, keys.EP_IDX, keys.STEP_IDX]
        source.update({keys.EP_IDX: None, keys.STEP_IDX: None})
        for feature in self.features:
            if feature not in named and feature not in source:
                source[feature] = feature
        if self._tasks and "task_index" in self.features and TASK not in source:
            source[TASK] = None
        return source, default

    def _scan(self) -> tuple[list[str], np.ndarray]:
        """The data files of the episodes read and the rows of each episode in them, checked
        against the metadata (each episode's rows contiguous, as many as its length)."""
        owner, pq = type(self).__name__, _parquet()
        files = list(dict.fromkeys(e.data for e in self._episodes))
        index = []
        for file in files:
            path = self.root / file
            if not path.is_file():
                eps = [e.index for e in self._episodes if e.data == file]
                raise DatasetFormatError(
                    f"{owner} requires the data file {path} (episodes {eps}), which does not exist"
                )
            if "episode_index" not in pq.read_schema(path).names:
                raise DatasetFormatError(f"{owner} requires an episode_index column in {path}")
            index.append(pq.read_table(path, columns=["episode_index"]).column(0).to_numpy())
        ep = np.concatenate(index).astype(np.int64) if index else np.zeros(0, np.int64)
        starts = np.concatenate([[0], np.flatnonzero(np.diff(ep)) + 1]) if len(ep) else np.zeros(0, np.int64)
        runs: dict[int, tuple[int, int]] = {}
        for start, stop in zip(starts, [*starts[1:], len(ep)], strict=True):
            value = int(ep[start])
            if value in runs:
                raise DatasetFormatError(
                    f"{owner} requires the rows of each episode together, got episode {value} split"
                )
            runs[value] = (int(start), int(stop - start))
        rows = []
        for episode in self._episodes:
            start, n = runs.get(episode.index, (0, 0))
            if n != episode.length:
                raise DatasetFormatError(
                    f"{owner} requires episode {episode.index} to hold {episode.length} rows (its length in "
                    f"{self.root / 'meta'}), got {n} rows in {self.root / episode.data}"
                )
            rows.append(np.arange(start, start + n, dtype=np.int64))
        return files, np.concatenate(rows) if rows else np.zeros(0, np.int64)

    # -- reading --------------------------------------------------------------------------------
    @property
    def stored_columns(self) -> list[str]:
        return list(self._columns)

    @property
    def column_names(self) -> list[str]:
        """``keys_to_load``, by default upstream's: pixels, action, proprio, the aliases, ep_idx, step_idx."""
        return list(self._keys_to_load) if self._keys_to_load is not None else list(self._default)

    def _arrow(self, feature: str) -> Any:
        """The Arrow column of ``feature`` for our rows (read once)."""
        if feature not in self._arrays:
            import pyarrow as pa

            pq, chunks = _parquet(), []
            for file in self._files:
                path = self.root / file
                if feature not in pq.read_schema(path).names:
                    raise DatasetFormatError(
                        f"{type(self).__name__} requires a column {feature!r} (a feature of {INFO}) in {path}"
                    )
                chunks.extend(pq.read_table(path, columns=[feature]).column(0).chunks)
            self._arrays[feature] = pa.chunked_array(chunks).take(pa.array(self._rows)).combine_chunks()
        return self._arrays[feature]

    def _numbers(self, feature: str) -> np.ndarray:
        """Rows ``(N, *shape)`` of a non-camera feature (``(N,)`` when stored as scalars)."""
        if feature not in self._values:
            values, ft = self._arrow(feature), self.features[feature]
            shape, n = tuple(int(s) for s in ft["shape"]), len(self._rows)
            if _is_list(values.type):
                flat = values
                while _is_list(flat.type):  # Array2D and up: lists of lists
                    flat = flat.flatten()
                out = flat.to_numpy(zero_copy_only=False)
                if out.size != n * int(np.prod(shape, dtype=np.int64)):
                    raise DatasetFormatError(
                        f"{type(self).__name__} requires {feature!r} rows of shape {list(shape)} ({INFO}), "
                        f"got {out.size} values for {n} rows"
                    )
                out = out.reshape(n, *shape)
            else:
                out = values.to_numpy(zero_copy_only=False)
            if ft["dtype"] not in ("string", "str"):
                try:
                    out = out.astype(np.dtype(ft["dtype"]), copy=False)
                except TypeError:
                    pass  # a dtype numpy does not know: keep what is stored
            self._values[feature] = out
        return self._values[feature]

    def _timestamps(self) -> np.ndarray:
        if "timestamp" in self.features:
            return self._numbers("timestamp").reshape(len(self._rows)).astype(np.float64)
        return self._step_of_row / self.fps

    def _take(self, col: str, rows: np.ndarray) -> np.ndarray:
        """Rows ``rows`` (sorted, of one column) of ``col``."""
        if col in self._cache:
            return self._cache[col][rows]
        if col not in self._source:
            raise missing_column(type(self).__name__, col, self.stored_columns)
        feature = self._source[col]
        if not len(rows):
            return self._empty(col, feature)
        if col == keys.EP_IDX and feature is None:
            return self._ep_of_row[rows]
        if col == keys.STEP_IDX and feature is None:
            return self._step_of_row[rows]
        if col == TASK and feature is None:
            index = self._numbers("task_index").reshape(len(self._rows))[rows]
            unknown = sorted(set(index.tolist()) - set(self._tasks))
            if unknown:
                raise DatasetFormatError(f"{type(self).__name__} requires the tasks {unknown} in {self.root / 'meta'}")
            return np.array([self._tasks[int(i)] for i in index], dtype=str)
        kind = self.features[feature]["dtype"]
        if kind == "video":
            return self._video(feature, rows)
        if kind == "image":
            cells = self._arrow(feature).take(rows).to_pylist()
            channels = _channels(self.features[feature])
            return np.stack([decode_image(c, self.root, channels) for c in cells])
        return self._numbers(feature)[rows]

    def _empty(self, col: str, feature: str | None) -> np.ndarray:
        """No rows of ``col``, shaped as its rows are."""
        if feature is None:
            return np.zeros(0, str if col == TASK else np.int64)
        ft = self.features[feature]
        shape = [int(s) for s in ft["shape"]]
        if ft["dtype"] in CAMERA_DTYPES:
            names = [str(n) for n in ft.get("names") or []]
            hwc = names[:1] != ["channels"] and names[:1] != ["channel"] and shape[-1:] in ([1], [3], [4])
            h, w = shape[:2] if hwc else shape[1:3]
            return np.zeros((0, h, w, _channels(ft)), np.uint8)
        try:
            dtype = np.dtype(ft["dtype"])
        except TypeError:
            dtype = np.dtype(object)
        return np.zeros((0, *([] if shape == [1] else shape)), dtype)

    def _video(self, feature: str, rows: np.ndarray) -> np.ndarray:
        times, eps = self._timestamps()[rows], self._ep_of_row[rows]
        cuts = np.flatnonzero(np.diff(eps)) + 1
        parts = []
        for part, ts in zip(np.split(np.arange(len(rows)), cuts), np.split(times, cuts), strict=True):
            file, start = self._episodes[int(eps[part[0]])].videos[feature]
            channels = _channels(self.features[feature])
            parts.append(
                self._videos.frames(self.root / file, start + ts, self.tolerance_s, channels, type(self).__name__)
            )
        return np.concatenate(parts)

    def _read(self, col: str, start: int, stop: int) -> np.ndarray:
        return self._take(col, np.arange(start, stop))

    def _read_strided(self, col: str, start: int, stop: int, step: int) -> np.ndarray:
        return self._take(col, np.arange(start, stop, step))  # only the frames a window keeps are decoded

    def get_row_data(self, idx: int | Sequence[int]) -> dict[str, np.ndarray]:
        """Row(s) ``idx`` of the loaded columns (``column_names``, as upstream), as numpy arrays."""
        rows = np.atleast_1d(np.asarray(idx, np.int64))
        if rows.size and (rows.min() < 0 or rows.max() >= self.num_rows):
            raise IndexError(f"{type(self).__name__} row {rows.tolist()} out of range for {self.num_rows} rows")
        out = {col: self._take(col, rows) for col in self.column_names}
        return {k: v[0] for k, v in out.items()} if np.ndim(idx) == 0 else out

    def __getstate__(self) -> dict[str, Any]:
        state = self.__dict__.copy()
        state["_videos"] = VideoFrames()  # a worker opens the videos itself
        return state

    def close(self) -> None:
        """Close the video files this process opened."""
        self._videos.close()

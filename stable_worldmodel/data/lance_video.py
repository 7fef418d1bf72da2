"""Lance video datasets (upstream main's ``lance_video`` format), read and written with ``pylance``
and PyAV.

A dataset is two Lance tables side by side::

    <name>.lance/           frames table: episode_idx, step_idx and every non-image column,
                            exactly as the ``lance`` format writes them (:mod:`.lance`)
    <name>_videos.lance/    one row per (episode, image column):
        episode_idx   int32
        video_key     string          the column's name (``.`` written ``_``, as in the frames table)
        video_bytes   large_binary    that episode's frames of that column as one MP4 (H.264,
                                      yuv420p, ``fps`` 10 by default), a Lance blob (field
                                      metadata ``lance-encoding:blob: true``, storage version 2.1)

Image columns are the uint8 ``(H, W, C)`` ones with C 1 or 3 (H.264 has no alpha: 4-channel
columns stay in the frames table, one PNG per row, as the ``lance`` format stores them). Odd
sizes are padded (edge pixels) to even ones when encoding and cropped back when decoding; the
``video_key`` field's metadata (key ``swm``) records each column's name, row shape and dtype.
Grey frames are encoded as RGB and read back as one channel. Keyframes every
:data:`KEYFRAME_INTERVAL` frames keep random access cheap. H.264 is lossy: frames come back close
to, not equal to, the ones written.

The reader decodes only the frames a window needs (seeking to the keyframe before them), keeps a
few open decoders per process, keyed (episode, column), and decodes each frame a batch needs once.
The writer commits the videos of a batch of episodes before their rows of the frames table (the
frames table says which episodes exist): a batch that fails leaves no video rows behind, and
video rows a crash left behind are ignored by the reader and removed by the next writer.
"""

from __future__ import annotations

import io
import json
import logging
import os
import shutil
from collections import OrderedDict
from collections.abc import Iterator, Mapping, Sequence
from fractions import Fraction
from pathlib import Path
from typing import Any

import numpy as np

from .._optional import require
from ..errors import ConfigError, DatasetFormatError, DatasetNotFoundError, check_int
from .dataset import missing_column
from .format import BatchedCommits, per_step_columns, validate_write_mode
from .lance import COMMIT_EPISODES, COMPACT_ABOVE, EPISODE_INDEX, META_KEY, LanceDataset, LanceWriter, _lance, _meta
from .writer import is_image_column

__all__ = ["LanceVideoDataset", "LanceVideoWriter", "lance_video_dirs", "videos_dir"]

logger = logging.getLogger(__name__)

VIDEO_KEY = "video_key"
VIDEO_BYTES = "video_bytes"
BLOB_META = {b"lance-encoding:blob": b"true"}
#: storage version of a new videos table (upstream's: what LanceDB writes; 2.1 keeps the blob metadata)
VIDEOS_STORAGE_VERSION = "2.1"
DEFAULT_FPS = 10
DEFAULT_CODEC = "libx264"
#: frames between two keyframes of the videos we write (a read decodes at most this many extra frames)
KEYFRAME_INTERVAL = 32
SUFFIX = "_videos"


def _av() -> Any:
    return require("av", purpose="lance_video datasets")


def videos_dir(frames: Path) -> Path:
    """The videos table next to the frames table ``frames`` (``x.lance`` -> ``x_videos.lance``)."""
    return frames.with_name(f"{frames.stem}{SUFFIX}.lance")


def _frames_tables(folder: Path) -> list[Path]:
    """The ``*.lance`` tables of ``folder`` that are not the videos table of another one."""
    tables = sorted(folder.glob("*.lance")) if folder.is_dir() else []
    names = {t.name for t in tables}
    return [t for t in tables if not (t.stem.endswith(SUFFIX) and f"{t.stem[: -len(SUFFIX)]}.lance" in names)]


def lance_video_dirs(path: str | os.PathLike, table_name: str | None, owner: str) -> tuple[Path, Path]:
    """The frames and videos tables that ``path`` (and ``table_name``) name: ``x.lance`` (and
    ``x_videos.lance`` beside it); ``<path>/<table_name>.lance``; the one frames table in the folder
    ``path``; or, for a folder holding none (a new dataset), ``<path>/<folder name>.lance`` (upstream's
    writer names the table after the folder)."""
    p = Path(path).expanduser()
    if table_name is not None:
        frames = p / f"{table_name}.lance"
    elif p.suffix.lower() == ".lance":
        frames = p
    else:
        tables = _frames_tables(p)
        if len(tables) > 1:
            raise ConfigError(
                f"{owner} requires a path ending in .lance, or table_name=, got {str(path)!r}, a folder holding "
                f"{len(tables)} tables: {', '.join(t.name for t in tables)}"
            )
        frames = tables[0] if tables else p / f"{p.name}.lance"
    return frames, videos_dir(frames)


def _rgb(frames: np.ndarray) -> np.ndarray:
    """``(L, H, W, 1|3)`` uint8 as ``(L, H', W', 3)``, H' and W' even (edge pixels repeated)."""
    if frames.shape[-1] == 1:
        frames = np.repeat(frames, 3, axis=-1)
    h, w = frames.shape[1:3]
    if h % 2 or w % 2:
        frames = np.pad(frames, ((0, 0), (0, h % 2), (0, w % 2), (0, 0)), mode="edge")
    return np.ascontiguousarray(frames)


def encode_mp4(frames: np.ndarray, fps: float, codec: str = DEFAULT_CODEC) -> bytes:
    """Frames ``(L, H, W, C)`` uint8 (C 1 or 3, L >= 1) as the bytes of one MP4 (yuv420p, a keyframe
    every :data:`KEYFRAME_INTERVAL` frames)."""
    av = _av()
    rgb = _rgb(frames)
    out = io.BytesIO()
    with av.open(out, mode="w", format="mp4") as container:
        stream = container.add_stream(codec, rate=Fraction(fps).limit_denominator(1001))
        stream.height, stream.width = rgb.shape[1:3]
        stream.pix_fmt = "yuv420p"
        stream.codec_context.gop_size = KEYFRAME_INTERVAL
        for frame in rgb:
            container.mux(stream.encode(av.VideoFrame.from_ndarray(frame, format="rgb24")))
        container.mux(stream.encode())
    return out.getvalue()


class _Decoder:
    """One episode's MP4 of one column, open: gives frames by index, decoding forward from where
    it stopped when the next frame wanted is close, else seeking to the keyframe before it."""

    def __init__(self, data: bytes, where: str, rgb: Any):
        self.where = where
        self.container = _av().open(io.BytesIO(data), mode="r")
        self._rgb = rgb  # the column's converter (a frame's own to_ndarray(format=...) sets one up each time)
        self.stream = self.container.streams.video[0]
        self.rate = Fraction(self.stream.average_rate or self.stream.guessed_rate or DEFAULT_FPS)
        self.time_base = Fraction(self.stream.time_base)
        self.start = self.stream.start_time or 0
        self._scale = float(self.time_base * self.rate)  # frames per pts tick
        self._frames: Iterator[tuple[int, Any]] | None = None
        self._next = 0  # index of the frame self._frames gives next

    def _index(self, frame: Any) -> int:
        return round((frame.pts - self.start) * self._scale)

    def _seek(self, index: int) -> None:
        target = self.start + int(index / self.rate / self.time_base)
        self.container.seek(target, stream=self.stream, backward=True, any_frame=False)
        self._frames = ((self._index(f), f) for f in self.container.decode(self.stream))
        self._next = -1  # not known until the first frame

    def frames(self, indices: Sequence[int]) -> list[np.ndarray]:
        """Frames ``indices`` (increasing) as ``(H', W', 3)`` uint8 arrays."""
        out = []
        for index in indices:
            if self._frames is None or not 0 <= index - self._next < KEYFRAME_INTERVAL:
                self._seek(index)
            retried = False
            while True:
                got, frame = next(self._frames, (None, None))
                if got is None:
                    self._frames = None
                    raise DatasetFormatError(f"LanceVideoDataset requires frame {index} in {self.where}, got fewer")
                self._next = got + 1
                if got == index:
                    out.append(self._rgb.reformat(frame, format="rgb24").to_ndarray())
                    break
                if got > index:  # the seek landed past the frame: decode from the first one
                    if retried:
                        raise DatasetFormatError(f"LanceVideoDataset cannot find frame {index} in {self.where}")
                    retried = True
                    self._seek(0)
        return out

    def close(self) -> None:
        self.container.close()


class LanceVideoDataset(LanceDataset):
    """A Lance video dataset (module docstring) as a :class:`~.dataset.Dataset`.

    ``path``: the frames table ``<name>.lance`` (its videos table ``<name>_videos.lance`` beside
    it), a folder holding the pair, or a folder and ``table_name``. ``video_keys``: the image
    columns to read from the videos table (default: all). ``decoder_cache_size``: open decoders
    kept per process. The other arguments are :class:`~.lance.LanceDataset`'s. Image columns
    come out as uint8 ``(H, W, C)`` rows (items: ``(T, C, H, W)`` tensors).
    """

    def __init__(
        self,
        path: str | os.PathLike | None = None,
        table_name: str | None = None,
        *,
        video_keys: Sequence[str] | None = None,
        decoder_cache_size: int = 16,
        **kwargs: Any,
    ):
        owner = type(self).__name__
        uri = kwargs.pop("uri", None)
        where = path if path is not None else uri
        if where is None:
            raise ConfigError(f"{owner} requires path= (a .lance frames table, or a folder holding one)")
        self._decoder_cache_size = check_int(owner, "decoder_cache_size", decoder_cache_size)
        frames, videos = lance_video_dirs(where, table_name, owner)
        if not frames.is_dir():
            raise DatasetNotFoundError(f"{owner} requires an existing .lance frames table, got {str(frames)!r}")
        if not videos.is_dir():
            hint = (
                " (the path names a videos table: pass the frames table beside it)"
                if frames.stem.endswith(SUFFIX)
                else ""
            )
            raise DatasetNotFoundError(
                f"{owner} requires the videos table {videos.name} beside {frames.name}, got none in {frames.parent}"
                f"{hint}; write the dataset with the 'lance_video' format (a plain Lance dataset reads with 'lance')"
            )
        _av()
        self.videos_path = videos
        vds = _lance().dataset(str(videos))
        needed = [EPISODE_INDEX, VIDEO_KEY, VIDEO_BYTES]
        if any(c not in vds.schema.names for c in needed):
            raise DatasetFormatError(f"{owner} requires the columns {needed} in {videos}, got {vds.schema.names}")
        self._videos_version = vds.version
        listing = vds.to_table(columns=[EPISODE_INDEX, VIDEO_KEY])
        row_eps = listing.column(0).to_numpy()
        row_keys = [str(k) for k in listing.column(1).to_pylist()]
        described = _meta(vds.schema.field(VIDEO_KEY)).get("columns", {})
        stored = list(described) + [k for k in dict.fromkeys(row_keys) if k not in described]
        names = {described.get(k, {}).get("name", k): k for k in stored}  # column name -> video_key
        if video_keys is not None:
            if isinstance(video_keys, str):
                video_keys = [video_keys]
            renamed = {k: n for n, k in names.items()}
            unknown = [k for k in video_keys if k not in names and k not in renamed]
            if unknown:
                raise missing_column(f"{owner} video_keys", unknown[0], list(names))
            wanted = {renamed.get(k, k) for k in video_keys}
            names = {n: k for n, k in names.items() if n in wanted}
        self._video_key = names
        self._video_shape = {
            n: tuple(described[k]["shape"]) for n, k in names.items() if described.get(k, {}).get("shape")
        }
        cached = list(kwargs.pop("keys_to_cache", None) or ())
        super().__init__(frames, None, keys_to_cache=[c for c in cached if c not in names], **kwargs)
        self.image_columns -= set(names)
        for n, shape in self._video_shape.items():
            self._meta[n] = {"name": n, "shape": list(shape), "dtype": "|u1"}
        # the episode numbers of the frames table, and where each episode's videos are (the last row wins)
        episode_column = kwargs.get("episode_index_column", EPISODE_INDEX)
        firsts = self._dataset().take(self.offsets, columns=[self._field.get(episode_column, episode_column)])
        self._episode_numbers = firsts.column(0).to_numpy().astype(np.int64)
        rows = {(int(e), k): i for i, (e, k) in enumerate(zip(row_eps.tolist(), row_keys, strict=True))}
        self._blob_rows: dict[str, np.ndarray] = {}
        for n, k in names.items():
            found = np.array([rows.get((int(e), k), -1) for e in self._episode_numbers], np.int64)
            if (found < 0).any():
                lost = self._episode_numbers[found < 0][:5].tolist()
                raise DatasetFormatError(
                    f"{owner} requires a video of column {n!r} for every episode, got none for episodes {lost} in "
                    f"{videos}"
                )
            self._blob_rows[n] = found
        self._vpid = os.getpid()
        self._videos_ds: Any = vds
        self._decoders: OrderedDict[tuple[int, str], _Decoder] = OrderedDict()
        self._converters: dict[str, Any] = {}  # column -> its frames' converter to RGB
        for col in cached:
            if col in names:
                self._cache[col] = self._frames_at(col, np.arange(self.num_rows))

    # the stored columns: the frames table's (LanceDataset sets them) and then the videos'
    @property
    def _columns(self) -> list[str]:
        return [*getattr(self, "_frame_columns", ()), *getattr(self, "_video_key", ())]

    @_columns.setter
    def _columns(self, value: list[str]) -> None:
        self._frame_columns = [c for c in value if c not in getattr(self, "_video_key", ())]

    @property
    def video_keys(self) -> list[str]:
        """The image columns read from the videos table."""
        return list(self._video_key)

    def __getstate__(self) -> dict[str, Any]:
        state = super().__getstate__()
        state["_videos_ds"] = None  # a worker opens the videos table and its decoders itself
        state["_decoders"], state["_converters"] = OrderedDict(), {}
        return state

    def _videos(self) -> Any:
        if self._videos_ds is None or self._vpid != os.getpid():
            self._videos_ds = _lance().dataset(str(self.videos_path), version=self._videos_version)
            self._decoders, self._converters, self._vpid = OrderedDict(), {}, os.getpid()
        return self._videos_ds

    def _decoder(self, ep: int, col: str) -> _Decoder:
        videos = self._videos()
        key = (ep, col)
        decoder = self._decoders.get(key)
        if decoder is not None:
            self._decoders.move_to_end(key)
            return decoder
        blob = videos.take_blobs(blob_column=VIDEO_BYTES, indices=[int(self._blob_rows[col][ep])])[0]
        try:
            data = blob.readall()
        finally:
            blob.close()
        rgb = self._converters.get(col)
        if rgb is None:
            rgb = self._converters[col] = _av().video.reformatter.VideoReformatter()
        decoder = _Decoder(data, f"the video of column {col!r}, episode {int(self._episode_numbers[ep])}", rgb)
        self._decoders[key] = decoder
        while len(self._decoders) > self._decoder_cache_size:
            self._decoders.popitem(last=False)[1].close()
        return decoder

    def _frames_at(self, col: str, rows: np.ndarray) -> np.ndarray:
        """Rows ``rows`` (global, any order) of the video column ``col`` as ``(n, H, W, C)`` uint8:
        each frame decoded once."""
        rows = np.asarray(rows, np.int64).reshape(-1)
        if col in self._cache:
            return self._cache[col][rows]
        shape = self._video_shape.get(col)
        if not rows.size:
            return np.zeros((0, *(shape or (0, 0, 3))), np.uint8)
        unique, inverse = np.unique(rows, return_inverse=True)
        eps = np.searchsorted(self.offsets, unique, side="right") - 1
        frames: list[np.ndarray] = []
        for ep in np.unique(eps).tolist():
            local = (unique[eps == ep] - self.offsets[ep]).tolist()
            frames.extend(self._decoder(ep, col).frames(local))
        out = np.stack(frames)
        if shape is not None:
            h, w, c = shape
            out = out[:, :h, :w, :c]
        return np.ascontiguousarray(out)[inverse]

    def _read(self, col: str, start: int, stop: int) -> np.ndarray:
        if col in self._video_key:
            return self._frames_at(col, np.arange(start, stop))
        return super()._read(col, start, stop)

    def _read_strided(self, col: str, start: int, stop: int, step: int) -> np.ndarray:
        if col in self._video_key:
            return self._frames_at(col, np.arange(start, stop, step))
        return super()._read_strided(col, start, stop, step)

    def _read_windows(self, col: str, starts: np.ndarray) -> np.ndarray:
        if col not in self._video_key:
            return super()._read_windows(col, starts)
        offsets = np.arange(0, self.span, self._row_step(col))
        rows = np.asarray(starts, np.int64)[:, None] + offsets
        got = self._frames_at(col, rows)
        return got.reshape(len(starts), len(offsets), *got.shape[1:])

    def close(self) -> None:
        """Close the open decoders."""
        for decoder in self._decoders.values():
            decoder.close()
        self._decoders.clear()


class LanceVideoWriter(BatchedCommits):
    """Append episodes to a Lance video dataset (module docstring).

    ``path``: the frames table ``<name>.lance``, a folder and ``table_name``, or a folder (the
    table is named after it, as upstream). ``fps`` and ``codec`` (an ffmpeg encoder) of the
    videos; ``mode`` as :data:`~.format.WRITE_MODES`. One commit of each table per
    :data:`~.lance.COMMIT_EPISODES` episodes.
    """

    commit_episodes = COMMIT_EPISODES

    def __init__(
        self,
        path: str | os.PathLike,
        table_name: str | None = None,
        *,
        fps: float = DEFAULT_FPS,
        codec: str = DEFAULT_CODEC,
        connect_kwargs: Mapping[str, Any] | None = None,
        mode: str = "append",
    ):
        owner = type(self).__name__
        self.mode = validate_write_mode(mode, owner)
        if isinstance(fps, bool) or not isinstance(fps, (int, float)) or not fps > 0:
            raise ConfigError(f"{owner} requires fps > 0, got {fps!r}")
        if not isinstance(codec, str) or not codec:
            raise ConfigError(f"{owner} requires codec to be an ffmpeg encoder name such as 'libx264', got {codec!r}")
        if connect_kwargs:
            raise ConfigError(
                f"{owner} writes local Lance directories only, got connect_kwargs={dict(connect_kwargs)!r}"
            )
        av = _av()
        try:
            av.codec.Codec(codec, "w")
        except Exception as exc:  # av raises its own UnknownCodecError
            raise ConfigError(f"{owner} requires an ffmpeg encoder PyAV knows, got codec={codec!r}") from exc
        self.fps, self.codec = fps, codec
        self.path, self.videos_path = lance_video_dirs(path, table_name, owner)
        self._lance = _lance()
        exists = self.path.exists() or self.videos_path.exists()
        if exists and mode == "error":
            raise FileExistsError(
                f"{owner}(mode='error') requires a new dataset, got {self.path}, which exists; "
                "pass mode='append' to extend it or mode='overwrite' to replace it"
            )
        if exists and mode == "overwrite":
            for table in (self.path, self.videos_path):
                if table.exists():
                    shutil.rmtree(table)
        if self.path.exists() != self.videos_path.exists():
            there, missing = (self.path, self.videos_path) if self.path.exists() else (self.videos_path, self.path)
            raise DatasetFormatError(
                f"{owner} appends to a dataset holding both tables, got {there.name} without {missing.name} in "
                f"{there.parent}; pass mode='overwrite' to replace it"
            )
        self._frames = LanceWriter(self.path, mode="append")
        self._videos: dict[str, dict[str, Any]] = {}  # column -> {"name": video_key, "shape", "dtype"}
        self._closed = False
        self._commits = 0
        self._planned = self.videos_path.exists()
        if self._planned:
            ds = self._lance.dataset(str(self.videos_path))
            described = _meta(ds.schema.field(VIDEO_KEY)).get("columns", {})
            found = dict.fromkeys(str(k) for k in ds.to_table(columns=[VIDEO_KEY]).column(0).to_pylist())
            for key in [*described, *(k for k in found if k not in described)]:
                meta = described.get(key, {})
                self._videos[meta.get("name", key)] = {**meta, "name": key}
            stale = f"{EPISODE_INDEX} >= {self.num_episodes}"
            if ds.count_rows(filter=stale):  # videos of episodes whose rows a crash did not commit
                logger.warning("%s: removing the videos of uncommitted episodes in %s", owner, self.videos_path)
                ds.delete(stale)
            self._schema = self._videos_schema(described or None)  # upstream's tables: no metadata

    @property
    def num_episodes(self) -> int:
        return self._frames.num_episodes

    @property
    def columns(self) -> list[str]:
        return [*self._frames.columns, *self._videos]

    @staticmethod
    def _videos_schema(columns: Mapping[str, Any] | None) -> Any:
        """The videos table's schema; ``columns``: video_key -> column name, row shape and dtype."""
        import pyarrow as pa

        described = None if columns is None else {META_KEY: json.dumps({"columns": dict(columns)})}
        return pa.schema(
            [
                pa.field(EPISODE_INDEX, pa.int32()),
                pa.field(VIDEO_KEY, pa.string(), metadata=described),
                pa.field(VIDEO_BYTES, pa.large_binary(), metadata=BLOB_META),
            ]
        )

    def _plan(self, rows: Mapping[str, np.ndarray]) -> None:
        """The image columns, from the first episode of a new dataset."""
        self._videos = {}
        for col, arr in rows.items():
            if col in (EPISODE_INDEX, "step_idx"):
                continue
            if arr.ndim == 4 and is_image_column(arr.shape[1:], arr.dtype) and arr.shape[-1] in (1, 3):
                self._videos[col] = {"name": col.replace(".", "_"), "shape": list(arr.shape[1:]), "dtype": "|u1"}
        if len(self._videos) == len(rows):
            raise DatasetFormatError(
                f"LanceVideoWriter requires a column besides the image columns ({', '.join(rows)}), got none: the "
                "frames table holds the steps of each episode"
            )
        self._schema = self._videos_schema({p["name"]: {**p, "name": c} for c, p in self._videos.items()})
        self._planned = True

    def _split(self, rows: dict[str, np.ndarray]) -> tuple[dict[str, np.ndarray], int]:
        """The image columns of an episode, taken out of ``rows``, and its length."""
        renamed = {c.replace(".", "_"): c for c in rows}
        images = {}
        for col, plan in self._videos.items():
            got = col if col in rows else renamed.get(plan["name"])
            if got is None:
                raise DatasetFormatError(
                    f"LanceVideoWriter requires the dataset's image columns {list(self._videos)}, got no {col!r}"
                )
            arr = rows.pop(got)
            shape = tuple(plan.get("shape") or arr.shape[1:])
            if arr.ndim != 4 or arr.shape[1:] != shape or arr.dtype != np.uint8 or shape[-1] not in (1, 3):
                raise DatasetFormatError(
                    f"LanceVideoWriter requires column {col!r} rows of uint8 {shape}, got {arr.dtype} {arr.shape[1:]}"
                )
            images[col] = arr
        lengths = {c: len(a) if a.ndim else None for c, a in {**images, **rows}.items()}
        if None in lengths.values() or len(set(lengths.values())) != 1:
            raise DatasetFormatError(
                f"LanceVideoWriter requires every column of an episode to have the same length, got {lengths}"
            )
        return images, next(iter(lengths.values()))

    def _commit(self, episodes: list[Mapping[str, Any]]) -> None:
        import pyarrow as pa

        if self._closed:
            raise DatasetFormatError(f"LanceVideoWriter requires an open writer, got a closed one for {self.path}")
        first = self.num_episodes
        eps, keys, blobs, steps = [], [], [], []
        for i, episode in enumerate(episodes):
            rows = {str(c): np.asarray(v) for c, v in per_step_columns(episode, "LanceVideoWriter").items()}
            if not self._planned:
                self._plan(rows)
            images, n = self._split(rows)
            for col, frames in images.items():
                if n:
                    eps.append(first + i)
                    keys.append(self._videos[col]["name"])
                    blobs.append(encode_mp4(frames, self.fps, self.codec))
            steps.append(rows)
        table = pa.table(
            [pa.array(eps, pa.int32()), pa.array(keys, pa.string()), pa.array(blobs, pa.large_binary())],
            schema=self._schema,
        )
        if not self.videos_path.exists():
            self._lance.write_dataset(
                table, str(self.videos_path), schema=self._schema, data_storage_version=VIDEOS_STORAGE_VERSION
            )
        elif len(table):
            self._lance.write_dataset(table, str(self.videos_path), schema=self._schema, mode="append")
        try:
            self._frames.write_episodes(steps)  # at most COMMIT_EPISODES: one commit
        except BaseException:
            if len(table):  # the rows of these episodes were not written: neither are their videos
                self._lance.dataset(str(self.videos_path)).delete(f"{EPISODE_INDEX} >= {first}")
            raise
        self._commits += 1

    def close(self) -> None:
        """Compact the small fragments per-batch commits leave (every commit is on disk already)."""
        if self._closed:
            return
        self._closed = True
        self._frames.close()
        if self._commits and self.videos_path.exists():
            ds = self._lance.dataset(str(self.videos_path))
            if len(ds.get_fragments()) > COMPACT_ABOVE:
                ds.optimize.compact_files()

"""Lance datasets (upstream 0.1.1's default collect format), read and written with ``pylance``.

A dataset is a Lance directory ``<name>.lance`` (what upstream's LanceDB table holds; its
reader opens the ones we write and ours the ones it writes). One row per step, episodes
contiguous and in order::

    episode_idx   int32                    episode of the row (non-decreasing)
    step_idx      int32                    step of the row in its episode
    pixels        binary                   one encoded frame per row (JPEG, quality 95, as upstream;
                                           PNG for 4-channel frames): every uint8 (H, W, C) column
    <column>      fixed_size_list<T>[d]    every other column, rows flattened (upstream writes
                                           T = float32; we keep the column's dtype)

Names with ``.`` are written with ``_`` (Lance takes ``.`` as a path into a struct). We also
store, per field, the original name, row shape and dtype in the field metadata (key ``swm``),
so our reader gives columns back as they were written; upstream's reader ignores it and reads
``(N, d)`` arrays. A column a recording holds under an index name (our ``step_idx``) is not
written twice: the index column holds it, and the metadata says to read it back as a column.

Each ``write_episodes`` call (each ``write_episode``) is one Lance commit: a crash leaves every
earlier commit readable, as Lance versions are atomic. :meth:`LanceWriter.close` compacts the
small fragments that per-episode commits leave.
"""

from __future__ import annotations

import io
import json
import logging
import os
import shutil
import sys
from collections.abc import Callable, Collection, Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from .._optional import require
from ..errors import ConfigError, DatasetFormatError, DatasetNotFoundError
from .dataset import Dataset
from .format import BatchedCommits, per_step_columns, validate_write_mode
from .writer import is_image_column

__all__ = ["LanceDataset", "LanceWriter", "lance_dir"]

logger = logging.getLogger(__name__)

EPISODE_INDEX = "episode_idx"
STEP_INDEX = "step_idx"
META_KEY = b"swm"
JPEG_QUALITY = 95
#: episodes per commit when ``write_episodes`` is given many
COMMIT_EPISODES = 32
#: more fragments than this are compacted when a writer closes
COMPACT_ABOVE = 16


def _lance() -> Any:
    return require("lance", "lance", "Lance datasets")


def lance_dir(path: str | os.PathLike, table_name: str | None, owner: str) -> Path:
    """The ``.lance`` directory that ``path`` (and ``table_name``, upstream's LanceDB table)
    names: ``x.lance``; ``<path>/<table_name>.lance``; or the one ``*.lance`` inside ``path``."""
    p = Path(path).expanduser()
    if table_name is not None:
        return p / f"{table_name}.lance"
    if p.suffix.lower() == ".lance":
        return p
    tables = sorted(p.glob("*.lance")) if p.is_dir() else []
    if len(tables) == 1:
        return tables[0]
    raise ConfigError(
        f"{owner} requires a path ending in .lance, or table_name=, got {str(path)!r}"
        + (f", a folder holding {len(tables)} tables: {', '.join(t.name for t in tables)}" if tables else "")
    )


_SPAWNING: list[bool] = []


def fork_safe_workers() -> None:
    """Make new processes start with ``spawn`` (once per process; Linux, where ``fork`` is the
    default): lance is not fork-safe, and a forked DataLoader worker reading a Lance dataset
    crashes. Upstream 0.1.1 does the same when it opens one. A start method the user set to
    ``forkserver`` or ``spawn`` is kept."""
    import multiprocessing as mp

    if _SPAWNING or not sys.platform.startswith("linux"):
        return
    _SPAWNING.append(True)
    current = mp.get_start_method(allow_none=True)
    if current in (None, "fork"):
        try:
            mp.set_start_method("spawn", force=True)
            logger.info("Lance datasets are not fork-safe: new processes now start with 'spawn' (was %s)", current)
        except RuntimeError as exc:  # pragma: no cover - set_start_method refuses while a context is in use
            logger.warning("Lance datasets are not fork-safe, and the start method stays %r: %s", current, exc)


def _meta(field: Any) -> dict[str, Any]:
    raw = (field.metadata or {}).get(META_KEY)
    return json.loads(raw) if raw else {}


def _encode(frame: np.ndarray, quality: int) -> bytes:
    from PIL import Image

    img = Image.fromarray(frame[..., 0] if frame.shape[-1] == 1 else frame)
    out = io.BytesIO()
    if frame.shape[-1] == 4:
        img.save(out, format="PNG")  # JPEG has no alpha
    else:
        img.save(out, format="JPEG", quality=quality)
    return out.getvalue()


def _decode(blob: bytes, channels: int | None) -> np.ndarray:
    """One encoded frame as uint8 ``(H, W, C)`` (``C`` 3 unless the writer recorded 1 or 4): OpenCV
    decodes JPEG ~2.5x faster than PIL; PIL is the fallback for what OpenCV cannot read."""
    import cv2

    flag = cv2.IMREAD_GRAYSCALE if channels == 1 else cv2.IMREAD_UNCHANGED if channels == 4 else cv2.IMREAD_COLOR
    frame = cv2.imdecode(np.frombuffer(blob, np.uint8), flag)
    if frame is None:
        from PIL import Image

        with Image.open(io.BytesIO(blob)) as img:
            if channels == 1:
                return np.asarray(img.convert("L"))[..., None]
            return np.asarray(img.convert("RGBA" if channels == 4 else "RGB"))
    if channels == 1:
        return frame[..., None]
    if frame.ndim == 2:  # a grey JPEG read in colour mode by a reader that did not record channels
        return np.repeat(frame[..., None], 3, axis=-1)
    return cv2.cvtColor(frame, cv2.COLOR_BGRA2RGBA if frame.shape[-1] == 4 else cv2.COLOR_BGR2RGB)


class LanceDataset(Dataset):
    """A Lance dataset (module docstring) as a :class:`~.dataset.Dataset`.

    ``path``: the ``.lance`` directory (or a folder holding one, or a LanceDB folder with
    ``table_name``). The other arguments are every dataset's; ``keys_to_cache`` reads those
    columns into memory once; ``image_columns`` overrides which binary columns are frames.
    """

    def __init__(
        self,
        path: str | os.PathLike | None = None,
        table_name: str | None = None,
        *,
        uri: str | os.PathLike | None = None,
        frameskip: int = 1,
        num_steps: int = 1,
        transform: Callable[[dict], dict] | None = None,
        keys_to_load: Sequence[str] | None = None,
        keys_to_cache: Sequence[str] | None = None,
        image_columns: Collection[str] | None = None,
        episode_index_column: str = EPISODE_INDEX,
        step_index_column: str = STEP_INDEX,
        dense_columns: Collection[str] | str | None = None,
        connect_kwargs: Mapping[str, Any] | None = None,
    ):
        owner = type(self).__name__
        super().__init__(
            frameskip=frameskip,
            num_steps=num_steps,
            transform=transform,
            keys_to_load=keys_to_load,
            dense_columns=dense_columns,
        )
        where = path if path is not None else uri
        if where is None:
            raise ConfigError(f"{owner} requires path= (a .lance directory)")
        if connect_kwargs:
            raise ConfigError(
                f"{owner} reads local Lance directories only, got connect_kwargs={dict(connect_kwargs)!r}"
            )
        self.path = lance_dir(where, table_name, owner)
        if not self.path.is_dir():
            raise DatasetNotFoundError(f"{owner} requires an existing .lance directory, got {str(self.path)!r}")
        self.name = self.path.stem
        fork_safe_workers()
        self._pid = os.getpid()
        self._ds = _lance().dataset(str(self.path))
        schema = self._ds.schema
        index = (episode_index_column, step_index_column)
        missing = [c for c in index if c not in schema.names]
        if missing:
            raise DatasetFormatError(
                f"{owner} requires the index columns {list(index)} in {self.path}, got columns {schema.names}"
            )
        # columns go by the names they were written with (our metadata: "variation.color"), upstream's
        # files by their field names ("variation_color"); _field maps one to the other
        self._field = {_meta(f).get("name", f.name): f.name for f in schema}
        self._fields = {name: schema.field(field) for name, field in self._field.items()}
        self._meta = {name: _meta(self._fields[name]) for name in self._field}
        self._index = index
        # a column our writer stored in an index column (the recording's own step_idx) reads back as a column
        import pyarrow as pa

        self._columns = [n for n, field in self._field.items() if field not in index or self._meta[n].get("column")]

        binary = {n for n, f in self._fields.items() if pa.types.is_binary(f.type) or pa.types.is_large_binary(f.type)}
        self.image_columns = set(binary if image_columns is None else image_columns) & set(self._columns)
        ep = self._ds.to_table(columns=[episode_index_column]).column(0).to_numpy()
        if len(ep) > 1 and (np.diff(ep) < 0).any():
            raise DatasetFormatError(
                f"{owner} requires episode-contiguous rows (episode_idx never decreasing), got {self.path}; "
                "rewrite it with swm convert"
            )
        starts = np.flatnonzero(np.diff(ep) != 0) + 1 if len(ep) else np.zeros(0, np.int64)
        offsets = np.concatenate([[0], starts]).astype(np.int64) if len(ep) else np.zeros(0, np.int64)
        self.lengths = np.diff(np.concatenate([offsets, [len(ep)]])).astype(np.int64)
        self.offsets = offsets
        if keys_to_load is not None:
            self.check_keys(self.column_names)
        self._cache: dict[str, np.ndarray] = {}
        for col in keys_to_cache or ():
            self.check_keys([col])
            self._cache[col] = self._convert(col, self._table(col, None).column(0))

    def _dataset(self) -> Any:
        if self._ds is None or self._pid != os.getpid():  # unpickled in a worker (or forked): its own handle
            self._ds, self._pid = _lance().dataset(str(self.path)), os.getpid()
        return self._ds

    def __getstate__(self) -> dict[str, Any]:
        state = self.__dict__.copy()
        state["_ds"] = None  # a worker opens the dataset itself
        return state

    def _table(self, col: str, rows: np.ndarray | None) -> Any:
        """Column ``col`` (its rows ``rows``, or all) as an Arrow table."""
        ds, columns = self._dataset(), [self._field[col]]
        if rows is None:
            return ds.to_table(columns=columns)
        return ds.take(np.asarray(rows, np.int64), columns=columns)

    def _convert(self, col: str, values: Any) -> np.ndarray:
        """Rows ``(n, ...)`` of ``col`` from its Arrow column: frames decoded, lists reshaped to
        the row shape our writer recorded (``(n, d)`` for upstream's files)."""
        import pyarrow as pa

        meta = self._meta.get(col, {})
        shape = tuple(meta.get("shape", ()))
        n = len(values)
        if col in self.image_columns:
            channels = shape[-1] if shape else None
            frames = [_decode(b, channels) for b in values.to_pylist()]
            return np.stack(frames) if frames else np.zeros((0, *(shape or (0, 0, 3))), np.uint8)
        if isinstance(values, pa.ChunkedArray):
            values = values.combine_chunks()
        if pa.types.is_fixed_size_list(values.type):
            flat = values.flatten().to_numpy(zero_copy_only=False)
            out = flat.reshape(n, *shape) if meta else flat.reshape(n, values.type.list_size)
        else:
            out = values.to_numpy(zero_copy_only=False)
        dtype = meta.get("dtype")
        return out.astype(dtype, copy=False) if dtype else out

    def _read(self, col: str, start: int, stop: int) -> np.ndarray:
        if col in self._cache:
            return self._cache[col][start:stop]
        return self._convert(col, self._table(col, np.arange(start, stop)).column(0))

    def _read_windows(self, col: str, starts: np.ndarray) -> np.ndarray:
        offsets = np.arange(0, self.span, self._row_step(col))
        rows = (np.asarray(starts, np.int64)[:, None] + offsets).ravel()
        if col in self._cache:
            got = self._cache[col][rows]
        else:
            unique, inverse = np.unique(rows, return_inverse=True)  # one take for the whole batch
            got = self._convert(col, self._table(col, unique).column(0))[inverse]
        return got.reshape(len(starts), len(offsets), *got.shape[1:])

    def column_shape(self, col: str) -> tuple[tuple[int, ...], np.dtype]:
        meta = self._meta.get(col, {})
        if meta.get("shape") is not None and meta.get("dtype"):
            self.check_keys([col])
            return tuple(meta["shape"]), np.dtype(meta["dtype"])
        return super().column_shape(col)

    def close(self) -> None:
        """Nothing to release: Lance opens files per read."""


class LanceWriter(BatchedCommits):
    """Append episodes to a Lance dataset (module docstring).

    ``path``: the ``.lance`` directory (or a folder and ``table_name``, as upstream's LanceDB
    writer). ``mode`` as :data:`~.format.WRITE_MODES` (upstream's older ``overwrite=True`` is
    ``mode="overwrite"``). ``jpeg_quality``: of the encoded frames (upstream: 95).
    """

    commit_episodes = COMMIT_EPISODES

    def __init__(
        self,
        path: str | os.PathLike,
        table_name: str | None = None,
        *,
        mode: str = "append",
        jpeg_quality: int = JPEG_QUALITY,
        overwrite: bool | None = None,
        connect_kwargs: Mapping[str, Any] | None = None,
    ):
        owner = type(self).__name__
        if overwrite is not None:
            mode = "overwrite" if overwrite else mode
        self.mode = validate_write_mode(mode, owner)
        if not isinstance(jpeg_quality, int) or not 1 <= jpeg_quality <= 100:
            raise ConfigError(f"{owner} requires 1 <= jpeg_quality <= 100, got {jpeg_quality!r}")
        if connect_kwargs:
            raise ConfigError(
                f"{owner} writes local Lance directories only, got connect_kwargs={dict(connect_kwargs)!r}"
            )
        self.path = lance_dir(path, table_name, owner)
        self.jpeg_quality = jpeg_quality
        self._lance = _lance()
        if self.path.exists() and mode == "error":
            raise FileExistsError(
                f"{owner}(mode='error') requires a new dataset, got {self.path}, which exists; "
                "pass mode='append' to extend it or mode='overwrite' to replace it"
            )
        if self.path.exists() and mode == "overwrite":
            shutil.rmtree(self.path)
        self._schema = None
        self._layout: dict[str, dict[str, Any]] = {}  # column -> {"name", "shape", "dtype", "image"}
        self._dropped: set[str] = set()  # non-numeric columns of the first episode (not stored)
        self.num_episodes = 0
        self._commits = 0
        self._closed = False
        if self.path.exists():
            ds = self._lance.dataset(str(self.path))
            self._schema = ds.schema
            ep = ds.to_table(columns=[EPISODE_INDEX]).column(0).to_numpy()
            self.num_episodes = int(ep.max()) + 1 if len(ep) else 0
            for f in ds.schema:
                meta = _meta(f)
                if f.name in (EPISODE_INDEX, STEP_INDEX) and not meta.get("column"):
                    continue
                import pyarrow as pa

                image = pa.types.is_binary(f.type) or pa.types.is_large_binary(f.type)
                text = pa.types.is_string(f.type) or pa.types.is_large_string(f.type)
                index = f.name in (EPISODE_INDEX, STEP_INDEX)  # a recording's own step_idx, held by the index
                self._layout[meta.get("name", f.name)] = {
                    **meta,
                    "name": f.name,
                    "image": image,
                    "text": text,
                    "index": index,
                }

    @property
    def columns(self) -> list[str]:
        return list(self._layout)

    def _commit(self, episodes: list[Mapping[str, Any]]) -> None:
        import pyarrow as pa

        if self._closed:
            raise DatasetFormatError(f"LanceWriter requires an open writer, got a closed one for {self.path}")
        tables = []
        for episode in episodes:
            rows = {str(c): np.asarray(v) for c, v in per_step_columns(episode, "LanceWriter").items()}
            if not self._layout:
                self._plan(rows)
            tables.append(self._episode_table(rows, self.num_episodes + len(tables)))
        table = pa.concat_tables(tables)
        mode = "append" if self.path.exists() else "create"
        self._lance.write_dataset(table, str(self.path), schema=self._schema, mode=mode)
        self.num_episodes += len(tables)
        self._commits += 1

    def _plan(self, rows: Mapping[str, np.ndarray]) -> None:
        """The schema, from the first episode (module docstring)."""
        import pyarrow as pa

        fields = [pa.field(EPISODE_INDEX, pa.int32()), pa.field(STEP_INDEX, pa.int32())]
        dropped = [c for c, a in rows.items() if a.dtype.kind not in "biufUS"]
        if dropped:  # upstream drops them too
            logger.warning("LanceWriter stores numeric and text columns only: dropped %s", ", ".join(dropped))
            self._dropped = set(dropped)
        for col, arr in rows.items():
            if col in self._dropped:
                continue
            meta = {"name": col, "shape": list(arr.shape[1:]), "dtype": arr.dtype.str}
            if col in (EPISODE_INDEX, STEP_INDEX):
                self._layout[col] = {**meta, "image": False, "index": True}
                i = 0 if col == EPISODE_INDEX else 1
                fields[i] = fields[i].with_metadata({META_KEY: json.dumps({**meta, "column": True})})
                continue
            name = col.replace(".", "_")
            image = is_image_column(arr.shape[1:], arr.dtype)
            text = arr.dtype.kind in "US"
            if text:
                meta = {"name": col, "text": True}
            self._layout[col] = {**meta, "name": name, "image": image}
            width = int(np.prod(arr.shape[1:], dtype=np.int64))
            if text:
                kind = pa.string()
            else:
                kind = pa.binary() if image else pa.list_(pa.from_numpy_dtype(arr.dtype), max(width, 1))
            fields.append(pa.field(name, kind, metadata={META_KEY: json.dumps(meta)}))
        self._schema = pa.schema(fields)

    def _episode_table(self, rows: Mapping[str, np.ndarray], ep: int) -> Any:
        import pyarrow as pa

        rows = {c: a for c, a in rows.items() if c not in self._dropped}
        for col in (EPISODE_INDEX, STEP_INDEX):  # a dataset whose index is not also a column (upstream's files)
            if col in rows and col not in self._layout:
                self._check_index(col, rows.pop(col), ep)
        dotted = {c.replace(".", "_"): c for c in self._layout}  # upstream's files know the renamed names only
        rows = {c if c in self._layout else dotted.get(c.replace(".", "_"), c): a for c, a in rows.items()}
        lengths = {c: len(a) if a.ndim else None for c, a in rows.items()}
        if set(rows) != set(self._layout):
            missing, extra = sorted(set(self._layout) - set(rows)), sorted(set(rows) - set(self._layout))
            raise DatasetFormatError(
                f"LanceWriter requires the dataset's columns, got missing={missing}, extra={extra}"
            )
        if None in lengths.values() or len(set(lengths.values())) != 1:
            raise DatasetFormatError(
                f"LanceWriter requires every column of an episode to have the same length, got {lengths}"
            )
        n = next(iter(lengths.values()))
        columns: dict[str, Any] = {
            EPISODE_INDEX: pa.array(np.full(n, ep, np.int32)),
            STEP_INDEX: pa.array(np.arange(n, dtype=np.int32)),
        }
        for col, arr in rows.items():
            plan = self._layout[col]
            shape = tuple(plan.get("shape", arr.shape[1:]))
            if tuple(arr.shape[1:]) != shape:
                raise DatasetFormatError(
                    f"LanceWriter requires column {col!r} rows of shape {shape}, got {arr.shape[1:]}"
                )
            if plan.get("index"):
                self._check_index(col, arr, ep)
                continue
            if plan["image"]:
                columns[plan["name"]] = pa.array([_encode(f, self.jpeg_quality) for f in arr], pa.binary())
                continue
            if plan.get("text"):
                texts = [x.decode() if isinstance(x, bytes) else str(x) for x in arr.reshape(n).tolist()]
                columns[plan["name"]] = pa.array(texts, pa.string())
                continue
            dtype = np.dtype(plan.get("dtype", "<f4"))
            flat = np.ascontiguousarray(arr, dtype=dtype).reshape(-1)
            width = max(int(np.prod(shape, dtype=np.int64)), 1)
            columns[plan["name"]] = pa.FixedSizeListArray.from_arrays(pa.array(flat), width)
        return pa.table([columns[f.name] for f in self._schema], schema=self._schema)

    @staticmethod
    def _check_index(col: str, arr: np.ndarray, ep: int) -> None:
        """A column named as an index column is stored by it: it must hold what the index holds."""
        n = len(arr)
        expected = np.arange(n) if col == STEP_INDEX else np.full(n, ep)
        if arr.shape != (n,) or not np.array_equal(arr, expected):
            wanted = "0, 1, ..., L-1" if col == STEP_INDEX else "the episode number"
            raise DatasetFormatError(
                f"LanceWriter stores column {col!r} in its index column, which requires {wanted}; "
                f"got {arr.reshape(-1)[:5]}..."
            )

    def close(self) -> None:
        """Compact the small fragments per-episode commits leave (every commit is on disk already)."""
        if self._closed:
            return
        self._closed = True
        if self._commits and self.path.exists():
            ds = self._lance.dataset(str(self.path))
            if len(ds.get_fragments()) > COMPACT_ABOVE:
                ds.optimize.compact_files()

"""What a dataset *folder* holds: the two layouts that folder and video datasets read.

The released layout (0.0.3 reads and 0.1.1 writes it; our writers write it)::

    <root>/
      ep_len.npz                    arr_0 (E,) int    rows of each episode
      ep_offset.npz                 arr_0 (E,) int    first row of each episode
      <col>.npz                     arr_0 (N, ...)    one file per numeric column
      <key>/ep_{e}_step_{s}.jpeg    one image per step of episode e (folder / image datasets; .jpg read too)
      <key>/ep_{e}.mp4              one video per episode (video datasets)
      <key>/frames.json             ours, optional: {"shape": [H, W, C]} of the frames in the MP4s
                                    (H.264 needs even sizes: odd ones are padded, then cropped back)

The root holds nothing else: 0.0.3 takes every entry of it for a column.

Our earlier layout (read only)::

    <root>/
      meta.json                     {"format": "folder" | "video", "images": {key: [H, W, C]}, "fps": 30}
      columns.npz                   every numeric column (N, ...) plus ep_len (E,) and ep_offset (E,)
      <key>/{row:09d}.jpg           one JPEG per row (row = global row number)
      <key>/episode_{e:06d}.mp4     one video per episode
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from .. import keys
from ..errors import DatasetFormatError

EP_LEN_FILE = f"{keys.EP_LEN}.npz"
EP_OFFSET_FILE = f"{keys.EP_OFFSET}.npz"
FRAMES_FILE = "frames.json"
META = "meta.json"
COLUMNS = "columns.npz"
IMAGE_SUFFIXES = (".jpeg", ".jpg")


def _npz(path: Path) -> np.ndarray:
    with np.load(path) as npz:
        if "arr_0" not in npz.files:
            raise DatasetFormatError(f"dataset folder requires {path.name} to hold an array 'arr_0', got {npz.files}")
        return npz["arr_0"]


class Layout:
    """Episode index, numeric columns and media files of a dataset folder."""

    name = ""

    def __init__(self, root: Path):
        self.root = root
        self.lengths = np.zeros(0, np.int64)
        self.offsets = np.zeros(0, np.int64)
        self.numeric: list[str] = []
        self.media: list[str] = []  # sub-folders of images or videos
        self.shapes: dict[str, tuple[int, int, int]] = {}  # media frame shapes, where the layout records them

    def load(self, col: str) -> np.ndarray:
        raise NotImplementedError("load(col) -> (N, ...) rows of a numeric column")

    def image_file(self, col: str, ep: int, step: int, row: int) -> Path:
        raise NotImplementedError("image_file(col, ep, step, row) -> path of one image")

    def video_file(self, col: str, ep: int) -> Path:
        raise NotImplementedError("video_file(col, ep) -> path of one episode's video")


class ReleasedLayout(Layout):
    """``ep_len.npz`` + one ``.npz`` per column + ``<key>/ep_*`` media (the module docstring)."""

    name = "released"

    def __init__(self, root: Path):
        super().__init__(root)
        self.lengths = _npz(root / EP_LEN_FILE).astype(np.int64)
        offsets = root / EP_OFFSET_FILE
        self.offsets = (
            _npz(offsets).astype(np.int64)
            if offsets.is_file()
            else np.concatenate([[0], np.cumsum(self.lengths)[:-1]]).astype(np.int64)
        )
        stems = (keys.EP_LEN, keys.EP_OFFSET)
        self.numeric = sorted(p.stem for p in root.glob("*.npz") if p.stem not in stems)
        self.media = sorted(p.name for p in root.iterdir() if p.is_dir() and not p.name.startswith("."))
        for col in self.media:
            frames = root / col / FRAMES_FILE
            if frames.is_file():
                self.shapes[col] = tuple(json.loads(frames.read_text())["shape"])

    def load(self, col: str) -> np.ndarray:
        return _npz(self.root / f"{col}.npz")

    def image_file(self, col: str, ep: int, step: int, row: int) -> Path:
        base = self.root / col / f"ep_{ep}_step_{step}"
        for suffix in IMAGE_SUFFIXES:
            if base.with_suffix(suffix).is_file():
                return base.with_suffix(suffix)
        return base.with_suffix(IMAGE_SUFFIXES[0])

    def video_file(self, col: str, ep: int) -> Path:
        return self.root / col / f"ep_{ep}.mp4"


class MetaLayout(Layout):
    """``meta.json`` + ``columns.npz`` (our earlier layout, read only)."""

    name = "meta"

    def __init__(self, root: Path):
        super().__init__(root)
        self.meta = json.loads((root / META).read_text())
        with np.load(root / COLUMNS) as npz:
            self._arrays = {k: npz[k] for k in npz.files}
        self.lengths = self._arrays.pop(keys.EP_LEN).astype(np.int64)
        self.offsets = self._arrays.pop(keys.EP_OFFSET).astype(np.int64)
        self.numeric = sorted(self._arrays)
        self.shapes = {k: tuple(v) for k, v in self.meta.get("images", {}).items()}
        self.media = sorted(self.shapes)

    @property
    def kind(self) -> str | None:
        return self.meta.get("format")

    def load(self, col: str) -> np.ndarray:
        return self._arrays[col]

    def image_file(self, col: str, ep: int, step: int, row: int) -> Path:
        return self.root / col / f"{row:09d}.jpg"

    def video_file(self, col: str, ep: int) -> Path:
        return self.root / col / f"episode_{ep:06d}.mp4"


def meta_kind(root: Path) -> str | None:
    """The ``format`` recorded in ``root/meta.json`` (our earlier layout), or None."""
    meta = root / META
    if not meta.is_file():
        return None
    try:
        return json.loads(meta.read_text()).get("format")
    except (OSError, ValueError, AttributeError):
        return None


def has_videos(root: Path) -> bool:
    """Some sub-folder of ``root`` holds an ``ep_<e>.mp4``."""
    return any(next(sub.glob("ep_*.mp4"), None) is not None for sub in root.iterdir() if sub.is_dir())


def open_layout(root: Path, owner: str) -> Layout:
    """The layout of dataset folder ``root``; a missing folder raises FileNotFoundError."""
    if (root / META).is_file():
        return MetaLayout(root)
    if (root / EP_LEN_FILE).is_file():
        return ReleasedLayout(root)
    if not root.is_dir():
        raise FileNotFoundError(f"{owner} requires an existing dataset folder, got {str(root)!r}, which does not exist")
    raise FileNotFoundError(
        f"{owner} requires a dataset folder holding {EP_LEN_FILE} (or our earlier {META}), got {str(root)!r}: "
        f"{EP_LEN_FILE} not found"
    )

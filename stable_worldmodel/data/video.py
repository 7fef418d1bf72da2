"""MP4 writing (H.264, yuv420p, even sizes: plays in browsers) and dataset replays."""

from __future__ import annotations

import logging
import os
from collections.abc import Iterable, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from .. import keys
from ..errors import ConfigError, UnknownNameError

logger = logging.getLogger(__name__)

__all__ = ["write_mp4", "hstack_frames", "vstack_frames", "record_video_from_dataset", "preview_dataset"]


def _even(frame: np.ndarray) -> np.ndarray:
    """Pad ``(H, W, 3)`` with black to even H and W (yuv420p needs them)."""
    h, w = frame.shape[:2]
    if h % 2 == 0 and w % 2 == 0:
        return frame
    return np.pad(frame, ((0, h % 2), (0, w % 2), (0, 0)))


def _rgb(frame: Any) -> np.ndarray:
    arr = np.asarray(frame)
    if arr.ndim == 3 and arr.shape[0] in (1, 3) and arr.shape[-1] not in (1, 3):  # (C, H, W)
        arr = arr.transpose(1, 2, 0)
    if arr.ndim == 2:
        arr = arr[..., None]
    if arr.shape[-1] == 1:
        arr = np.repeat(arr, 3, axis=-1)
    if arr.dtype != np.uint8:
        raise ConfigError(f"write_mp4 requires uint8 frames, got {arr.dtype}")
    return arr[..., :3]


def hstack_frames(frames: Sequence[np.ndarray]) -> np.ndarray:
    """Frames ``(H_i, W_i, 3)`` side by side (shorter ones padded at the bottom)."""
    frames = [_rgb(f) for f in frames]
    h = max(f.shape[0] for f in frames)
    return np.concatenate([np.pad(f, ((0, h - f.shape[0]), (0, 0), (0, 0))) for f in frames], axis=1)


def vstack_frames(frames: Sequence[np.ndarray]) -> np.ndarray:
    """Frames ``(H_i, W_i, 3)`` one above the other (narrower ones padded on the right)."""
    frames = [_rgb(f) for f in frames]
    w = max(f.shape[1] for f in frames)
    return np.concatenate([np.pad(f, ((0, 0), (0, w - f.shape[1]), (0, 0))) for f in frames], axis=0)


def write_mp4(
    path: str | os.PathLike, frames: Iterable[np.ndarray], fps: int = 30, quality: float = 5, codec: str = "libx264"
) -> Path:
    """Write ``frames`` (each ``(H, W, 3)`` uint8, same size) as an MP4 at ``path`` (``codec``: an
    ffmpeg encoder, H.264 by default).

    ``quality`` goes from 0 (smallest) to 10 (nearly lossless).
    """
    import imageio.v2 as imageio

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    writer = imageio.get_writer(
        str(path),
        fps=fps,
        codec=codec,
        quality=quality,
        pixelformat="yuv420p",
        macro_block_size=1,
        ffmpeg_log_level="error",
    )
    try:
        count = 0
        for frame in frames:
            writer.append_data(_even(_rgb(frame)))
            count += 1
    finally:
        writer.close()
    if count == 0:
        path.unlink(missing_ok=True)
        raise ConfigError(f"write_mp4 requires at least one frame, got none for {path}")
    return path


def record_video_from_dataset(
    video_path: str | os.PathLike,
    dataset: Any,
    episode_idx: int | Sequence[int],
    max_steps: int = 500,
    fps: int = 30,
    viewname: str | Sequence[str] = keys.PIXELS,
    cache_dir: str | os.PathLike | None = None,
) -> list[Path]:
    """Write ``<video_path>/episode_<idx>.mp4`` for each episode of ``dataset``.

    ``dataset`` is any dataset with ``column_names`` and ``load_episode`` (images ``(L, C, H, W)``
    or ``(L, H, W, C)``), or the name of a dataset in ``cache_dir``. The views named by
    ``viewname`` are placed side by side; a ``goal`` column (when not already a view) goes
    below them. At most ``max_steps`` frames per episode. Returns the written paths.
    """
    if isinstance(dataset, (str, os.PathLike)):
        from .utils import load_dataset

        dataset = load_dataset(dataset, cache_dir=cache_dir)
    views = [viewname] if isinstance(viewname, str) else list(viewname)
    columns = list(dataset.column_names)
    missing = [v for v in views if v not in columns]
    if missing:
        raise UnknownNameError(
            f"record_video_from_dataset view {missing[0]!r} not found in the dataset columns {columns}"
        )
    below = [keys.GOAL] if keys.GOAL in columns and keys.GOAL not in views else []
    out = []
    for ep in np.atleast_1d(episode_idx).tolist():
        steps = dataset.load_episode(int(ep))
        frames = {k: np.asarray(steps[k])[: int(max_steps)] for k in views + below}
        n = min(len(v) for v in frames.values())
        rows = (
            vstack_frames([hstack_frames([frames[v][i] for v in views]), *[frames[b][i] for b in below]])
            for i in range(n)
        )
        out.append(write_mp4(Path(video_path) / f"episode_{ep}.mp4", rows, fps=fps))
    return out


def preview_dataset(
    name: str | os.PathLike,
    *,
    episodes: Sequence[int] | None = None,
    n: int = 4,
    out: str | os.PathLike | None = None,
    fps: int = 10,
    seed: int = 0,
    cache_dir: str | os.PathLike | None = None,
) -> list[Path]:
    """One MP4 per episode of dataset ``name`` (any registered format): every image column side by
    side (``pixels``, other views, ``goal`` below), for a first look (``swm preview``).

    ``episodes``: which ones (default: ``n`` drawn with ``seed``, in order). ``out``: the folder
    (default ``<cache>/previews/<dataset>/``). Returns the paths written.
    """
    from ..errors import check_int
    from .utils import get_cache_dir, load_dataset, resolve_dataset
    from .writer import is_image_column

    path = resolve_dataset(name, cache_dir, who="preview")
    dataset = load_dataset(path)
    try:
        columns = list(dataset.column_names)
        views = [c for c in columns if c != keys.GOAL and is_image_column(*dataset.column_shape(c))]
        if not views:
            raise ConfigError(
                f"preview requires a dataset with image columns, got {str(path)!r} with columns {columns}"
            )
        total = int(dataset.num_episodes)
        if episodes is None:
            count = min(check_int("preview", "n", n), total)
            chosen = sorted(np.random.default_rng(seed).choice(total, size=count, replace=False).tolist())
        else:
            chosen = [int(e) for e in episodes]
            bad = [e for e in chosen if not 0 <= e < total]
            if bad:
                raise ConfigError(f"preview requires episodes in [0, {total}) of {path.name}, got {bad}")
        folder = Path(out) if out is not None else get_cache_dir() / "previews" / path.stem
        return record_video_from_dataset(folder, dataset, chosen, fps=fps, viewname=views)
    finally:
        close = getattr(dataset, "close", None)
        if close is not None:
            close()

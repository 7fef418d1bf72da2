"""On-disk cache of a frozen encoder's features for every frame of a dataset.

A model with a frozen encoder (PreJEPA / DINO-WM: ``model.frozen_encoder()`` returns it) sees
the same features for a frame in every epoch and every run, so they are computed once and kept
beside the dataset: ``<dataset folder>/.features/<dataset name>/<fingerprint>.npy``, one row per
dataset row, float32. The fingerprint hashes the encoder's weights, the image preprocessing
(size, mean, std) and the dataset file's identity (path, size, modification time), so a
different encoder, preprocessing or a rewritten dataset gets a new file. Files are written as
``.partial`` and renamed when complete: a killed run leaves no half-written cache behind.
"""

from __future__ import annotations

import hashlib
import logging
import os
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import torch

from .. import keys
from ..wm.preprocess import preprocess_images

logger = logging.getLogger(__name__)

__all__ = ["FeatureCache", "feature_fingerprint", "fit_frozen_encoder", "load_or_compute_features"]

CHUNK_ROWS = 256  # frames encoded per forward pass while filling the cache


@dataclass(frozen=True)
class FeatureCache:
    """Features ``(N, ...)`` of the ``N`` dataset rows (a read-only memory map), where they are
    stored, whether this run computed them and the seconds it spent computing or loading them."""

    features: np.ndarray
    path: Path
    computed: bool
    seconds: float

    def describe(self) -> str:
        verb = "computed" if self.computed else "loaded from the cache"
        return f"frozen-encoder features of {len(self.features)} frames {verb} in {self.seconds:.1f} s ({self.path})"


def fit_frozen_encoder(
    encoder: torch.nn.Module, dataset: Any, episodes: Any, cfg: Any, device: torch.device, max_frames: int = 4096
) -> bool:
    """Fit a frozen encoder (or a model) that learns fixed statistics from data (one with
    ``fit_to_frames``, e.g. :class:`~stable_worldmodel.wm.prejepa.module.BlurPatchEncoder`, also
    inside an ``EvalOnly`` wrapper, or :class:`~stable_worldmodel.wm.dreamer.Dreamer`) on up to
    ``max_frames`` frames of ``episodes``, evenly spaced and preprocessed as for training. Returns
    whether there was anything to fit. The fitted buffers are part of the encoder's state dict, so
    the feature cache's fingerprint follows them."""
    target = getattr(encoder, "backbone", encoder)
    fit = getattr(target, "fit_to_frames", None)
    if not callable(fit):
        return False
    eps = np.asarray(episodes, dtype=np.int64)
    lengths, offsets = np.asarray(dataset.lengths)[eps], np.asarray(dataset.offsets)[eps]
    rows = (
        np.concatenate([np.arange(o, o + n) for o, n in zip(offsets, lengths, strict=False)])
        if len(eps)
        else np.zeros(0, np.int64)
    )
    if len(rows) < 2:
        raise ValueError(f"fitting the frozen encoder requires at least 2 training frames, got {len(rows)}")
    rows = rows[np.unique(np.linspace(0, len(rows) - 1, min(len(rows), max_frames)).astype(np.int64))]
    frames = np.concatenate([dataset._read(keys.PIXELS, int(r), int(r) + 1) for r in rows])  # (n, H, W, C)
    images = torch.from_numpy(np.ascontiguousarray(frames)).permute(0, 3, 1, 2).unsqueeze(1).to(device)
    fit(preprocess_images(images, cfg.image_mean, cfg.image_std, cfg.image_size)[:, 0])
    return True


def feature_fingerprint(encoder: torch.nn.Module, cfg: Any, dataset_path: Path) -> str:
    """A hex digest of the encoder's state dict, the image preprocessing and the dataset file's identity."""
    digest = hashlib.sha256()
    digest.update(type(encoder).__qualname__.encode())
    for name, tensor in sorted(encoder.state_dict().items()):
        t = tensor.detach().cpu().contiguous()
        digest.update(f"{name}|{t.dtype}|{tuple(t.shape)}".encode())
        digest.update(t.reshape(-1).view(torch.uint8).numpy().tobytes() if t.numel() else b"")
    stat = dataset_path.stat()
    digest.update(repr((cfg.image_size, tuple(cfg.image_mean), tuple(cfg.image_std))).encode())
    digest.update(repr((str(dataset_path.resolve()), stat.st_size, stat.st_mtime_ns)).encode())
    return digest.hexdigest()[:24]


def cache_file(dataset_path: Path, fingerprint: str) -> Path:
    """Where the features of ``dataset_path`` for ``fingerprint`` live."""
    return dataset_path.parent / ".features" / dataset_path.stem / f"{fingerprint}.npy"


def load_or_compute_features(
    dataset: Any,
    encode: Callable[[torch.Tensor], torch.Tensor],
    encoder: torch.nn.Module,
    cfg: Any,
    device: torch.device,
    chunk_rows: int = CHUNK_ROWS,
) -> FeatureCache:
    """The cached features of every row of ``dataset``'s pixels (computing and storing them
    on the first call): ``encode`` maps preprocessed ``(n, 1, C, S, S)`` images to ``(n, 1, ...)``."""
    path = cache_file(Path(dataset.path), feature_fingerprint(encoder, cfg, Path(dataset.path)))
    start = time.perf_counter()
    if path.is_file():
        try:
            features = np.load(path, mmap_mode="r")
        except (OSError, ValueError) as exc:  # damaged (not ours to trust): compute again
            logger.warning("Ignoring the unreadable feature cache %s (%s); computing it again", path, exc)
        else:
            if len(features) == dataset.num_rows:
                return FeatureCache(features, path, computed=False, seconds=time.perf_counter() - start)
            logger.warning(
                "Ignoring the feature cache %s: %d rows for %d dataset rows", path, len(features), dataset.num_rows
            )
    path.parent.mkdir(parents=True, exist_ok=True)
    partial = path.with_name(f".{path.name}.{os.getpid()}.partial")
    out = None
    try:
        with torch.inference_mode():
            for lo in range(0, dataset.num_rows, chunk_rows):
                hi = min(dataset.num_rows, lo + chunk_rows)
                frames = torch.from_numpy(np.ascontiguousarray(dataset._read(keys.PIXELS, lo, hi)))  # (n, H, W, C)
                images = frames.permute(0, 3, 1, 2).unsqueeze(1).to(device)
                feats = encode(preprocess_images(images, cfg.image_mean, cfg.image_std, cfg.image_size))[:, 0]
                feats = feats.float().cpu().numpy()
                if out is None:
                    out = np.lib.format.open_memmap(
                        partial, mode="w+", dtype=np.float32, shape=(dataset.num_rows, *feats.shape[1:])
                    )
                out[lo:hi] = feats
        if out is None:
            raise ValueError(f"Feature cache requires a dataset with rows, got none in {dataset.path}")
        out.flush()
        del out
        with open(partial, "rb") as f:
            os.fsync(f.fileno())
        os.replace(partial, path)
    except BaseException:
        partial.unlink(missing_ok=True)
        raise
    features = np.load(path, mmap_mode="r")
    return FeatureCache(features, path, computed=True, seconds=time.perf_counter() - start)

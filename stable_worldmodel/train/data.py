"""Training data: windows of a recorded dataset split by episode, normalized, batched on the device.

A sample is a window of ``num_steps = history_size + num_preds`` frames spaced by
``frameskip`` rows inside one episode (see :mod:`stable_worldmodel.data.dataset`); its
``action`` is ``(T, frameskip * A)``, the action block taken from each frame. Episodes are
split into train / validation with a seeded permutation (recorded in the run's
``protocol.json``); the action normalizer is fitted on the train episodes' rows only.
"""

from __future__ import annotations

import logging
from typing import Any

import numpy as np
import torch

from .. import keys
from ..errors import ConfigError, DatasetFormatError, did_you_mean
from ..wm.preprocess import Normalizer, preprocess_images

logger = logging.getLogger(__name__)

__all__ = ["TrainData", "split_episodes"]


def split_episodes(num_episodes: int, val_fraction: float, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """Sorted train and validation episode ids: a seeded permutation, at least one episode
    for validation when ``val_fraction > 0`` and there are two episodes or more."""
    perm = np.random.default_rng(seed).permutation(num_episodes)
    n_val = int(round(val_fraction * num_episodes))
    if val_fraction > 0 and num_episodes >= 2:
        n_val = max(n_val, 1)
    n_val = min(n_val, num_episodes - 1)
    return np.sort(perm[n_val:]), np.sort(perm[:n_val])


class TrainData:
    """Batches of ``pixels (B, T, C, S, S)`` (preprocessed floats) and normalized
    ``action (B, T, frameskip * A)`` on ``device``, from dataset ``name``.

    Raises :class:`~stable_worldmodel.errors.DatasetFormatError` when a column is missing
    or no episode is long enough for one window.
    """

    def __init__(self, name: str, cfg: Any, seed: int, device: torch.device, cache_dir: str | None = None):
        from ..data import HDF5Dataset
        from ..data.utils import resolve_dataset_path

        self.cfg, self.device = cfg, device
        path = resolve_dataset_path(name, cache_dir)
        if not path.is_file():
            names = sorted(p.stem for p in path.parent.glob("*.h5"))
            raise FileNotFoundError(
                f"Training requires a recorded .h5 dataset, got {str(name)!r} ({path} does not exist).{did_you_mean(str(name), names)} "
                f"Datasets in {path.parent}: {', '.join(names) or '(none)'}"
            )
        self.dataset = HDF5Dataset(name, frameskip=cfg.frameskip, num_steps=cfg.num_steps, cache_dir=cache_dir)
        missing = [k for k in (keys.PIXELS, keys.ACTION) if k not in self.dataset.column_names]
        if missing:
            raise DatasetFormatError(
                f"Training requires dataset columns {missing} in {self.dataset.path}, got {sorted(self.dataset.column_names)}"
            )
        self.dataset = HDF5Dataset(
            name, frameskip=cfg.frameskip, num_steps=cfg.num_steps, keys_to_load=[keys.PIXELS, keys.ACTION], cache_dir=cache_dir
        )
        shape, _ = self.dataset.column_shape(keys.PIXELS)
        if len(shape) != 3 or shape[-1] not in (1, 3):
            raise DatasetFormatError(f"Training requires pixels of shape (N, H, W, 3), got {shape} in {self.dataset.path}")
        if shape[-1] != len(cfg.image_mean):
            raise ConfigError(f"Training requires {len(cfg.image_mean)}-channel images, got {shape[-1]} channels in {self.dataset.path}")
        self.image_shape = tuple(int(v) for v in shape)
        self.action_dim = int(np.prod(self.dataset.column_shape(keys.ACTION)[0]))
        self.train_episodes, self.val_episodes = split_episodes(self.dataset.num_episodes, cfg.val_fraction, seed)
        eps, _ = self.dataset._locate_many(np.arange(len(self.dataset), dtype=np.int64))
        in_val = np.isin(eps, self.val_episodes)
        self.train_index, self.val_index = np.flatnonzero(~in_val), np.flatnonzero(in_val)
        if not len(self.train_index):
            longest = int(np.max(self.dataset.lengths)) if self.dataset.num_episodes else 0
            raise DatasetFormatError(
                f"Training requires episodes of at least num_steps * frameskip = {cfg.num_steps} * {cfg.frameskip} = "
                f"{self.dataset.span} steps, got none in the train split of {self.dataset.path} (longest: {longest}); "
                "lower --frameskip / history or record longer episodes"
            )
        self.normalizer = self._fit_normalizer()

    def _fit_normalizer(self) -> Normalizer:
        actions = self.dataset.get_col_data(keys.ACTION).reshape(self.dataset.num_rows, -1)
        rows = np.concatenate(
            [np.arange(o, o + n) for o, n in zip(self.dataset.offsets[self.train_episodes], self.dataset.lengths[self.train_episodes])]
        )
        return Normalizer.fit(actions[rows])

    @property
    def num_train(self) -> int:
        return len(self.train_index)

    @property
    def num_val(self) -> int:
        return len(self.val_index)

    def batch(self, index: np.ndarray) -> dict[str, torch.Tensor]:
        """The samples ``index`` (dataset sample ids) as a device batch."""
        raw = self.dataset._batch(np.asarray(index, dtype=np.int64))
        pixels = raw[keys.PIXELS].to(self.device, non_blocking=True)
        action = torch.nan_to_num(raw[keys.ACTION].to(self.device, dtype=torch.float32), 0.0)
        cfg = self.cfg
        return {
            keys.PIXELS: preprocess_images(pixels, cfg.image_mean, cfg.image_std, cfg.image_size),
            keys.ACTION: self.normalizer.torch(action, repeat=cfg.frameskip),
        }

    def train_batch(self, generator: torch.Generator, batch_size: int) -> dict[str, torch.Tensor]:
        """A train batch of ``batch_size`` samples drawn uniformly (with replacement) by ``generator``."""
        pick = torch.randint(self.num_train, (batch_size,), generator=generator).numpy()
        return self.batch(self.train_index[pick])

    def val_batches(self, batch_size: int, max_samples: int) -> list[np.ndarray]:
        """Fixed validation index batches (evenly spread over the validation samples), of at most
        ``batch_size`` and near-equal sizes: no lone last sample, whose batch statistics
        (VCReg's variance, SIGReg) would be NaN."""
        if not self.num_val:
            return []
        take = self.val_index[np.linspace(0, self.num_val - 1, min(max_samples, self.num_val)).astype(np.int64)]
        return np.array_split(take, -(-len(take) // batch_size))

    def protocol(self) -> dict[str, Any]:
        """What planning and evaluation need to know about the data the model saw."""
        return {
            "dataset": self.dataset.name,
            "dataset_path": str(self.dataset.path),
            "episodes": int(self.dataset.num_episodes),
            "train_episodes": self.train_episodes.tolist(),
            "val_episodes": self.val_episodes.tolist(),
            "train_samples": self.num_train,
            "val_samples": self.num_val,
            "dataset_image_shape": list(self.image_shape),
            "action_dim": self.action_dim,
            "normalizers": {keys.ACTION: self.normalizer.to_dict()},
        }

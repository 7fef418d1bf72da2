"""Training data: windows of a recorded dataset split by episode, normalized, batched on the device.

A sample is a window of ``num_steps = history_size + num_preds`` frames spaced by
``frameskip`` rows inside one episode (see :mod:`stable_worldmodel.data.dataset`); its
``action`` is ``(T, frameskip * A)``, the action block taken from each frame. Episodes are
split into train / validation with a seeded permutation (recorded in the run's
``protocol.json``); the action normalizer is fitted on the train episodes' rows only.

For a goal-conditioned config (:class:`~stable_worldmodel.train.goals.GoalConditioned`), a
batch also holds ``goal_pixels (B, 1, C, S, S)``, a hindsight goal frame per sample drawn by
the config's ``goal_probabilities`` (and ``actor_goal_pixels`` from
``actor_goal_probabilities`` when it is not empty), from the sample's own split. Goal frames
are preprocessed in the same call as the window's frames, so a goal equal to a frame stays
bit-identical to it.

For a config with ``needs_reward`` (TD-MPC2), a batch also holds ``reward (B, T)`` (float32, not
normalized): ``reward[:, k]`` is the sum of the ``frameskip`` env rewards earned by the action block
``action[:, k]``, i.e. of the ``reward`` column on rows ``start + k * frameskip + 1`` to
``start + (k + 1) * frameskip`` (a recorded row holds the reward of the step that led to it). The
last step's outcome lies outside the window: its reward is 0. NaN rewards count as 0.
"""

from __future__ import annotations

import logging
from pathlib import Path
from typing import Any

import numpy as np
import torch

from .. import keys
from ..errors import ConfigError, DatasetFormatError
from ..wm.preprocess import Normalizer, preprocess_images
from .goals import GoalConditioned, GoalSampler

logger = logging.getLogger(__name__)

__all__ = ["TrainData", "extra_columns", "split_episodes"]


def split_episodes(num_episodes: int, val_fraction: float, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """Sorted train and validation episode ids: a seeded permutation, at least one episode
    for validation when ``val_fraction > 0`` and there are two episodes or more."""
    perm = np.random.default_rng(seed).permutation(num_episodes)
    n_val = int(round(val_fraction * num_episodes))
    if val_fraction > 0 and num_episodes >= 2:
        n_val = max(n_val, 1)
    n_val = min(n_val, num_episodes - 1)
    return np.sort(perm[n_val:]), np.sort(perm[:n_val])


def extra_columns(cfg: Any) -> dict[str, int]:
    """The dataset columns besides pixels and actions that a config's model reads, with their
    widths (``cfg.extra_columns``, :class:`~stable_worldmodel.wm.base.WorldModelConfig`)."""
    return {str(k): int(v) for k, v in dict(cfg.extra_columns).items()}


class TrainData:
    """Batches of ``pixels (B, T, C, S, S)`` (preprocessed floats) and normalized
    ``action (B, T, frameskip * A)`` on ``device``, from dataset ``name``; plus normalized
    ``proprio (B, T, P)`` when the config asks for it (``cfg.proprio_dim > 0``, PreJEPA), and
    ``reward (B, T)`` when ``cfg.needs_reward`` (module docstring).

    Raises :class:`~stable_worldmodel.errors.DatasetFormatError` when a column is missing
    or no episode is long enough for one window.
    """

    def __init__(
        self,
        name: str,
        cfg: Any,
        seed: int,
        device: torch.device,
        cache_dir: str | None = None,
        *,
        dataset: Any = None,
    ):
        from ..data.utils import load_dataset, resolve_dataset

        self.cfg, self.device, self.seed = cfg, device, seed
        if dataset is None:
            self.path = resolve_dataset(name, cache_dir, who="Training")  # any registered format
            self.dataset = load_dataset(self.path, frameskip=cfg.frameskip, num_steps=cfg.num_steps)
        else:  # an open dataset with the config's windows (online training: a ReplayBuffer that grows)
            self.path = Path(getattr(dataset, "path", None) or name)
            self.dataset = dataset
        self.extra_widths = extra_columns(cfg)
        self.extra_keys = list(self.extra_widths)
        self.reads_pixels = bool(cfg.reads_pixels)  # False: a state-input model
        frame_keys = [keys.PIXELS] if self.reads_pixels else []
        missing = [k for k in (*frame_keys, keys.ACTION, *self.extra_keys) if k not in self.dataset.column_names]
        if missing:
            raise DatasetFormatError(
                f"Training requires dataset columns {missing} in {self.path}, got {sorted(self.dataset.column_names)}"
            )
        self.needs_reward = bool(cfg.needs_reward)
        if self.needs_reward and keys.REWARD not in self.dataset.column_names:
            model = cfg.model_name or type(cfg).__name__
            raise DatasetFormatError(
                f"Training {model} requires a {keys.REWARD!r} column, got none in dataset {str(name)!r} "
                f"({self.path}), "
                f"whose columns are {sorted(self.dataset.column_names)}. Record one: World.record_dataset(...) and "
                "`swm collect` store the env's reward of every step as 'reward' (an env whose reward is 0 everywhere "
                "gives nothing to learn)"
            )
        if dataset is None:
            self.dataset = load_dataset(
                self.path,
                frameskip=cfg.frameskip,
                num_steps=cfg.num_steps,
                keys_to_load=[*frame_keys, keys.ACTION, *self.extra_keys],
            )
        self.image_shape: tuple[int, ...] = ()
        if self.reads_pixels:
            shape, _ = self.dataset.column_shape(keys.PIXELS)
            if len(shape) != 3 or shape[-1] not in (1, 3):
                raise DatasetFormatError(f"Training requires pixels of shape (N, H, W, 3), got {shape} in {self.path}")
            if shape[-1] != len(cfg.image_mean):
                raise ConfigError(
                    f"Training requires {len(cfg.image_mean)}-channel images, got {shape[-1]} channels in {self.path}"
                )
            self.image_shape = tuple(int(v) for v in shape)
        self.action_dim = int(np.prod(self.dataset.column_shape(keys.ACTION)[0]))
        for key, expected in self.extra_widths.items():
            width = int(np.prod(self.dataset.column_shape(key)[0]))
            if width != expected:
                raise ConfigError(
                    f"Training requires {key}_dim equal to the width of column {key!r}, "
                    f"got {key}_dim={expected} and {width} in {self.path}"
                )
        self._split()
        self.normalizer = self._fit_normalizer()
        # goal_<k> is in the units of <k> when <k> is read too: it shares <k>'s normalizer (planning falls back to it
        # as well, see prepare_info), which the protocol therefore does not repeat
        prefix = keys.goal_key("")
        self._shared_normalizer = {
            key: key[len(prefix) :]
            for key in self.extra_keys
            if key.startswith(prefix) and key[len(prefix) :] in self.extra_widths
        }
        self.extra_normalizers = {
            key: self._fit_normalizer(key) for key in self.extra_keys if key not in self._shared_normalizer
        }
        self.extra_normalizers.update(
            {key: self.extra_normalizers[base] for key, base in self._shared_normalizer.items()}
        )
        self._reward_cumsum = self._cumulative_rewards() if self.needs_reward else None
        self.features: np.ndarray | None = None  # frozen-encoder features per dataset row (use_features)
        self.goals = self._goal_samplers(cfg) if isinstance(cfg, GoalConditioned) else {}

    def _split(self) -> None:
        """The seeded split of the episodes into train and validation, and the samples of each."""
        cfg = self.cfg
        self.train_episodes, self.val_episodes = split_episodes(self.dataset.num_episodes, cfg.val_fraction, self.seed)
        eps, _ = self.dataset._locate_many(np.arange(len(self.dataset), dtype=np.int64))
        in_val = np.isin(eps, self.val_episodes)
        self.train_index, self.val_index = np.flatnonzero(~in_val), np.flatnonzero(in_val)
        if not len(self.train_index):
            longest = int(np.max(self.dataset.lengths)) if self.dataset.num_episodes else 0
            raise DatasetFormatError(
                f"Training requires episodes of at least num_steps * frameskip = {cfg.num_steps} * {cfg.frameskip} = "
                f"{self.dataset.span} steps, got none in the train split of {self.path} (longest: {longest}); "
                "lower --frameskip / history or record longer episodes"
            )

    def refresh(self) -> None:
        """Take in the episodes a growing dataset gained (or lost: a replay buffer evicts): the split,
        the samples, the rewards and goal samplers follow; the normalizers stay as first fitted
        (the model learned in their units)."""
        self._split()
        if self.needs_reward:
            self._reward_cumsum = self._cumulative_rewards()
        if self.goals:
            self.goals = self._goal_samplers(self.cfg)

    def _goal_samplers(self, cfg: Any) -> dict[str, GoalSampler]:
        """Batch key -> sampler of its goals (``goal_pixels``, and ``actor_goal_pixels`` when configured)."""
        groups = [self.train_episodes, self.val_episodes]
        common = dict(
            gamma=cfg.goal_gamma, frameskip=cfg.frameskip, current_offset=(cfg.history_size - 1) * cfg.frameskip
        )
        lengths, offsets = np.asarray(self.dataset.lengths), np.asarray(self.dataset.offsets)
        goal_key = keys.goal_key(keys.PIXELS)
        samplers = {goal_key: GoalSampler(lengths, offsets, groups, cfg.goal_probabilities, **common)}
        if cfg.actor_goal_probabilities:
            samplers[f"actor_{goal_key}"] = GoalSampler(
                lengths, offsets, groups, cfg.actor_goal_probabilities, **common
            )
        return samplers

    def _fit_normalizer(self, key: str = keys.ACTION) -> Normalizer:
        values = self.dataset.get_col_data(key).reshape(self.dataset.num_rows, -1)
        rows = np.concatenate(
            [
                np.arange(o, o + n)
                for o, n in zip(
                    self.dataset.offsets[self.train_episodes], self.dataset.lengths[self.train_episodes], strict=False
                )
            ]
        )
        return Normalizer.fit(values[rows])

    def _cumulative_rewards(self) -> np.ndarray:
        """``C (num_rows + 1,)`` with ``C[i]`` the sum of the rewards of rows ``< i`` (NaN as 0)."""
        reward = np.asarray(self.dataset.get_col_data(keys.REWARD), dtype=np.float64).reshape(self.dataset.num_rows, -1)
        return np.concatenate([[0.0], np.cumsum(np.nan_to_num(reward.sum(-1), nan=0.0))])

    def _with_reward(self, index: np.ndarray, out: dict[str, torch.Tensor]) -> dict[str, torch.Tensor]:
        """``out`` plus ``reward (B, T)`` of the samples ``index`` when the config needs it (module docstring)."""
        if not self.needs_reward:
            return out
        eps, steps = self.dataset._locate_many(index)
        starts = self.dataset._sample_index()[1][eps] + steps
        fs, t = self.cfg.frameskip, self.cfg.num_steps
        lo = starts[:, None] + np.arange(t - 1)[None, :] * fs + 1
        reward = np.zeros((len(index), t), dtype=np.float32)
        reward[:, : t - 1] = self._reward_cumsum[lo + fs] - self._reward_cumsum[lo]
        out[keys.REWARD] = torch.from_numpy(reward).to(self.device)
        return out

    @property
    def num_train(self) -> int:
        return len(self.train_index)

    @property
    def num_val(self) -> int:
        return len(self.val_index)

    def batch(self, index: np.ndarray, generator: torch.Generator | None = None) -> dict[str, torch.Tensor]:
        """The samples ``index`` (dataset sample ids) as a device batch. Goals (goal-conditioned
        configs) are drawn by ``generator``; without one, by a generator seeded from the run's
        seed and ``index[0]`` (validation batches get the same goals every time)."""
        index = np.asarray(index, dtype=np.int64)
        if self.features is not None:
            return self._with_reward(index, self._feature_batch(index))
        raw = self.dataset._batch(index)
        if not self.reads_pixels:  # a state-input model: the normalized columns are the batch
            return self._with_reward(index, self._normalized(raw))
        frames = raw[keys.PIXELS]
        t = frames.shape[1]
        goal_keys = list(self.goals)
        goal_rows = {}
        if goal_keys:
            generator = generator or torch.Generator().manual_seed(self.seed * 1_000_003 + int(index[0]))
            eps, starts = self.dataset._locate_many(index)
            goal_rows = {k: self.goals[k].sample(eps, starts, generator) for k in goal_keys}
            frames = torch.cat([frames, *(self._goal_frames(goal_rows[k]) for k in goal_keys)], dim=1)
        cfg = self.cfg
        pixels = preprocess_images(
            frames.to(self.device, non_blocking=True), cfg.image_mean, cfg.image_std, cfg.image_size
        )
        out = {keys.PIXELS: pixels[:, :t], **self._normalized(raw)}
        for i, key in enumerate(goal_keys):
            out[key] = pixels[:, t + i : t + i + 1]
            out.update(self._goal_extras(key, goal_rows[key]))
        return self._with_reward(index, out)

    def _goal_extras(self, goal_pixels_key: str, rows: np.ndarray) -> dict[str, torch.Tensor]:
        """The extra columns (proprio, ...) at the goal rows, normalized as the window's: ``goal_<k>``
        beside ``goal_pixels`` (``actor_goal_<k>`` beside ``actor_goal_pixels``), each ``(B, 1, P)``."""
        prefix = goal_pixels_key[: -len(keys.PIXELS)]
        out = {}
        for key, norm in self.extra_normalizers.items():
            if key.startswith(keys.goal_key("")):
                continue  # the episode's own goal column: a hindsight goal has none
            values = np.stack([self.dataset._read(key, int(r), int(r) + 1)[0] for r in rows])
            values = torch.nan_to_num(torch.as_tensor(values, dtype=torch.float32, device=self.device), 0.0)
            out[prefix + key] = norm.torch(values.reshape(len(rows), 1, -1))
        return out

    def use_features(self, features: np.ndarray) -> None:
        """Serve ``pixels_emb (B, T, ...)`` gathered from ``features`` (one row per dataset row,
        see :mod:`.features`) instead of ``pixels``: the frames are then never decoded."""
        if self.goals:
            raise ConfigError("Training from cached features requires a config without hindsight goals")
        if len(features) != self.dataset.num_rows:
            raise ConfigError(
                f"Training requires one feature row per dataset row, got {len(features)} for {self.dataset.num_rows}"
            )
        self.features = features

    def _feature_batch(self, index: np.ndarray) -> dict[str, torch.Tensor]:
        ds = self.dataset
        eps, steps = ds._locate_many(index)
        starts = ds._sample_index()[1][eps] + steps
        rows = starts[:, None] + ds._row_offsets(keys.PIXELS)[None, :]  # (B, T) dataset rows of the frames
        unique, where = np.unique(rows, return_inverse=True)  # one sorted read of the memory map
        feats = torch.from_numpy(np.asarray(self.features[unique]))
        raw = {
            key: torch.from_numpy(np.ascontiguousarray(ds._read_windows(key, starts)))
            for key in (keys.ACTION, *self.extra_keys)
        }
        raw[keys.ACTION] = raw[keys.ACTION].reshape(len(starts), ds.num_steps, -1)  # (B, span, A) -> action blocks
        return {
            "pixels_emb": feats[torch.from_numpy(where.reshape(rows.shape))].to(self.device),
            **self._normalized(raw),
        }

    def _normalized(self, raw: dict[str, torch.Tensor]) -> dict[str, torch.Tensor]:
        """``action`` blocks and the extra columns of ``raw`` ``(B, T, ...)`` as normalized
        float tensors on the device (missing values, NaN, become 0 first)."""
        out = {}
        for key in (keys.ACTION, *self.extra_keys):
            values = torch.nan_to_num(raw[key].to(self.device, dtype=torch.float32), 0.0)
            if key == keys.ACTION:
                out[key] = self.normalizer.torch(values, repeat=self.cfg.frameskip)
            else:
                out[key] = self.extra_normalizers[key].torch(values.reshape(*values.shape[:2], -1))
        return out

    def _goal_frames(self, rows: np.ndarray) -> torch.Tensor:
        """The pixels of dataset rows ``(B,)`` as ``(B, 1, C, H, W)`` uint8."""
        frames = np.stack([self.dataset._read(keys.PIXELS, int(r), int(r) + 1)[0] for r in rows])  # (B, H, W, C)
        return torch.from_numpy(np.ascontiguousarray(frames)).permute(0, 3, 1, 2).unsqueeze(1)

    def train_pick(self, generator: torch.Generator, batch_size: int) -> np.ndarray:
        """The sample ids of a train batch of ``batch_size``, drawn uniformly (with replacement) by ``generator``."""
        return self.train_index[torch.randint(self.num_train, (batch_size,), generator=generator).numpy()]

    def train_batch(self, generator: torch.Generator, batch_size: int) -> dict[str, torch.Tensor]:
        """A train batch of ``batch_size`` samples drawn uniformly (with replacement) by ``generator``."""
        return self.batch(self.train_pick(generator, batch_size), generator)

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
        from ..data.writer import ENV_ID_ATTR

        env = getattr(self.dataset, "attrs", {}).get(ENV_ID_ATTR)  # recorded by World.record_dataset
        return {
            **({"env": env} if env else {}),
            "dataset": self.path.stem,
            "dataset_path": str(self.path),
            "episodes": int(self.dataset.num_episodes),
            "train_episodes": self.train_episodes.tolist(),
            "val_episodes": self.val_episodes.tolist(),
            "train_samples": self.num_train,
            "val_samples": self.num_val,
            "dataset_image_shape": list(self.image_shape),
            "action_dim": self.action_dim,
            "normalizers": {
                keys.ACTION: self.normalizer.to_dict(),
                **{k: n.to_dict() for k, n in self.extra_normalizers.items() if k not in self._shared_normalizer},
            },
        }

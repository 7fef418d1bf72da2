"""Hindsight goals for goal-conditioned training: a goal frame for each training window.

A window starts at step ``s`` of episode ``e`` (length ``L``); its last history frame is
``c = s + (history_size - 1) * frameskip``. A goal is a row of the dataset, drawn by kind
(see :data:`stable_worldmodel.wm.gcrl.config.GOAL_SAMPLING`)::

    current     c
    geometric   c + k * frameskip, k ~ Geometric(1 - gamma) on 1, 2, ...   clipped to the episode
    uniform     c + k * frameskip, k uniform on 1 .. K                    (K = (L - 1 - c) // frameskip)
    random      any row of any episode of the window's group (its train / validation split)

When nothing is left after ``c`` (K = 0), future goals fall back to ``c``. Every draw comes
from the ``torch.Generator`` given, four uniforms per window whatever the kinds, so the goals
of a run are reproduced by its seed (and by a resumed run).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np
import torch

from ..wm.base import GoalConditioned
from ..wm.gcrl.config import GOAL_SAMPLING, check_goal_probabilities

__all__ = ["GoalConditioned", "GoalSampler"]


class GoalSampler:
    """Draws goal rows for windows of a dataset with episode ``lengths`` and row ``offsets``.

    ``groups``: lists of episode ids; a ``random`` goal is drawn from the group of the window's
    episode (e.g. ``[train_episodes, val_episodes]``: no goal leaks across the split).
    """

    def __init__(
        self,
        lengths: np.ndarray,
        offsets: np.ndarray,
        groups: Sequence[np.ndarray],
        probabilities: Mapping[str, float],
        gamma: float = 0.99,
        frameskip: int = 1,
        current_offset: int = 0,
    ):
        probs = check_goal_probabilities(probabilities, "GoalSampler")
        self.lengths, self.offsets = np.asarray(lengths, np.int64), np.asarray(offsets, np.int64)
        self.cum_probs = np.cumsum([probs.get(kind, 0.0) for kind in GOAL_SAMPLING])
        self.log_gamma = float(np.log(1.0 - max(1.0 - gamma, 1e-6)))
        self.frameskip, self.current_offset = int(frameskip), int(current_offset)
        self.group_of = np.full(len(self.lengths), -1, np.int64)
        self.pools: list[tuple[np.ndarray, np.ndarray]] = []  # per group: episodes, cumulative lengths
        for g, episodes in enumerate(groups):
            episodes = np.asarray(episodes, np.int64)
            self.group_of[episodes] = g
            self.pools.append((episodes, np.cumsum(self.lengths[episodes])))

    def sample(self, episodes: np.ndarray, starts: np.ndarray, generator: torch.Generator) -> np.ndarray:
        """Global goal rows ``(B,)`` for windows starting at step ``starts`` of ``episodes`` (both ``(B,)``)."""
        episodes, starts = np.asarray(episodes, np.int64), np.asarray(starts, np.int64)
        u = torch.rand(4, len(episodes), generator=generator, dtype=torch.float64).numpy()
        kind = np.minimum(np.searchsorted(self.cum_probs, u[0], side="right"), len(GOAL_SAMPLING) - 1)
        current = starts + self.current_offset
        left = np.maximum((self.lengths[episodes] - 1 - current) // self.frameskip, 0)
        geometric = np.ceil(np.log1p(-u[1]) / self.log_gamma).astype(np.int64)
        uniform = np.floor(u[2] * left).astype(np.int64) + 1
        k = np.where(kind == GOAL_SAMPLING.index("geometric"), geometric, uniform)
        k = np.minimum(np.maximum(k, 1), left)  # 0 when nothing is left: the current frame
        steps = np.where(kind == GOAL_SAMPLING.index("current"), current, current + k * self.frameskip)
        goal_eps = episodes.copy()
        random = kind == GOAL_SAMPLING.index("random")
        if random.any():
            goal_eps[random], steps[random] = self._random(episodes[random], u[3][random])
        return self.offsets[goal_eps] + steps

    def _random(self, episodes: np.ndarray, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        eps, steps = episodes.copy(), np.zeros(len(episodes), np.int64)
        groups = self.group_of[episodes]
        for g in np.unique(groups):
            sel = groups == g
            pool, cum = self.pools[g] if g >= 0 else (episodes[sel][:1], self.lengths[episodes[sel][:1]])
            flat = np.minimum(np.floor(u[sel] * cum[-1]).astype(np.int64), cum[-1] - 1)
            k = np.searchsorted(cum, flat, side="right")
            eps[sel] = pool[k]
            steps[sel] = flat - np.concatenate([[0], cum])[k]
        return eps, steps

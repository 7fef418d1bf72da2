"""Success-rate statistics shown by ``swm eval`` and ``swm demo``."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

#: two-sided 95% normal quantile
Z95 = 1.959963984540054


def wilson_interval(successes: int, n: int, z: float = Z95) -> tuple[float, float]:
    """Wilson score interval (fractions in [0, 1]) of ``successes`` out of ``n`` trials.

    Unlike the normal approximation it stays inside [0, 1] and is not empty at 0 or n
    successes. ``n == 0`` gives the uninformative ``(0, 1)``.
    """
    if n <= 0:
        return 0.0, 1.0
    p = successes / n
    denom = 1.0 + z * z / n
    center = (p + z * z / (2 * n)) / denom
    half = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / denom
    low = 0.0 if successes <= 0 else max(0.0, center - half)  # exact at the ends (no rounding residue)
    high = 1.0 if successes >= n else min(1.0, center + half)
    return low, high


@dataclass(frozen=True)
class SuccessSummary:
    """What one evaluation gives the tables and the plot."""

    label: str
    episodes: int
    successes: int
    mean_length: float

    @property
    def rate(self) -> float:
        return self.successes / self.episodes if self.episodes else 0.0

    @property
    def interval(self) -> tuple[float, float]:
        return wilson_interval(self.successes, self.episodes)

    @classmethod
    def from_results(cls, label: str, results: dict) -> SuccessSummary:
        """From the dict of ``World.evaluate`` (``episode_successes``, ``episode_lengths``)."""
        ok = np.asarray(results["episode_successes"], bool)
        lengths = np.asarray(results.get("episode_lengths", []), float)
        return cls(label, int(ok.size), int(ok.sum()), float(lengths.mean()) if lengths.size else float("nan"))

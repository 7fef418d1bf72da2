"""The 95% Wilson interval behind the success tables and the demo plot."""

from __future__ import annotations

import numpy as np
import pytest

from stable_worldmodel.cli.stats import SuccessSummary, wilson_interval


@pytest.mark.parametrize(
    ("k", "n", "expected"),
    [(5, 10, (0.2366, 0.7634)), (0, 10, (0.0, 0.2775)), (10, 10, (0.7225, 1.0)), (81, 263, (0.2553, 0.3662))],
)
def test_wilson_reference_values(k, n, expected):
    assert wilson_interval(k, n) == pytest.approx(expected, abs=1e-4)


def test_wilson_properties():
    for n in (1, 3, 20, 100):
        for k in range(n + 1):
            low, high = wilson_interval(k, n)
            assert 0.0 <= low <= k / n <= high <= 1.0
            mirror = wilson_interval(n - k, n)
            assert (low, high) == pytest.approx((1 - mirror[1], 1 - mirror[0]))
    assert wilson_interval(0, 0) == (0.0, 1.0)
    widths = [np.subtract(*wilson_interval(n // 2, n)[::-1]) for n in (10, 100, 1000)]
    assert widths[0] > widths[1] > widths[2]


def test_summary_from_evaluate_results():
    s = SuccessSummary.from_results(
        "p", {"episode_successes": np.array([True, False, True, True]), "episode_lengths": np.array([3, 10, 5, 4])}
    )
    assert (s.episodes, s.successes, s.rate, s.mean_length) == (4, 3, 0.75, 5.5)
    assert s.interval == wilson_interval(3, 4)

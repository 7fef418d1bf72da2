"""PlanConfig refuses a non-bool warm_start in __post_init__ (a string like 'no' would be truthy)."""

from __future__ import annotations

import numpy as np
import pytest

from stable_worldmodel.errors import ConfigError
from stable_worldmodel.policy import PlanConfig


@pytest.mark.parametrize(
    "warm_start, fragment",
    [("no", "got 'no'"), ("False", "got 'False'"), (0, "got 0"), (1, "got 1"), (None, "got None"), (1.0, "got 1.0")],
)
def test_non_bool_warm_start_raises_config_error(warm_start, fragment):
    with pytest.raises(ConfigError) as info:
        PlanConfig(horizon=2, receding_horizon=1, warm_start=warm_start)
    message = str(info.value)
    assert isinstance(info.value, ValueError)
    assert "PlanConfig requires warm_start to be a bool" in message and fragment in message


@pytest.mark.parametrize("warm_start", [True, False, np.bool_(True), np.False_])
def test_bool_warm_start_is_accepted(warm_start):
    assert bool(PlanConfig(horizon=2, receding_horizon=1, warm_start=warm_start).warm_start) == bool(warm_start)

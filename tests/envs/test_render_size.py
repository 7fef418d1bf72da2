"""``set_render_size`` takes an (H, W) pair of positive ints; anything else is a ConfigError naming the env."""

from __future__ import annotations

import gymnasium as gym
import pytest

import stable_worldmodel  # noqa: F401  (registers the ids)
from stable_worldmodel.errors import ConfigError


@pytest.mark.parametrize("env_id", ["swm/PushT-v2", "swm/TwoRoom-v0", "swm/SimplePointMaze-v0"])
@pytest.mark.parametrize("size", [(0, 8), (8,), "ab", None])
def test_bad_render_size(env_id, size):
    env = gym.make(env_id, disable_env_checker=True, render_mode="rgb_array").unwrapped
    env.reset(seed=0)
    with pytest.raises(ConfigError, match=r"requires render_size \(H, W\) of positive ints"):
        env.set_render_size(size)
    env.set_render_size((12, 10))
    assert env.render_size == (12, 10) and env.render().shape[:2] == (12, 10)

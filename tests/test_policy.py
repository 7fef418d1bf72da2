"""Policies of stable_worldmodel.policy (the planning ones are tested in tests/planning)."""

from __future__ import annotations

import dataclasses

import gymnasium as gym
import numpy as np
import pytest

import stable_worldmodel as swm
from stable_worldmodel.errors import ConfigError
from stable_worldmodel.policy import BasePolicy, ExpertPolicy, PlanConfig, RandomPolicy, Transformable


class FakeVecEnv:
    def __init__(self, space):
        self.action_space = space
        self.num_envs = space.shape[0] if space.shape else 1


def test_base_policy_stores_kwargs_and_env():
    policy = BasePolicy(alpha=1, name="x")
    assert policy.alpha == 1 and policy.name == "x" and policy.kwargs == {"alpha": 1, "name": "x"}
    env = FakeVecEnv(gym.spaces.Box(-1, 1, (2, 3)))
    policy.set_env(env)
    assert policy.env is env
    with pytest.raises(NotImplementedError):
        policy.get_action({})


def test_random_policy_requires_env():
    with pytest.raises(RuntimeError, match="set_policy"):
        RandomPolicy().get_action({})


@pytest.mark.parametrize(
    "space",
    [
        gym.spaces.Box(-1, 1, (4, 2), np.float32),
        gym.spaces.Box(-np.inf, np.inf, (4, 2), np.float32),  # unbounded: gymnasium's own sampler
        gym.spaces.MultiDiscrete([3, 3, 3, 3]),
    ],
)
def test_random_policy_seeded_like_the_space(space):
    policy = RandomPolicy(seed=3)
    policy.set_env(FakeVecEnv(space))
    policy.set_seed(3)  # what World.set_policy does once after set_env
    reference = type(space).__new__(type(space))
    reference.__dict__.update(space.__dict__)
    reference.seed(3)
    for _ in range(3):
        action = policy.get_action({})
        expected = reference.sample()
        assert action.dtype == expected.dtype and action.shape == expected.shape
        np.testing.assert_array_equal(action, expected)
        assert space.contains(action)


def test_random_policy_set_seed_reseeds():
    policy = RandomPolicy()
    policy.set_env(FakeVecEnv(gym.spaces.Box(-1, 1, (2, 2), np.float32)))
    policy.set_seed(11)
    a = policy.get_action({})
    policy.set_seed(11)
    np.testing.assert_array_equal(a, policy.get_action({}))


def test_world_applies_policy_seed():
    def run():
        world = swm.World("swm/Toy-v0", num_envs=2, image_shape=(8, 8), verbose=0, vectorization_mode="sync")
        world.set_policy(RandomPolicy(seed=5))
        world.reset(seed=0)
        world.step()
        return world.infos["action"].copy()

    np.testing.assert_array_equal(run(), run())


def test_expert_policy_is_a_base_and_typed():
    expert = ExpertPolicy(env_id="swm/Toy-v0")
    assert expert.type == "expert" and expert.env_id == "swm/Toy-v0"
    assert expert.get_action({}) is None  # the base has no expert logic (seed 000)
    assert isinstance(swm.envs.expert_policy("swm/Toy-v0"), ExpertPolicy)


def test_plan_config_fields_and_plan_len():
    cfg = PlanConfig(horizon=5, receding_horizon=2, action_block=3)
    assert cfg.plan_len == 15 and cfg.history_len == 1 and cfg.warm_start is True
    with pytest.raises(dataclasses.FrozenInstanceError):
        cfg.horizon = 3  # type: ignore[misc]
    assert swm.PlanConfig is PlanConfig


@pytest.mark.parametrize(
    "kwargs, field",
    [
        (dict(horizon=0, receding_horizon=1), "horizon"),
        (dict(horizon=3, receding_horizon=4), "receding_horizon"),
        (dict(horizon=3, receding_horizon=1, action_block=0), "action_block"),
        (dict(horizon=2.5, receding_horizon=1), "horizon"),
        (dict(horizon=3, receding_horizon=1, history_len=True), "history_len"),
    ],
)
def test_plan_config_validates(kwargs, field):
    with pytest.raises(ConfigError, match=field):
        PlanConfig(**kwargs)


def test_transformable_protocol():
    class Scaler:
        def transform(self, x):
            return x * 2

        def inverse_transform(self, x):
            return x / 2

    assert isinstance(Scaler(), Transformable)
    assert not isinstance(object(), Transformable)


def test_unknown_expert_env():
    with pytest.raises(KeyError, match="swm/TwoRoom-v2"):
        swm.envs.expert_policy("swm/TwoRom-v1")

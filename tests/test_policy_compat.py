"""Policy behaviours of the original release (0.0.3, same in upstream 0.1.1) that stay available.

Observed there: ``_load_model_with_attribute`` and ``BasePolicy._prepare_info`` exist,
``ExpertPolicy.get_action`` returns None, the Auto* loaders raise ``RuntimeError`` when no
module has the method, ``RandomPolicy.set_env`` does not reseed, ``FeedForwardPolicy``
returns the model's inverse-transformed output and keeps ``process`` as given, and
``WorldModelPolicy`` has ``flatten_receding_horizon`` and accepts an env without ``num_envs``.
"""

from __future__ import annotations

import inspect

import gymnasium as gym
import numpy as np
import pytest
import torch

import stable_worldmodel as swm
from stable_worldmodel.errors import ConfigError
from stable_worldmodel.policy import (
    AutoActionableModel,
    AutoCostModel,
    BasePolicy,
    ExpertPolicy,
    FeedForwardPolicy,
    PlanConfig,
    RandomPolicy,
    WorldModelPolicy,
)
from stable_worldmodel.solver import CEMSolver


class FakeVecEnv:
    def __init__(self, space):
        self.action_space = space
        self.num_envs = space.shape[0]


class Double:
    """A fitted processor: ``transform`` doubles, ``inverse_transform`` halves."""

    def transform(self, x):
        return x * 2

    def inverse_transform(self, x):
        return x / 2


# -- checkpoint loading -----------------------------------------------------------------------
class Head(torch.nn.Module):
    def __init__(self):
        super().__init__()
        self.lin = torch.nn.Linear(2, 1)
        self.scale = 3.0  # a plain (non-callable) attribute

    def get_cost(self, info, candidates):
        return candidates.sum(dim=(2, 3))


class Outer(torch.nn.Module):
    def __init__(self):
        super().__init__()
        self.head = Head()


def test_load_model_with_attribute_has_the_seed_signature(_stablewm_home):
    from stable_worldmodel.policy import _load_model_with_attribute

    params = list(inspect.signature(_load_model_with_attribute).parameters.values())
    assert [p.name for p in params[:3]] == ["run_name", "attribute_name", "cache_dir"]
    assert params[2].default is None

    _stablewm_home.mkdir(parents=True, exist_ok=True)
    torch.save(Outer().train(), _stablewm_home / "run_object.ckpt")
    with pytest.warns(UserWarning, match="pickled checkpoint"):
        found = _load_model_with_attribute("run", "scale")  # any attribute, not only methods
    assert isinstance(found, Head) and not found.training  # the sub-module, in eval mode
    with pytest.warns(UserWarning), pytest.raises(RuntimeError, match="No module with 'missing' found"):
        _load_model_with_attribute("run", "missing")


@pytest.mark.parametrize("loader, method", [(AutoCostModel, "get_cost"), (AutoActionableModel, "get_action")])
def test_auto_loaders_raise_runtime_error_and_config_error(_stablewm_home, loader, method):
    _stablewm_home.mkdir(parents=True, exist_ok=True)
    torch.save(torch.nn.Linear(2, 2), _stablewm_home / "plain_object.ckpt")
    with pytest.warns(UserWarning), pytest.raises(RuntimeError, match=f"No module with '{method}' found") as info:
        loader("plain")
    assert isinstance(info.value, ConfigError)  # ours stays a typed ConfigError too


# -- BasePolicy / ExpertPolicy / RandomPolicy -----------------------------------------------------
def test_prepare_info_converts_and_applies_process_and_transform():
    assert list(inspect.signature(BasePolicy._prepare_info).parameters) == ["self", "info_dict"]
    info = {"state": np.ones((2, 1, 3), np.float32), "name": np.array(["a", "b"])}
    plain = BasePolicy()._prepare_info(info)
    assert torch.is_tensor(plain["state"]) and plain["state"].shape == (2, 1, 3)
    assert isinstance(plain["name"], np.ndarray)  # strings stay numpy, as in 0.0.3

    policy = BasePolicy(process={"state": Double()}, transform={"state": lambda x: x + 1})
    out = policy._prepare_info(info)
    torch.testing.assert_close(out["state"], torch.full((2, 1, 3), 3.0))
    assert isinstance(info["state"], np.ndarray)  # ours never modifies the World's infos


def test_expert_policy_get_action_returns_none():
    assert ExpertPolicy().get_action({}, None) is None
    assert ExpertPolicy().get_action({}) is None


def test_random_policy_set_env_does_not_reseed():
    space = gym.spaces.Box(-1, 1, (2, 2), np.float32)
    reference = gym.spaces.Box(-1, 1, (2, 2), np.float32)
    space.seed(11)
    reference.seed(11)
    policy = RandomPolicy(seed=3)
    policy.set_env(FakeVecEnv(space))
    np.testing.assert_array_equal(policy.get_action({}), reference.sample())  # the stream went on untouched
    policy.set_seed(3)  # the seed is applied by set_seed (World.set_policy calls it once)
    reference.seed(3)
    np.testing.assert_array_equal(policy.get_action({}), reference.sample())


def test_world_set_policy_seeds_the_random_policy_once():
    def first_actions():
        world = swm.World("swm/Toy-v0", num_envs=2, image_shape=(8, 8), verbose=0, vectorization_mode="sync")
        world.set_policy(RandomPolicy(seed=5))
        return world.policy.get_action({})

    np.testing.assert_array_equal(first_actions(), first_actions())


# -- FeedForwardPolicy ----------------------------------------------------------------------------
class Actor(torch.nn.Module):
    def __init__(self, value):
        super().__init__()
        self.lin = torch.nn.Linear(1, 1)
        self.value = value
        self.seen = None

    def get_action(self, info):
        self.seen = info
        return torch.full((2, 2), self.value)


def test_feed_forward_returns_the_inverse_transformed_model_output():
    process = {"action": Double()}
    transform = {}
    model = Actor(5.0).train()
    policy = FeedForwardPolicy(model, process=process, transform=transform)
    assert policy.process is process and policy.transform is transform  # kept, not copied
    assert not model.training
    policy.set_env(FakeVecEnv(gym.spaces.Box(-1, 1, (2, 2), np.float32)))
    action = policy.get_action({"goal": np.zeros((2, 1, 4, 4, 3), np.uint8), "x": np.ones((2, 1, 3), np.float32)})
    assert isinstance(action, np.ndarray) and action.dtype == np.float32
    np.testing.assert_array_equal(action, np.full((2, 2), 2.5))  # 5 / 2, not clipped to the bounds
    assert "goal_pixels" in model.seen  # the GCBC key of 0.0.3


def test_feed_forward_without_process_returns_the_raw_output():
    policy = FeedForwardPolicy(Actor(7.0))
    assert policy.process == {} and policy.transform == {}
    policy.set_env(FakeVecEnv(gym.spaces.Box(-1, 1, (2, 2), np.float32)))
    np.testing.assert_array_equal(policy.get_action({}), np.full((2, 2), 7.0))


# -- WorldModelPolicy -----------------------------------------------------------------------------
class Toward:
    def __init__(self, target):
        self.target = target

    def get_cost(self, info, candidates):
        return ((candidates - self.target) ** 2).sum(dim=(2, 3))


def test_flatten_receding_horizon():
    policy = WorldModelPolicy(CEMSolver(Toward(0.0)), PlanConfig(horizon=5, receding_horizon=2, action_block=3))
    assert policy.flatten_receding_horizon == 6


def test_world_model_policy_on_one_env_without_num_envs():
    class OneEnv:
        action_space = gym.spaces.Box(-1, 1, (2,), np.float32)

    solver = CEMSolver(Toward(0.5), num_samples=32, n_steps=5, topk=4)
    policy = WorldModelPolicy(solver, PlanConfig(horizon=2, receding_horizon=1))
    policy.set_env(OneEnv())
    assert solver.n_envs == 1 and solver.action_space.shape == (1, 2)
    action = policy.get_action({"state": np.zeros((1, 3), np.float32)})  # one env's infos: (T, ...)
    assert action.shape == (2,) and OneEnv.action_space.contains(action)
    np.testing.assert_allclose(action, 0.5, atol=0.15)

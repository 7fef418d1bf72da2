"""WorldModelPolicy with a fake vector env: receding-horizon bookkeeping, warm start, shapes, errors."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
import torch

from stable_worldmodel.errors import ConfigError, UnknownNameError
from stable_worldmodel.policy import PlanConfig, WorldModelPolicy
from stable_worldmodel.solver import CEMSolver, Solver

BOX = gym.spaces.Box(-10.0, 10.0, (2,), np.float32)


class FakeEnv:
    def __init__(self, n=2, single=BOX):
        self.num_envs = n
        self.single_action_space = single
        self.action_space = gym.vector.utils.batch_space(single, n)


class ScriptedSolver:
    """A Solver whose plan ``k`` (k-th solve) holds ``k + 0.01 * block + 0.001 * column``."""

    def __init__(self):
        self.calls, self.configured = [], None

    def configure(self, *, action_space, n_envs, config):
        self.configured = (action_space, n_envs, config)

    @property
    def n_envs(self):
        return None if self.configured is None else self.configured[1]

    @property
    def horizon(self):
        return self.configured[2].horizon

    @property
    def action_dim(self):
        space, _, config = self.configured
        return int(np.prod(space.shape[1:])) * config.action_block

    def solve(self, info_dict, init_action=None):
        self.calls.append((info_dict, init_action))
        k = len(self.calls)
        h, a = self.horizon, self.action_dim
        plan = k + 0.01 * torch.arange(h)[:, None] + 0.001 * torch.arange(a)[None, :]
        return {"actions": plan.expand(self.n_envs, h, a).clone()}

    __call__ = solve


def make_policy(config, env=None, **kwargs):
    solver = ScriptedSolver()
    policy = WorldModelPolicy(solver, config, **kwargs)
    policy.set_env(env or FakeEnv())
    return policy, solver


INFO = {"state": np.zeros((2, 1, 3), np.float32)}


def test_set_env_configures_the_solver():
    env = FakeEnv(n=3)
    config = PlanConfig(horizon=4, receding_horizon=2, action_block=3)
    policy, solver = make_policy(config, env)
    space, n, cfg = solver.configured
    assert isinstance(solver, Solver) and n == 3 and cfg is config and space.shape == (3, 2)
    assert policy.config is config and policy.type == "world_model"


def test_replans_every_receding_horizon_blocks_and_queues_them_in_order():
    config = PlanConfig(horizon=4, receding_horizon=2, action_block=3)
    policy, solver = make_policy(config)
    actions = [policy.get_action(INFO) for _ in range(13)]
    assert len(solver.calls) == 3  # calls 0, 6 and 12 replan (2 blocks x 3 steps)
    assert all(a.shape == (2, 2) and a.dtype == np.float32 for a in actions)
    # step i of a plan: block i // 3, columns 2 * (i % 3) and 2 * (i % 3) + 1 of that block
    for i in range(6):
        block, col = divmod(i, 3)
        expected = 1 + 0.01 * block + 0.001 * np.array([2 * col, 2 * col + 1])
        assert np.allclose(actions[i], np.broadcast_to(expected, (2, 2)), atol=1e-6)
    assert np.allclose(actions[6][0, 0], 2.0) and np.allclose(actions[12][0, 0], 3.0)


def test_warm_start_passes_the_rest_of_the_plan():
    policy, solver = make_policy(PlanConfig(horizon=4, receding_horizon=1, action_block=2))
    for _ in range(5):
        policy.get_action(INFO)
    assert solver.calls[0][1] is None
    warm = solver.calls[1][1]
    assert warm.shape == (2, 3, 4)  # (B, H - receding_horizon, A)
    assert torch.allclose(warm[0, :, 0], torch.tensor([1.01, 1.02, 1.03]))
    cold, cold_solver = make_policy(PlanConfig(horizon=4, receding_horizon=1, action_block=2, warm_start=False))
    for _ in range(3):
        cold.get_action(INFO)
    assert all(init is None for _, init in cold_solver.calls)
    full, full_solver = make_policy(PlanConfig(horizon=2, receding_horizon=2))
    for _ in range(3):
        full.get_action(INFO)
    assert full_solver.calls[1][1] is None  # nothing left to warm-start with


def test_reset_plan_forces_a_replan_without_warm_start():
    policy, solver = make_policy(PlanConfig(horizon=3, receding_horizon=2))
    policy.get_action(INFO)
    policy.reset_plan()
    policy.get_action(INFO)
    assert len(solver.calls) == 2 and solver.calls[1][1] is None


def test_the_model_gets_the_last_history_len_frames():
    infos = {"state": np.arange(2 * 4 * 3, dtype=np.float32).reshape(2, 4, 3), "step_idx": np.ones((2, 4), np.int64)}
    for history in (1, 2, 4):
        policy, solver = make_policy(PlanConfig(horizon=2, receding_horizon=1, history_len=history))
        policy.get_action(infos)
        got = solver.calls[0][0]
        assert got["state"].shape == (2, history, 3) and tuple(got["step_idx"].shape) == (2, history)
        np.testing.assert_array_equal(np.asarray(got["state"]), infos["state"][:, -history:])
    policy, solver = make_policy(PlanConfig(horizon=2, receding_horizon=1))
    policy.get_action({"state": infos["state"][:, 0]})  # (B, 3) without step_idx: not World infos, left whole
    assert solver.calls[0][0]["state"].shape == (2, 3)


class Scale:
    def __init__(self, k):
        self.k = k

    def transform(self, x):
        return x * self.k

    def inverse_transform(self, x):
        return x / self.k


def test_action_process_sets_solver_bounds_and_is_inverted():
    env = FakeEnv(single=gym.spaces.Box(-1.0, 1.0, (2,), np.float32))
    process = {"action": Scale(4.0), "state": Scale(2.0)}
    policy, solver = make_policy(PlanConfig(horizon=2, receding_horizon=1), env, process=process)
    space = solver.configured[0]
    assert np.allclose(space.low, -4.0) and np.allclose(space.high, 4.0)
    action = policy.get_action({"state": np.ones((2, 1, 3), np.float32)})
    assert np.allclose(action, np.broadcast_to([0.25, 0.25 + 0.00025], (2, 2)))  # plan 1.0.. / 4
    info = solver.calls[0][0]
    assert torch.is_tensor(info["state"]) and torch.allclose(info["state"], torch.full((2, 1, 3), 2.0))


def test_discrete_env_gets_integer_actions():
    env = FakeEnv(n=2, single=gym.spaces.Discrete(5))
    policy, _ = make_policy(PlanConfig(horizon=2, receding_horizon=1), env)
    action = policy.get_action(INFO)
    assert action.shape == (2,) and action.dtype == env.action_space.dtype and action.tolist() == [1, 1]


def test_errors_are_clear():
    config = PlanConfig(horizon=2, receding_horizon=1)
    with pytest.raises(ConfigError, match="Solver"):
        WorldModelPolicy(object(), config)
    with pytest.raises(ConfigError, match="PlanConfig"):
        WorldModelPolicy(ScriptedSolver(), {"horizon": 2})
    with pytest.raises(ConfigError, match="inverse_transform"):
        WorldModelPolicy(ScriptedSolver(), config, process={"action": object()})
    with pytest.raises(RuntimeError, match="set_env"):
        WorldModelPolicy(ScriptedSolver(), config).get_action(INFO)

    class NeedsGoal:
        def get_cost(self, info, candidates):
            return (info["goal_state"] - candidates).sum(dim=(2, 3))

    policy = WorldModelPolicy(CEMSolver(NeedsGoal(), num_samples=4, n_steps=1, topk=2), config)
    policy.set_env(FakeEnv())
    with pytest.raises(UnknownNameError, match="'goal_state'.*state"):
        policy.get_action(INFO)


def test_with_a_real_solver_actions_follow_the_cost():
    class Target:
        def get_cost(self, info, candidates):  # target per env from the info: (B, S, 1, 2)
            return ((candidates - info["target"][:, :, :1].repeat(1, 1, 1, 2)) ** 2).sum(dim=(2, 3))

    config = PlanConfig(horizon=2, receding_horizon=1, action_block=2)
    policy = WorldModelPolicy(CEMSolver(Target(), num_samples=64, n_steps=10, topk=8), config)
    policy.set_env(FakeEnv())
    target = np.array([[[0.5, -0.5]], [[-0.25, 0.75]]], np.float32)  # (B, T=1, 2)
    first, second = policy.get_action({"target": target}), policy.get_action({"target": target})
    assert np.allclose(first, target[:, 0], atol=0.1) and np.allclose(second, target[:, 0], atol=0.1)

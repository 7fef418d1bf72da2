"""PGDSolver: projected gradient descent on the simplex relaxation of discrete actions."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
import torch

from stable_worldmodel.errors import SpaceError
from stable_worldmodel.policy import PlanConfig
from stable_worldmodel.solver import PGDSolver, Solver
from stable_worldmodel.solver.discrete_solvers import project_simplex


class Table:
    """Linear cost ``sum_c p_c * table[b, h, j, c]``: the optimum picks ``argmin_c table``."""

    def __init__(self, table):
        self.table = table  # (B, H, A, n)
        self.shapes = []

    def get_cost(self, info, candidates):
        self.shapes.append(tuple(candidates.shape))
        b, s, h, _ = candidates.shape
        probs = candidates.reshape(b, s, h, *self.table.shape[2:])
        return (probs * self.table.unsqueeze(1)).sum(dim=(2, 3, 4))


def make(table, n_envs=3, action_block=2, **kwargs):
    solver = PGDSolver(Table(table), **{"n_steps": 30, "num_samples": 2, "optimizer_kwargs": {"lr": 0.5}, **kwargs})
    space = gym.vector.utils.batch_space(gym.spaces.Discrete(table.shape[-1]), n_envs)
    solver.configure(action_space=space, n_envs=n_envs, config=PlanConfig(table.shape[1], 1, action_block=action_block))
    return solver


def test_project_simplex_is_a_projection():
    v = torch.tensor([[0.2, 0.3, 0.5], [2.0, -1.0, 0.0], [0.5, 0.5, 0.5]])
    p = project_simplex(v)
    assert torch.allclose(p.sum(-1), torch.ones(3)) and (p >= 0).all()
    assert torch.allclose(p[0], v[0]) and torch.allclose(p[1], torch.tensor([1.0, 0.0, 0.0]))
    assert torch.allclose(p[2], torch.full((3,), 1 / 3))


def test_pgd_finds_the_integer_optimum_for_several_envs():
    gen = torch.Generator().manual_seed(0)
    table = torch.rand(3, 2, 2, 4, generator=gen)  # B=3, H=2, A=action_block=2, n=4
    solver = make(table)
    assert isinstance(solver, Solver)
    assert (solver.action_dim, solver.n_choices, solver.action_simplex_dim) == (2, 4, 8)
    out = solver.solve({})
    assert out["actions"].dtype == torch.int64 and out["actions"].shape == (3, 2, 2)
    assert torch.equal(out["actions"], table.argmin(dim=-1))
    assert torch.allclose(out["costs"], table.min(dim=-1).values.sum(dim=(1, 2)))
    assert solver.model.shapes[0] == (3, 2, 2, 8)  # relaxed candidates (B, S, H, A * n)


def test_pgd_warm_start_and_padding():
    table = torch.zeros(2, 3, 1, 3)  # flat cost: nothing moves the warm start
    solver = make(table, n_envs=2, action_block=1, var_scale=1e-9, optimizer_kwargs={"lr": 0.0})
    init = torch.tensor([[[2], [1]], [[0], [2]]])  # (B, k=2, A=1)
    out = solver.solve({}, init_action=init)
    assert torch.equal(out["actions"][:, :2], init)


def test_pgd_rejects_continuous_spaces():
    solver = PGDSolver(Table(torch.zeros(1, 1, 1, 2)), n_steps=1)
    with pytest.raises(SpaceError, match="discrete"):
        solver.configure(action_space=gym.spaces.Box(-1, 1, (2, 1)), n_envs=2, config=PlanConfig(1, 1))
    with pytest.raises(SpaceError, match="equal nvec"):
        solver.configure(action_space=gym.spaces.MultiDiscrete(np.array([3, 4])), n_envs=2, config=PlanConfig(1, 1))

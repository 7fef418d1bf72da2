"""Solver behaviours of the original release (0.0.3) and of upstream 0.1.1 that stay available.

Each test states what was observed on those releases: PGD on a single ``Discrete(n)`` space
with ``init_action(actions, from_scalar)``, ``init_action_distrib`` on the sampling solvers,
``init_action`` on the gradient solver, ``var_scale=0`` as "no noise", and upstream's
planning-side ``CEMSolver(cost=...)``.
"""

from __future__ import annotations

import inspect

import gymnasium as gym
import numpy as np
import pytest
import torch

from stable_worldmodel.errors import ConfigError, SpaceError
from stable_worldmodel.policy import PlanConfig
from stable_worldmodel.solver import CEMSolver, GradientSolver, ICEMSolver, MPPISolver, PGDSolver, RandomSolver


class Target:
    """Quadratic cost with its minimum at ``target`` in every block: ``(B, S, H, A) -> (B, S)``."""

    def __init__(self, target):
        self.target = torch.as_tensor(target, dtype=torch.float32)

    def get_cost(self, info, candidates):
        return ((candidates - self.target) ** 2).sum(dim=(2, 3))


def one_hot_target(n, choice):
    target = torch.zeros(n)
    target[choice] = 1.0
    return Target(target)


# -- PGD on a single Discrete(n), as in 0.0.3 --------------------------------------------------
def test_pgd_configures_with_the_single_discrete_space():
    solver = PGDSolver(one_hot_target(4, 2), n_steps=5, num_samples=4, var_scale=0.1, optimizer_kwargs={"lr": 1.0})
    solver.configure(action_space=gym.spaces.Discrete(4), n_envs=2, config=PlanConfig(3, 1))
    # 0.0.3: action_dim 1 (x action_block), action_simplex_dim n (x action_block), horizon 3
    assert (solver.n_envs, solver.horizon, solver.action_dim, solver.action_simplex_dim) == (2, 3, 1, 4)
    out = solver.solve({"x": torch.zeros(2, 1)})
    assert out["actions"].shape == (2, 3, 1) and out["actions"].dtype == torch.int64
    assert (out["actions"] == 2).all()


def test_pgd_single_discrete_with_action_blocks():
    target = Target([0.0, 1.0, 0.0, 0.0, 0.0, 1.0])  # block of 2 actions: choice 1, then choice 2
    solver = PGDSolver(target, n_steps=3, num_samples=2, optimizer_kwargs={"lr": 1.0})
    solver.configure(action_space=gym.spaces.Discrete(3), n_envs=1, config=PlanConfig(2, 1, action_block=2))
    assert (solver.action_dim, solver.action_simplex_dim) == (2, 6)
    actions = solver.solve({})["actions"]
    assert actions.shape == (1, 2, 2) and actions[0].tolist() == [[1, 2], [1, 2]]


def test_pgd_refuses_a_box_with_the_original_phrase():
    solver = PGDSolver(one_hot_target(2, 0), n_steps=1)
    with pytest.raises(SpaceError, match="must be discrete"):
        solver.configure(action_space=gym.spaces.Box(-1, 1, (2,)), n_envs=2, config=PlanConfig(2, 1))


def test_pgd_init_action_fills_init_like_the_original():
    solver = PGDSolver(one_hot_target(4, 0), n_steps=1, num_samples=3, var_scale=0.5)
    solver.configure(action_space=gym.spaces.Discrete(4), n_envs=2, config=PlanConfig(3, 1))
    assert solver.init_action() is None  # 0.0.3 returns None and stores the start in .init
    assert solver.init.shape == (2, 3, 3, 4)  # (B, S, H, action_simplex_dim)

    actions = torch.tensor([[[1]], [[3]]])  # (B, k=1, action_block) integers
    solver.init_action(actions, from_scalar=True)
    first = solver.init[:, 0, 0]  # sample 0, block 0: the warm start itself
    torch.testing.assert_close(first, torch.nn.functional.one_hot(actions[:, 0, 0], 4).float())
    assert torch.allclose(solver.init.sum(-1), torch.ones(2, 3, 3))  # every point on the simplex

    scalar_init = solver.init.clone()
    solver.init_action(torch.nn.functional.one_hot(actions, 4).float().flatten(-2))  # the soft form
    torch.testing.assert_close(solver.init, scalar_init)


def test_pgd_solve_takes_from_scalar():
    solver = PGDSolver(one_hot_target(3, 0), n_steps=2, num_samples=2, var_scale=0.0, optimizer_kwargs={"lr": 0.0})
    solver.configure(action_space=gym.spaces.Discrete(3), n_envs=2, config=PlanConfig(2, 1))
    warm = torch.tensor([[[2], [1]], [[1], [2]]])
    out = solver.solve({}, init_action=warm, from_scalar=True)
    torch.testing.assert_close(out["actions"], warm)  # lr 0 and no noise: the plan is the warm start
    torch.testing.assert_close(solver({}, init_action=warm, from_scalar=True)["actions"], warm)
    with pytest.raises(ConfigError, match=r"in \[0, 3\)"):
        solver.solve({}, init_action=torch.tensor([[[3]], [[0]]]), from_scalar=True)


# -- init_action_distrib (CEM, MPPI) and init_action (GD) ----------------------------------------
@pytest.mark.parametrize("cls", [CEMSolver, MPPISolver, ICEMSolver])
def test_init_action_distrib_returns_mean_and_var(cls):
    solver = cls(Target(0.0), num_samples=4, topk=2, n_steps=1, var_scale=0.3)
    solver.configure(action_space=gym.spaces.Box(-1, 1, (2, 3)), n_envs=2, config=PlanConfig(4, 1, action_block=2))
    mean, var = solver.init_action_distrib()
    assert mean.shape == var.shape == (2, 4, 6)
    assert (mean == 0).all() and torch.allclose(var, torch.full((2, 4, 6), 0.3))

    warm = torch.full((2, 1, 6), 0.5)
    mean, _ = solver.init_action_distrib(warm)  # 0.0.3 form: padded with zeros to the horizon
    assert (mean[:, 0] == 0.5).all() and (mean[:, 1:] == 0).all()
    mean_011, var_011 = solver.init_action_distrib(2, warm)  # upstream 0.1.1 form: (n_envs, actions)
    torch.testing.assert_close(mean_011, mean)
    with pytest.raises(ConfigError, match="n_envs"):
        solver.init_action_distrib(3)


def test_gradient_init_action_matches_the_next_solve():
    space, config = gym.spaces.Box(-2, 2, (2, 3)), PlanConfig(4, 1)
    solver = GradientSolver(Target(0.0), n_steps=1, num_samples=3, var_scale=0.5, optimizer_kwargs={"lr": 0.0})
    solver.configure(action_space=space, n_envs=2, config=config)
    assert solver.init_action(torch.ones(2, 2, 3)) is None
    assert solver.init.shape == (2, 3, 4, 3)  # (B, S, H, A)
    assert (solver.init[:, 0, :2] == 1).all() and (solver.init[:, 0, 2:] == 0).all()  # sample 0: padded warm start
    assert not torch.equal(solver.init[:, 1], solver.init[:, 0])  # the other samples are perturbed

    solver.init_action()
    drawn = solver.init.clone()
    # with lr 0 the solve keeps its start: its best sample is one of the drawn ones, and the
    # random stream was not advanced by init_action (a second call draws the same)
    best = solver.solve({})["actions"]
    assert any(torch.allclose(best[0], drawn[0, s]) for s in range(3))
    solver.init_action()
    assert not torch.equal(solver.init, drawn)  # the stream moved on with the solve


# -- var_scale = 0 ---------------------------------------------------------------------------------
@pytest.mark.parametrize(
    "make",
    [
        lambda m: CEMSolver(m, num_samples=6, topk=2, n_steps=3, var_scale=0),
        lambda m: MPPISolver(m, num_samples=6, topk=2, n_steps=3, var_scale=0),
        lambda m: ICEMSolver(m, num_samples=6, topk=2, n_steps=3, var_scale=0),
        lambda m: RandomSolver(m, num_samples=6, var_scale=0),
        lambda m: GradientSolver(m, n_steps=2, num_samples=3, var_scale=0, optimizer_kwargs={"lr": 0.0}),
    ],
    ids=["cem", "mppi", "icem", "random", "gd"],
)
def test_var_scale_zero_means_no_noise(make):
    solver = make(Target(0.5))
    unbounded = gym.spaces.Box(-np.inf, np.inf, (2, 2), np.float32)
    solver.configure(action_space=unbounded, n_envs=2, config=PlanConfig(3, 1))
    assert solver.var_scale == 0
    warm = torch.full((2, 3, 2), -0.25)
    torch.testing.assert_close(solver.solve({}, init_action=warm)["actions"], warm)  # never leaves the start


def test_var_scale_zero_in_init_action_distrib_and_gd_init():
    cem = CEMSolver(Target(0.0), num_samples=4, topk=2, var_scale=0)
    cem.configure(action_space=gym.spaces.Box(-1, 1, (1, 2)), n_envs=1, config=PlanConfig(2, 1))
    assert (cem.init_action_distrib()[1] == 0).all()
    gd = GradientSolver(Target(0.0), n_steps=1, num_samples=3, var_scale=0)
    gd.configure(action_space=gym.spaces.Box(-1, 1, (1, 2)), n_envs=1, config=PlanConfig(2, 1))
    gd.init_action()
    assert (gd.init == 0).all()


def test_gradient_solver_names_a_cost_without_graph():
    class Detached(Target):
        def get_cost(self, info, candidates):
            return super().get_cost(info, candidates.detach())

    solver = GradientSolver(Detached(0.0), n_steps=1)
    solver.configure(action_space=gym.spaces.Box(-1, 1, (1, 2)), n_envs=1, config=PlanConfig(2, 1))
    with pytest.raises(ConfigError, match="Cost must requires_grad for GD solver"):
        solver.solve({})


# -- upstream 0.1.1's planning-side CEMSolver(cost=...) -------------------------------------------
def test_planning_cem_signature_is_upstreams():
    from stable_worldmodel.planning import CEMSolver as PlanningCEM

    params = inspect.signature(PlanningCEM).parameters
    assert list(params) == [
        "cost",
        "batch_size",
        "num_samples",
        "var_scale",
        "n_steps",
        "topk",
        "device",
        "seed",
        "callbacks",
    ]
    defaults = {name: p.default for name, p in params.items() if name != "cost"}
    assert defaults == {
        "batch_size": 1,
        "num_samples": 300,
        "var_scale": 1,
        "n_steps": 30,
        "topk": 30,
        "device": "cpu",
        "seed": 1234,
        "callbacks": None,
    }
    from stable_worldmodel.planning.solver import CEMSolver as A
    from stable_worldmodel.planning.solver.cem import CEMSolver as B

    assert A is B is PlanningCEM


@pytest.mark.parametrize("as_function", [False, True])
def test_planning_cem_plans_against_a_cost(as_function):
    from stable_worldmodel.planning import CEMSolver as PlanningCEM

    target = Target(0.5)
    cost = target.get_cost if as_function else target
    space, config = gym.spaces.Box(-1, 1, (2, 2)), PlanConfig(3, 1)
    planning = PlanningCEM(cost=cost, num_samples=64, n_steps=8, topk=8, seed=7)
    model_side = CEMSolver(target, num_samples=64, n_steps=8, topk=8, seed=7)
    for solver in (planning, model_side):
        solver.configure(action_space=space, n_envs=2, config=config)
    assert planning.cost is cost
    out = planning.solve({})
    torch.testing.assert_close(out["actions"], model_side.solve({})["actions"])  # the same algorithm
    assert torch.allclose(out["actions"], torch.full((2, 3, 2), 0.5), atol=0.1)
    assert {"actions", "costs", "mean", "var"} <= set(out)


def test_planning_cem_refuses_what_it_cannot_use():
    from stable_worldmodel.planning import CEMSolver as PlanningCEM

    with pytest.raises(ConfigError, match="requires cost"):
        PlanningCEM(cost=42)
    with pytest.raises(ConfigError, match="callbacks"):
        PlanningCEM(cost=Target(0.0), callbacks=[object()])
    PlanningCEM(cost=Target(0.0), callbacks=[])


def test_nevergrad_still_needs_a_positive_sigma():
    pytest.importorskip("nevergrad")
    from stable_worldmodel.solver import NevergradSolver

    with pytest.raises(ConfigError, match="var_scale"):
        NevergradSolver(Target(0.0), var_scale=0)

"""The cost layer of upstream's main: ``ShootingCostEvaluator`` composing a world model's
encode/rollout with objectives (``GoalMSE``, ``ControlPenalty``, ``WeightedSum``), the
``stable_worldmodel.protocols`` it is typed against, and the solvers consuming it."""

from __future__ import annotations

import sys
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest
import torch

from stable_worldmodel import keys
from stable_worldmodel.errors import ConfigError
from stable_worldmodel.planning import (
    ControlPenalty,
    GoalMSE,
    LagrangianSolver,
    ShootingCostEvaluator,
    WeightedSum,
)
from stable_worldmodel.policy import PlanConfig
from stable_worldmodel.protocols import Actionable, Constrainable, Costable, Dynamics, Objective
from stable_worldmodel.solver import CEMSolver

sys.path.insert(0, str(Path(__file__).parents[1] / "wm"))
from _tiny import IMAGE, condition_on_actions, images, make_tiny, randn  # noqa: E402 - the shared tiny models

A = 2


@pytest.fixture(scope="module")
def lewm():
    return condition_on_actions(make_tiny("lewm")).eval()


def infos(b=2, s=5):
    """The per-candidate views the solvers pass: ``(B, S, T, C, H, W)`` of one copy per env."""
    ctx, goal = images(b, 1), images(b, 1, seed=1)
    shape = (b, s, 1, 3, IMAGE, IMAGE)
    return {keys.PIXELS: ctx.unsqueeze(1).expand(shape), keys.GOAL: goal.unsqueeze(1).expand(shape)}


def test_goal_mse_reproduces_the_models_own_cost(lewm):
    evaluator = ShootingCostEvaluator(lewm, GoalMSE())
    candidates = randn(2, 5, 3, A)
    with torch.no_grad():
        ours, model = evaluator.get_cost(infos(), candidates), lewm.get_cost(infos(), candidates)
    assert ours.shape == (2, 5)
    torch.testing.assert_close(ours, model)
    assert isinstance(evaluator, Costable) and isinstance(lewm, Dynamics) and isinstance(lewm, Costable)
    assert list(evaluator.parameters())  # the model is a submodule: solvers find its dtype and device


def test_weighted_sum_adds_an_action_cost_the_model_never_knew(lewm):
    candidates = randn(2, 5, 3, A)
    info = infos()
    with torch.no_grad():
        goal = ShootingCostEvaluator(lewm, GoalMSE()).get_cost(infos(), candidates)
        both = ShootingCostEvaluator(lewm, WeightedSum([(1.0, GoalMSE()), (0.5, ControlPenalty())])).get_cost(
            info, candidates
        )
    torch.testing.assert_close(both, goal + 0.5 * candidates.square().sum(dim=(2, 3)))
    assert torch.equal(info["action_candidates"], candidates) and "goal_emb" in info
    assert isinstance(GoalMSE(), Objective) and not isinstance(GoalMSE(), Actionable)


def test_constraints_are_exposed_for_the_lagrangian_solver(lewm):
    limit = 0.5
    budget = ShootingCostEvaluator(lewm, GoalMSE(), constraints=[lambda info: ControlPenalty()(info) - limit])
    plain = ShootingCostEvaluator(lewm, GoalMSE())
    assert isinstance(budget, Constrainable) and not isinstance(plain, Constrainable)
    with torch.no_grad():
        g = budget.get_constraints(infos(), randn(2, 5, 3, A))
    assert g.shape == (2, 5, 1)
    solver = LagrangianSolver(budget, n_steps=6, n_outer_steps=3, optimizer_kwargs={"lr": 0.2}, var_scale=0.5)
    solver.configure(action_space=gym.spaces.Box(-3, 3, (2, A), np.float32), n_envs=2, config=PlanConfig(3, 1))
    info = {k: v[:, 0] for k, v in infos().items()}
    out = solver.solve(info)
    assert out["actions"].shape == (2, 3, A)
    assert (out["actions"].square().sum(dim=(1, 2)) <= limit + 0.05).all()  # the control budget holds


def test_a_sampling_solver_plans_through_it(lewm):
    evaluator = ShootingCostEvaluator(lewm, WeightedSum([(1.0, GoalMSE()), (1e-3, ControlPenalty())]))
    solver = CEMSolver(evaluator, num_samples=16, n_steps=3, topk=4)
    solver.configure(action_space=gym.spaces.Box(-1, 1, (2, A), np.float32), n_envs=2, config=PlanConfig(3, 1))
    out = solver.solve({k: v[:, 0] for k, v in infos().items()})
    assert out["actions"].shape == (2, 3, A) and torch.isfinite(out["costs"]).all()


def test_bad_parts_are_typed_errors(lewm):
    with pytest.raises(ConfigError, match="encode and rollout.*without encode, rollout"):
        ShootingCostEvaluator(torch.nn.Linear(2, 2), GoalMSE())
    with pytest.raises(ConfigError, match="callable objective"):
        ShootingCostEvaluator(lewm, "goal")
    with pytest.raises(ValueError, match="at least one"):
        WeightedSum([])
    with pytest.raises(KeyError, match="goal"):
        ShootingCostEvaluator(lewm, GoalMSE()).get_cost({keys.PIXELS: infos()[keys.PIXELS]}, randn(2, 5, 3, A))

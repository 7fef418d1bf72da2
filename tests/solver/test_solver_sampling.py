"""Algorithm-specific behaviour of the sampling solvers (iCEM noise and elite reuse, MPPI weighting)."""

from __future__ import annotations

import pytest
import torch
from _analytic import Bowl, configure, targets

from stable_worldmodel.errors import ConfigError
from stable_worldmodel.solver import ICEMSolver, MPPISolver
from stable_worldmodel.solver.icem import colored_noise


def test_colored_noise_has_unit_variance_and_is_smooth():
    white = torch.randn(20000, 16, generator=torch.Generator().manual_seed(0))
    red = colored_noise(white, beta=2.0)
    assert red.shape == white.shape
    assert torch.allclose(red.var(dim=0).mean(), torch.tensor(1.0), atol=0.05)
    lag1 = lambda x: (x[:, 1:] * x[:, :-1]).mean() / x.var()  # noqa: E731
    assert lag1(red) > 0.5 and abs(lag1(white)) < 0.05
    assert torch.equal(colored_noise(white, beta=0.0), white)


def test_icem_reuses_elites_in_the_next_iteration():
    model = Bowl()
    solver = configure(ICEMSolver(model, num_samples=10, n_steps=3, topk=5, elite_keep_frac=0.4), n_envs=2, horizon=4)
    solver.solve(targets([[0.1, 0.2]] * 2))
    assert [shape[1] for _, shape in model.calls] == [10, 12, 12]  # 2 kept elites from the 2nd iteration on
    with pytest.raises(ConfigError, match="elite_keep_frac"):
        ICEMSolver(Bowl(), elite_keep_frac=1.0)


def test_icem_returns_the_best_plan_seen():
    model = Bowl()
    solver = configure(ICEMSolver(model, num_samples=16, n_steps=4, topk=4), n_envs=2, horizon=3)
    info = targets([[0.3, -0.3], [0.0, 0.5]])
    out = solver.solve(info)
    recomputed = ((out["actions"] - info["target"][:, None]) ** 2).sum(dim=(1, 2))
    assert torch.allclose(out["costs"], recomputed, atol=1e-5)


class Scaled(Bowl):
    def __init__(self, k):
        super().__init__()
        self.k = k

    def get_cost(self, info, candidates):
        return self.k * super().get_cost(info, candidates)


def test_mppi_temperature_is_relative_to_the_cost_spread():
    def plan(k):
        solver = configure(MPPISolver(Scaled(k), num_samples=32, n_steps=5, topk=8, seed=0), n_envs=2, horizon=2)
        return solver.solve(targets([[0.4, -0.6], [0.1, 0.9]]))["actions"]

    assert torch.allclose(plan(1.0), plan(1000.0), atol=1e-5)
    with pytest.raises(ConfigError, match="temperature"):
        MPPISolver(Bowl(), temperature=0)

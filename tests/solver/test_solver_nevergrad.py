"""NevergradSolver (the ``nevergrad`` extra)."""

from __future__ import annotations

import pytest

pytest.importorskip("nevergrad")

import torch  # noqa: E402
from _analytic import Bowl, DoubleWell, configure, targets  # noqa: E402

from stable_worldmodel.errors import UnknownNameError  # noqa: E402
from stable_worldmodel.solver import NevergradSolver, Solver  # noqa: E402

pytestmark = pytest.mark.extra


def solve(model, rows, low=-1.0, high=1.0, **kwargs):
    solver = configure(NevergradSolver(model, n_steps=15, num_samples=8, seed=0, **kwargs), low=low, high=high)
    assert isinstance(solver, Solver)
    return solver.solve(targets(rows))


def test_finds_the_bowl_minimum_and_the_bound():
    inside = [[0.5, -0.3], [0.2, 0.6], [-0.7, 0.1]]
    assert torch.allclose(solve(Bowl(), inside)["actions"][:, 0], torch.tensor(inside), atol=0.05)
    outside = torch.tensor([[2.0, -3.0], [0.5, 5.0], [-4.0, -0.2]])
    out = solve(Bowl(), outside.tolist())
    assert torch.allclose(out["actions"][:, 0], outside.clamp(-1, 1), atol=0.05)
    assert torch.allclose(out["costs"], ((out["actions"][:, 0] - outside) ** 2).sum(dim=1), atol=1e-4)


def test_finds_the_deeper_well():
    wells = [[1.0, -1.0], [-1.0, -1.0], [1.0, 1.0]]
    out = solve(DoubleWell(), wells, low=-2.0, high=2.0)
    assert torch.allclose(out["actions"][:, 0], torch.tensor(wells), atol=0.1)


def test_same_seed_same_plans_and_unknown_optimizer():
    rows = [[0.5, -0.3]] * 3
    assert torch.equal(solve(Bowl(), rows)["actions"], solve(Bowl(), rows)["actions"])
    with pytest.raises(UnknownNameError, match="CMA"):
        NevergradSolver(Bowl(), optimizer="CMAA")

"""The fast path of the sampling solvers keeps the algorithm: same candidates, elites and refits as a plain loop."""

from __future__ import annotations

import os
import subprocess
import sys

import gymnasium as gym
import numpy as np
import pytest
import torch
from _analytic import Bowl, configure, targets

from stable_worldmodel.policy import PlanConfig
from stable_worldmodel.solver import CEMSolver, GradientSolver, make_solver
from stable_worldmodel.solver.icem import colored_noise, coloring_matrix


class Wavy:
    """A cost without ties: ``sum sin(3 a) + (a - target)^2`` (the reference loop needs a unique ranking)."""

    def __init__(self):
        self.candidates = []

    def get_cost(self, info, candidates):
        self.candidates.append(candidates.clone())
        target = info["target"].unsqueeze(2)
        return (torch.sin(3 * candidates) + (candidates - target) ** 2).sum(dim=(2, 3))


class Recorded(CEMSolver):
    """CEM whose noise draws are recorded, so a reference loop can replay them."""

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self.noise = []

    def _randn(self, *tail):
        noise = super()._randn(*tail)
        self.noise.append(noise.clone())
        return noise


def reference_cem(model, info, noises, low, high, var_scale, topk):
    """Textbook CEM on given noise: candidate 0 is the mean, clamp, top-k, refit mean and biased std."""
    b, _, h, a = noises[0].shape
    low, high = low[:, None, None], high[:, None, None]  # (B, 1, 1, A)
    mean = torch.zeros(b, h, a).clamp(low[:, 0], high[:, 0])
    std = torch.full((b, h, a), float(var_scale))
    info_s = {key: value.unsqueeze(1).expand(b, noises[0].shape[1], *value.shape[1:]) for key, value in info.items()}
    for noise in noises:
        noise = noise.clone()
        noise[:, 0] = 0
        candidates = torch.max(torch.min(mean.unsqueeze(1) + std.unsqueeze(1) * noise, high), low)
        costs = model.get_cost(info_s, candidates)
        order = costs.argsort(dim=1)[:, :topk]
        elites = candidates[torch.arange(b)[:, None], order]
        mean, std = elites.mean(dim=1), elites.std(dim=1, unbiased=False)
    return mean, std


@pytest.mark.parametrize("per_env_bounds", [False, True])
def test_cem_matches_a_reference_loop_on_the_same_noise(per_env_bounds):
    n, block = 3, 2
    if per_env_bounds:
        low = np.array([[-1.0, -0.2], [-0.5, 0.0], [-2.0, -1.0]], np.float32)
        high = np.array([[1.0, 0.3], [0.5, 2.0], [0.1, 1.0]], np.float32)
        space = gym.spaces.Box(low, high)
    else:
        space = gym.spaces.Box(-0.7, 0.7, (n, 2), np.float32)
    model = Wavy()
    solver = Recorded(model, num_samples=40, n_steps=6, topk=7, var_scale=0.8, seed=5)
    solver.configure(action_space=space, n_envs=n, config=PlanConfig(3, 1, action_block=block))
    info = targets([[0.3, -0.1, 0.2, 0.0], [0.0, 0.4, -0.3, 0.1], [-0.5, 0.2, 0.5, -0.4]])
    out = solver.solve(info)
    assert len(model.candidates) == 6 and all(c.shape == (n, 40, 3, 4) for c in model.candidates)

    tile = lambda x: torch.as_tensor(np.tile(x.reshape(n, -1), (1, block)))  # noqa: E731
    mean, std = reference_cem(Wavy(), info, solver.noise, tile(space.low), tile(space.high), 0.8, 7)
    assert torch.allclose(out["actions"], mean, atol=1e-5)
    assert torch.allclose(out["var"], std, atol=1e-5)


def test_per_env_bounds_are_kept_when_envs_are_planned_in_chunks():
    class Push:
        def get_cost(self, info, candidates):
            return -candidates.sum(dim=(2, 3))

    low = np.array([[-1.0, -2.0], [-0.5, 0.0], [0.2, -3.0]], np.float32)
    high = np.array([[1.0, 2.0], [0.5, 3.0], [0.4, -1.0]], np.float32)
    plans = []
    for batch_size in (None, 1, 2):
        solver = CEMSolver(Push(), batch_size=batch_size, num_samples=64, n_steps=10, topk=8, seed=0)
        solver.configure(action_space=gym.spaces.Box(low, high), n_envs=3, config=PlanConfig(2, 1))
        plans.append(solver.solve({})["actions"])
    lower, upper = torch.as_tensor(low).unsqueeze(1), torch.as_tensor(high).unsqueeze(1)
    for actions in plans:
        assert (actions <= upper + 1e-6).all() and (actions >= lower - 1e-6).all()
        assert ((actions - lower) / (upper - lower)).min() > 0.9  # every env near its own upper bound
    assert torch.equal(plans[0], plans[1]) and torch.equal(plans[0], plans[2])


class Probe(Bowl):
    def __init__(self):
        super().__init__()
        self.inference = []

    def get_cost(self, info, candidates):
        self.inference.append(torch.is_inference_mode_enabled())
        return super().get_cost(info, candidates)


@pytest.mark.parametrize("name", ["cem", "icem", "mppi", "random"])
def test_sampling_solvers_score_in_inference_mode_and_return_ordinary_tensors(name):
    model = Probe()
    kwargs = {"num_samples": 16} if name == "random" else {"num_samples": 16, "n_steps": 2, "topk": 4}
    out = configure(make_solver(name, model, **kwargs), n_envs=2).solve(targets([[0.1, 0.2]] * 2))
    assert model.inference and all(model.inference)
    for value in out.values():
        assert not value.is_inference()
    out["actions"].add_(1.0)  # in-place use outside inference mode is allowed
    assert out["actions"].clone().requires_grad_().sum().requires_grad


def test_gradient_solver_is_not_in_inference_mode():
    model = Probe()
    configure(GradientSolver(model, n_steps=2, num_samples=2), n_envs=2).solve(targets([[0.1, 0.2]] * 2))
    assert model.inference and not any(model.inference)


@pytest.mark.parametrize("h", [1, 2, 5, 8])
@pytest.mark.parametrize("beta", [0.0, 1.0, 2.0])
def test_coloring_matrix_is_colored_noise_as_a_matmul(h, beta):
    white = torch.randn(50, 3, h, generator=torch.Generator().manual_seed(h))
    matrix = coloring_matrix(h, beta)
    assert matrix.shape == (h, h) and matrix.dtype == torch.float32
    assert torch.allclose(white @ matrix, colored_noise(white, beta), atol=1e-5)
    if beta == 0 or h == 1:
        assert torch.allclose(matrix, torch.eye(h))


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="glibc heap behaviour")
def test_configure_keeps_freed_activations_in_the_heap():
    """After configure on the CPU, megabyte tensors freed by a batched model are not page-faulted back in."""
    code = (
        "import resource, torch, gymnasium as gym\n"
        "from stable_worldmodel.policy import PlanConfig\n"
        "from stable_worldmodel.solver import CEMSolver\n"
        "def faults():\n"
        "    before = resource.getrusage(resource.RUSAGE_SELF).ru_minflt\n"
        "    for _ in range(20):\n"
        "        parts = [torch.ones(400_000) for _ in range(4)]\n"
        "        del parts\n"
        "    return resource.getrusage(resource.RUSAGE_SELF).ru_minflt - before\n"
        "first = faults()\n"
        "class Model:\n"
        "    def get_cost(self, info, candidates):\n"
        "        return candidates.sum(dim=(2, 3))\n"
        "CEMSolver(Model()).configure(action_space=gym.spaces.Box(-1, 1, (1, 2)), n_envs=1, config=PlanConfig(1, 1))\n"
        "faults()\n"
        "print(first, faults())\n"
    )
    env = {key: value for key, value in os.environ.items() if not key.startswith("MALLOC_")}  # glibc defaults
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True, env=env)
    before, after = map(int, result.stdout.split())
    if before < 500:
        pytest.skip(f"this C library does not trim the heap here ({before} page faults)")
    assert after < before / 10

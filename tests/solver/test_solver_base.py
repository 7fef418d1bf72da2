"""The plumbing every solver shares: protocol, dims, expansion, warm start, bounds, seeding, chunking."""

from __future__ import annotations

import copy
import subprocess
import sys

import gymnasium as gym
import numpy as np
import pytest
import torch
from _analytic import Bowl, configure, targets

from stable_worldmodel.errors import ConfigError, DependencyNotInstalled, SpaceError, UnknownNameError
from stable_worldmodel.policy import PlanConfig
from stable_worldmodel.solver import (
    AUTO_BATCH,
    BaseSolver,
    CEMSolver,
    GradientSolver,
    NevergradSolver,
    PGDSolver,
    Solver,
    list_solvers,
    make_solver,
    register_solver,
)
from stable_worldmodel.solver import base as solver_base

FAST = {
    "cem": dict(num_samples=16, n_steps=3, topk=4),
    "icem": dict(num_samples=16, n_steps=3, topk=4),
    "mppi": dict(num_samples=16, n_steps=3, topk=4),
    "random": dict(num_samples=16),
    "gd": dict(n_steps=3, num_samples=2),
}


class Push:
    """Cost ``-sum(a)``: the optimum is the upper bound of every coordinate."""

    def get_cost(self, info, candidates):
        return -candidates.sum(dim=(2, 3))


def test_every_solver_conforms_to_the_protocol_before_and_after_configure():
    for name, kwargs in FAST.items():
        solver = make_solver(name, Bowl(), **kwargs)
        assert isinstance(solver, Solver) and isinstance(solver, BaseSolver)
        assert solver.horizon is None and solver.action_dim is None and solver.n_envs is None
        configure(solver, n_envs=4, shape=(2,), horizon=5, action_block=3)
        assert isinstance(solver, Solver)
        assert (solver.horizon, solver.action_dim, solver.n_envs) == (5, 6, 4)
    assert isinstance(PGDSolver(Bowl(), n_steps=1), Solver)
    assert not isinstance(object(), Solver)


def test_call_is_solve_and_result_is_on_cpu():
    solver = configure(CEMSolver(Bowl(), **FAST["cem"]), n_envs=2, horizon=3, action_block=2)
    info = targets([[0.1, 0.2, 0.1, 0.2], [0.0, 0.0, 0.0, 0.0]])
    out, again = solver(info), solver.solve(info)
    assert out["actions"].shape == (2, 3, 4) and out["actions"].device.type == "cpu"
    assert out["costs"].shape == (2,) and out["mean"].shape == out["var"].shape == (2, 3, 4)
    assert again["actions"].shape == (2, 3, 4)


def test_solve_before_configure_and_bad_spaces_raise():
    with pytest.raises(ConfigError, match="configure"):
        CEMSolver(Bowl()).solve({})
    one_env = CEMSolver(Bowl())  # one env's Box (0.0.3's examples): batched to the n_envs
    one_env.configure(action_space=gym.spaces.Box(-1, 1, (2,)), n_envs=3, config=PlanConfig(2, 1))
    assert one_env.action_space.shape == (3, 2) and one_env.action_dim == 2
    with pytest.raises(SpaceError, match="Box"):
        CEMSolver(Bowl()).configure(action_space=gym.spaces.MultiDiscrete([3, 3]), n_envs=2, config=PlanConfig(2, 1))
    with pytest.raises(ConfigError, match="PlanConfig"):
        CEMSolver(Bowl()).configure(action_space=gym.spaces.Box(-1, 1, (2, 1)), n_envs=2, config=object())
    with pytest.raises(ConfigError, match="get_cost"):
        CEMSolver(object())
    with pytest.raises(ConfigError, match="topk"):
        CEMSolver(Bowl(), topk=0)


def test_info_is_expanded_to_views_and_converted():
    model = Bowl()
    solver = configure(CEMSolver(model, num_samples=5, n_steps=1, topk=2), n_envs=3)
    names = np.array([["a"], ["b"], ["c"]])
    info = {"target": np.zeros((3, 2), np.float64), "name": names, "scalar": 7, "shared": torch.ones(4)}
    solver.solve(info)
    seen, shape = model.calls[0]
    assert shape == (3, 5, 1, 2)
    target = seen["target"]
    assert target.shape == (3, 5, 2) and target.dtype == torch.float32 and target.stride(1) == 0  # a view
    assert isinstance(seen["name"], np.ndarray) and seen["name"].shape == (3, 5, 1)
    assert not seen["name"].flags.owndata and seen["name"][2, 4, 0] == "c"
    assert seen["scalar"] == 7 and seen["shared"].shape == (4,)  # not batched: passed as is


def test_warm_start_is_padded_and_used():
    solver = configure(CEMSolver(Bowl(), num_samples=4, n_steps=1, topk=2, var_scale=1e-6), n_envs=2, horizon=3)
    init = torch.tensor([[[0.3, -0.4]], [[0.5, 0.5]]])  # (B, k=1, A)
    out = solver.solve(targets([[0.9, 0.9], [0.9, 0.9]]), init_action=init)
    assert torch.allclose(out["actions"][:, :1], init, atol=1e-4)
    assert torch.allclose(out["actions"][:, 1:], torch.zeros(2, 2, 2), atol=1e-4)  # padded blocks
    gd = configure(GradientSolver(Bowl(), n_steps=2, num_samples=3, optimizer_kwargs={"lr": 0.0}), n_envs=2, horizon=3)
    full = torch.rand(2, 3, 2) - 0.5
    assert torch.allclose(gd.solve(targets([[0.0, 0.0]] * 2), init_action=full)["actions"], full)
    with pytest.raises(ConfigError, match="init_action"):
        solver.solve(targets([[0.0, 0.0]] * 2), init_action=torch.zeros(2, 4, 2))
    with pytest.raises(ConfigError, match="init_action"):
        solver.solve(targets([[0.0, 0.0]] * 2), init_action=torch.zeros(2, 1, 3))


@pytest.mark.parametrize("name", FAST)
def test_bounds_are_tiled_over_the_block_and_per_env(name):
    kwargs = {**FAST[name], "num_samples": 64, "n_steps": 15} if name != "random" else {"num_samples": 256}
    kwargs.update({"topk": 8} if "topk" in kwargs else {})
    solver = make_solver(name, Push(), seed=0, **kwargs)
    low = np.array([[-1.0, -2.0], [-0.5, 0.0]], np.float32)
    high = np.array([[1.0, 2.0], [0.5, 3.0]], np.float32)
    solver.configure(action_space=gym.spaces.Box(low, high), n_envs=2, config=PlanConfig(2, 1, action_block=2))
    actions = solver.solve({})["actions"]
    upper = torch.tensor([[1.0, 2.0, 1.0, 2.0], [0.5, 3.0, 0.5, 3.0]]).unsqueeze(1)
    lower = torch.tensor([[-1.0, -2.0, -1.0, -2.0], [-0.5, 0.0, -0.5, 0.0]]).unsqueeze(1)
    assert (actions <= upper + 1e-6).all() and (actions >= lower - 1e-6).all()
    position = (actions - lower) / (upper - lower)  # 1 = upper bound
    assert (position.mean() if name == "random" else position.min()) > 0.6


@pytest.mark.parametrize("name", FAST)
def test_same_seed_same_plans(name):
    def plans(seed, n=2):
        solver = configure(make_solver(name, Bowl(), seed=seed, **FAST[name]), n_envs=3)
        return [solver.solve(targets([[0.2, 0.1]] * 3))["actions"] for _ in range(n)]

    first, second = plans(3), plans(3)
    assert all(torch.equal(a, b) for a, b in zip(first, second, strict=False))
    assert not torch.equal(plans(4)[0], first[0])
    assert not torch.equal(first[0], first[1])  # the stream advances between solves


def test_set_seed_restarts_the_stream():
    solver = configure(CEMSolver(Bowl(), **FAST["cem"]), n_envs=2)
    info = targets([[0.2, 0.1]] * 2)
    first = solver.solve(info)["actions"]
    solver.set_seed(1234)
    assert torch.equal(solver.solve(info)["actions"], first)


@pytest.mark.parametrize("name", FAST)
def test_batch_size_chunks_give_the_same_plans(name):
    rows = [[0.1 * i, -0.1 * i] for i in range(5)]
    model = Bowl()
    one_pass = configure(make_solver(name, model, **FAST[name]), n_envs=5).solve(targets(rows))
    assert {shape[0] for _, shape in model.calls} == {5}
    model.calls.clear()
    chunked = configure(make_solver(name, model, batch_size=2, **FAST[name]), n_envs=5).solve(targets(rows))
    assert {shape[0] for _, shape in model.calls} == {2, 1}
    assert torch.allclose(chunked["actions"], one_pass["actions"], atol=1e-6)
    assert torch.allclose(chunked["costs"], one_pass["costs"], atol=1e-5)


def test_batch_size_default_is_auto_and_explicit_one_is_env_by_env():
    assert CEMSolver(Bowl()).batch_size is AUTO_BATCH and AUTO_BATCH == 1 and repr(AUTO_BATCH) == "1"
    assert "batch_size='auto'" in repr(CEMSolver(Bowl()))
    assert copy.deepcopy(CEMSolver(Bowl())).batch_size is AUTO_BATCH
    model = Bowl()
    configure(CEMSolver(model, batch_size=1, **FAST["cem"]), n_envs=3).solve(targets([[0.0, 0.0]] * 3))
    assert {shape[0] for _, shape in model.calls} == {1}
    with pytest.raises(ConfigError, match="batch_size"):
        CEMSolver(Bowl(), batch_size=0)


class OOMAbove(Bowl):
    def __init__(self, limit):
        super().__init__()
        self.limit = limit

    def get_cost(self, info, candidates):
        if candidates.shape[0] > self.limit:
            raise torch.OutOfMemoryError("fake")
        return super().get_cost(info, candidates)


def test_auto_batch_halves_on_out_of_memory():
    rows = targets([[0.1, 0.1]] * 4)
    auto = configure(CEMSolver(OOMAbove(2), **FAST["cem"]), n_envs=4).solve(rows)
    capped = configure(CEMSolver(Bowl(), batch_size=2, **FAST["cem"]), n_envs=4).solve(rows)
    assert torch.equal(auto["actions"], capped["actions"])
    with pytest.raises(torch.OutOfMemoryError):
        configure(CEMSolver(OOMAbove(2), batch_size=4, **FAST["cem"]), n_envs=4).solve(rows)


def test_cost_shape_is_checked():
    class Bad:
        def get_cost(self, info, candidates):
            return candidates.sum()

    with pytest.raises(ConfigError, match="get_cost"):
        configure(CEMSolver(Bad(), **FAST["cem"]), n_envs=2).solve({})


class Linear(torch.nn.Module):
    def __init__(self, dtype=torch.float32, device="cpu"):
        super().__init__()
        self.w = torch.nn.Parameter(torch.ones(2, dtype=dtype, device=device))
        self.seen = None

    def get_cost(self, info, candidates):
        self.seen = candidates.dtype
        return ((candidates * self.w) ** 2).sum(dim=(2, 3))


def test_dtype_and_device_follow_the_model():
    model = Linear(torch.float64)
    out = configure(CEMSolver(model, **FAST["cem"]), n_envs=2).solve({})
    assert model.seen == torch.float64 and out["actions"].dtype == torch.float64
    with pytest.raises(ConfigError, match="device"):
        configure(CEMSolver(Linear(device="meta"), **FAST["cem"]), n_envs=2)
    auto = CEMSolver(Linear(), device=None, **FAST["cem"])
    assert configure(auto, n_envs=2).device == torch.device("cpu")


class Threads(Linear):
    """Records torch's intra-op thread count while it scores; ``size`` parameters in all."""

    def __init__(self, size=2):
        super().__init__()
        self.extra = torch.nn.Parameter(torch.zeros(size - 2))
        self.threads = set()

    def get_cost(self, info, candidates):
        self.threads.add(torch.get_num_threads())
        return super().get_cost(info, candidates)


@pytest.mark.parametrize(
    "policy, size, limit, expected",
    [
        ("PASSIVE", 2, None, 1),  # a small plan while OpenMP threads sleep between operations: one thread
        ("passive", 2, None, 1),
        ("ACTIVE", 2, None, 2),
        (None, 2, None, 2),
        ("PASSIVE", 1000, 64000, 2),  # 4 envs x 16 samples x horizon 1 x 1000 parameters: at the limit
        ("PASSIVE", 1000, 64001, 1),
    ],
)
def test_small_cpu_plans_run_on_one_thread_while_omp_threads_sleep(monkeypatch, policy, size, limit, expected):
    if limit is not None:
        monkeypatch.setattr(solver_base, "ONE_THREAD_WORK", limit)
    if policy is None:
        monkeypatch.delenv("OMP_WAIT_POLICY", raising=False)
    else:
        monkeypatch.setenv("OMP_WAIT_POLICY", policy)
    before = torch.get_num_threads()
    torch.set_num_threads(2)
    try:
        model = Threads(size)
        solver = configure(CEMSolver(model, **FAST["cem"], seed=0), n_envs=4)
        out = solver.solve({})
        assert model.threads == {expected} and torch.get_num_threads() == 2  # restored after the plan
        monkeypatch.setenv("OMP_WAIT_POLICY", "ACTIVE")
        again = configure(CEMSolver(Threads(size), **FAST["cem"], seed=0), n_envs=4).solve({})
        torch.testing.assert_close(out["actions"], again["actions"], rtol=0, atol=0)  # the same plans
    finally:
        torch.set_num_threads(before)


def test_gradient_solver_leaves_model_grads_alone_and_works_under_no_grad():
    model = Linear()
    solver = configure(GradientSolver(model, n_steps=20, num_samples=2, optimizer_kwargs={"lr": 0.1}), n_envs=2)
    with torch.no_grad():
        out = solver.solve({})
    assert model.w.grad is None
    assert out["actions"].abs().max() < 0.1  # minimum of (a * w)^2 at 0


def test_registry_names_lookup_and_custom_solvers(monkeypatch):
    from stable_worldmodel.solver import _registry

    monkeypatch.setattr(_registry, "_ENTRIES", dict(_registry._ENTRIES))  # the test's solver leaves with it
    assert {"cem", "icem", "mppi", "gd", "pgd", "random", "nevergrad"} <= set(list_solvers())
    with pytest.raises(UnknownNameError, match="Did you mean .*'cem'"):
        make_solver("cme", Bowl())

    @register_solver("test-zero")
    class ZeroSolver(BaseSolver):
        def _optimize(self, info, init_action):
            mean = self._initial_mean(init_action)
            return {"actions": mean, "costs": mean.sum(dim=(1, 2))}

    solver = configure(make_solver("test-zero", Bowl()), n_envs=2, horizon=2)
    assert ZeroSolver.name == "test-zero" and isinstance(solver, ZeroSolver)
    assert torch.equal(solver.solve({})["actions"], torch.zeros(2, 2, 2))
    with pytest.raises(ConfigError, match="free name"):
        register_solver("test-zero")(type("Other", (BaseSolver,), {}))


def test_nevergrad_without_the_extra_gives_the_pip_command(monkeypatch):
    monkeypatch.setitem(sys.modules, "nevergrad", None)
    with pytest.raises(DependencyNotInstalled, match=r"stable-worldmodel\[nevergrad\]"):
        NevergradSolver(Bowl())


def test_importing_the_package_is_light():
    code = (
        "import sys, stable_worldmodel.solver as s; names = s.list_solvers(); "
        "assert 'torch' not in sys.modules, 'torch imported'; assert 'cem' in names"
    )
    subprocess.run([sys.executable, "-c", code], check=True)


@pytest.mark.parametrize("name", [*FAST, "pgd"])
def test_no_host_sync_inside_the_iterations(name, monkeypatch):
    """On a GPU, .item()/.cpu()/bool(tensor) in the loop would stall it: none may run in _optimize."""
    if name == "pgd":
        solver = PGDSolver(Bowl(), n_steps=3)
        space = gym.vector.utils.batch_space(gym.spaces.Discrete(3), 2)
        solver.configure(action_space=space, n_envs=2, config=PlanConfig(2, 1))
        info = {"target": torch.zeros(2, 3)}
    else:
        solver = configure(make_solver(name, Bowl(), **FAST[name]), n_envs=2, horizon=2)
        info = targets([[0.1, 0.2]] * 2)
    solver.solve(info)  # warm-up outside the guard (lazy imports, first-use paths)

    def sync(*args, **kwargs):
        raise AssertionError("host-device sync inside the solver loop")

    for attr in ("item", "tolist", "cpu", "numpy", "__bool__", "__float__", "__int__"):
        monkeypatch.setattr(torch.Tensor, attr, sync)
    out = solver._optimize_rows(info, None, 0, 2)
    assert out["actions"].shape[:2] == (2, 2)

"""The solvers and callbacks of upstream 0.1.1 (``PredictiveSamplingSolver``, ``LagrangianSolver``,
``CategoricalCEMSolver``, ``solver.callbacks``, ``solver.pgd``), each on a toy cost with a known
optimum, batched over envs. Signatures and outputs follow 0.1.1's, as installed from PyPI."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
import torch
from _analytic import Bowl, configure, targets

from stable_worldmodel.errors import ConfigError, SpaceError
from stable_worldmodel.policy import PlanConfig
from stable_worldmodel.solver import (
    CategoricalCEMSolver,
    CEMSolver,
    GradientSolver,
    ICEMSolver,
    LagrangianSolver,
    PredictiveSamplingSolver,
    make_solver,
)
from stable_worldmodel.solver.callbacks import (
    ActionNormRecorder,
    BestCostRecorder,
    Callback,
    EarlyStopping,
    EliteCostRecorder,
    EliteSpreadRecorder,
    GradNormRecorder,
    MeanCostRecorder,
    MeanShiftRecorder,
    VarNormRecorder,
)

TARGETS = [[0.5, -0.25], [-0.5, 0.75], [0.0, 0.3]]


# -- predictive sampling ---------------------------------------------------------------------
def test_predictive_sampling_improves_on_the_nominal_and_converges():
    solver = configure(PredictiveSamplingSolver(Bowl(), num_samples=64, noise_scale=0.2, n_steps=10, seed=0), horizon=3)
    info = targets(TARGETS)
    first = solver.solve(info)
    assert first["actions"].shape == (3, 3, 2) and first["costs"].shape == (3,)
    nominal, costs = first["actions"], [first["costs"]]
    for _ in range(15):  # receding use: each plan warm-starts the next (never worse: candidate 0)
        out = solver.solve(info, init_action=nominal)
        assert (out["costs"] <= costs[-1] + 1e-6).all()
        nominal, costs = out["actions"], costs + [out["costs"]]
    target = torch.tensor(TARGETS).unsqueeze(1).expand(3, 3, 2)
    zero_plan = (target**2).sum(dim=(1, 2))  # the cost of the all-zeros plan it started from
    assert torch.allclose(nominal, target, atol=0.1) and (costs[-1] < 0.05 * zero_plan).all()


def test_predictive_sampling_plans_are_the_same_in_any_batching():
    whole = configure(PredictiveSamplingSolver(Bowl(), num_samples=16, n_steps=3, seed=5), horizon=2)
    one_by_one = configure(PredictiveSamplingSolver(Bowl(), batch_size=1, num_samples=16, n_steps=3, seed=5), horizon=2)
    a, b = whole.solve(targets(TARGETS)), one_by_one.solve(targets(TARGETS))
    assert torch.equal(a["actions"], b["actions"]) and torch.equal(a["costs"], b["costs"])


# -- Lagrangian ----------------------------------------------------------------------------
class CappedBowl(Bowl):
    """Bowl to the target, under ``a <= cap`` for every coordinate (C = H * A constraints)."""

    cap = 0.2

    def get_constraints(self, info, candidates):
        return (candidates - self.cap).flatten(2)  # (B, S, H * A), satisfied where <= 0


def test_lagrangian_meets_the_constraints_at_the_constrained_optimum():
    solver = configure(
        LagrangianSolver(CappedBowl(), n_steps=30, n_outer_steps=6, optimizer_kwargs={"lr": 0.05}), horizon=2
    )
    out = solver.solve(targets(TARGETS))
    target = torch.tensor(TARGETS).unsqueeze(1).expand(3, 2, 2)
    expected = torch.clamp(target, max=CappedBowl.cap)  # the projection of the target onto the feasible set
    assert torch.allclose(out["actions"], expected, atol=0.03)
    assert out["constraint_violation"].shape == (3,) and (out["constraint_violation"] < 0.01).all()
    active = (target > CappedBowl.cap).flatten(1)  # multipliers grow only on the binding constraints
    assert out["lambdas"].shape == (3, 4) and (out["lambdas"][active] > 0.01).all()
    assert (out["lambdas"][~active] < 0.01).all()
    assert torch.equal(solver.lambdas, out["lambdas"])  # carried to the next solve


def test_lagrangian_without_constraints_is_gradient_descent():
    solver = configure(LagrangianSolver(Bowl(), n_steps=40, n_outer_steps=2, optimizer_kwargs={"lr": 0.05}))
    out = solver.solve(targets(TARGETS))
    assert torch.allclose(out["actions"][:, 0], torch.tensor(TARGETS), atol=0.02)
    assert "lambdas" not in out and solver.lambdas is None


def test_lagrangian_multipliers_persist_unless_told_not_to():
    def run(persist):
        kwargs = dict(n_steps=10, n_outer_steps=2, var_scale=0.0, optimizer_kwargs={"lr": 0.05})
        solver = configure(LagrangianSolver(CappedBowl(), persist_multipliers=persist, **kwargs))
        return solver.solve(targets(TARGETS)), solver.solve(targets(TARGETS))

    first, second = run(False)  # the same start both times: the same plan and multipliers
    assert torch.equal(first["actions"], second["actions"]) and torch.equal(first["lambdas"], second["lambdas"])
    assert (first["lambdas"] > 0).any()
    first, second = run(True)  # the second solve starts from the first one's multipliers
    assert not torch.equal(first["lambdas"], second["lambdas"])
    bound = first["lambdas"] > 0  # (B, C = A): the plans stay at least as far inside the cap there
    assert (second["actions"][:, 0][bound] <= first["actions"][:, 0][bound] + 1e-6).all()


def test_lagrangian_bad_constraints_are_a_typed_error():
    class Wrong(Bowl):
        def get_constraints(self, info, candidates):
            return candidates.sum(dim=(2, 3))  # (B, S): no constraint axis

    with pytest.raises(ConfigError, match=r"get_constraints to return \(B, S, C\) = \(3, 1, C\)"):
        configure(LagrangianSolver(Wrong(), n_steps=2)).solve(targets(TARGETS))
    with pytest.raises(ConfigError, match="rho_scale"):
        LagrangianSolver(Bowl(), n_steps=2, rho_scale=0.5)


# -- categorical CEM -------------------------------------------------------------------------
class Sequence:
    """Hamming distance of one-hot plans ``(B, S, H, n)`` to ``info["seq"]: (B, S, H)`` ints."""

    def get_cost(self, info, candidates):
        chosen = candidates.argmax(dim=-1)
        return (chosen != info["seq"]).float().sum(dim=-1)


def test_categorical_cem_finds_each_envs_sequence():
    seqs = torch.tensor([[0, 1, 2, 3, 3], [3, 3, 0, 1, 2], [2, 2, 2, 0, 1]])
    solver = CategoricalCEMSolver(Sequence(), num_samples=200, n_steps=8, topk=20, smoothing=0.01, seed=0)
    solver.configure(action_space=gym.spaces.Discrete(4), n_envs=3, config=PlanConfig(5, 1))
    out = solver.solve({"seq": seqs}, init_action=torch.zeros(3, 5, 1))  # ignored, as upstream's
    assert out["actions"].dtype == torch.int64 and out["actions"].shape == (3, 5, 1)
    assert torch.equal(out["actions"][..., 0], seqs) and (out["costs"] == 0).all()
    assert out["probs"].shape == (3, 5, 1, 4) and torch.allclose(out["probs"].sum(-1), torch.ones(3, 5, 1))


def test_categorical_cem_requires_a_discrete_space():
    solver = CategoricalCEMSolver(Sequence(), num_samples=10, topk=2)
    with pytest.raises(SpaceError, match="CategoricalCEMSolver requires a discrete action space"):
        configure(solver)
    with pytest.raises(ConfigError, match="alpha"):
        CategoricalCEMSolver(Sequence(), alpha=1.5)


# -- callbacks ---------------------------------------------------------------------------
def test_cem_callbacks_record_every_iteration_per_batch_of_envs():
    recorders = [
        BestCostRecorder(),
        MeanCostRecorder(reduction="none"),
        EliteCostRecorder(),
        VarNormRecorder(),
        MeanShiftRecorder(reduction="sum"),
        EliteSpreadRecorder(),
    ]
    solver = configure(CEMSolver(Bowl(), batch_size=2, num_samples=32, n_steps=5, topk=4, callbacks=recorders))
    out = solver.solve(targets(TARGETS))
    hist = out["callbacks"]
    assert set(hist) == {type(r).__name__ for r in recorders}
    assert [len(batch) for batch in hist["BestCostRecorder"]] == [5, 5]  # envs 0-1, then env 2
    assert [len(step) for step in hist["MeanCostRecorder"][0]] == [2] * 5  # reduction="none": per env
    assert set(hist["EliteCostRecorder"][0][0]) == {"mean", "min", "max"}
    var = hist["VarNormRecorder"][0]
    assert var[-1] < var[0]  # the distribution narrows
    best = hist["BestCostRecorder"][1]
    assert best[-1] <= best[0]
    again = solver.solve(targets(TARGETS))["callbacks"]  # a new solve starts new histories
    assert [len(batch) for batch in again["BestCostRecorder"]] == [5, 5]


def test_gradient_callbacks_see_the_gradient():
    grads, norms = GradNormRecorder(per_step=True), ActionNormRecorder()
    solver = configure(GradientSolver(Bowl(), n_steps=4, callbacks=[grads, norms], var_scale=0.0), horizon=3)
    out = solver.solve(targets(TARGETS))
    assert len(out["callbacks"]["GradNormRecorder"][0]) == 4 and len(out["callbacks"]["GradNormRecorder"][0][0]) == 3
    first = out["callbacks"]["GradNormRecorder"][0][0]
    assert first[0] > 0  # d/da (a - t)^2 at a = 0 is -2t
    assert out["callbacks"]["ActionNormRecorder"][0][-1] > 0


def test_early_stopping_ends_the_iterations():
    class Flat:
        def get_cost(self, info, candidates):
            return candidates.sum(dim=(2, 3)) * 0  # nothing to improve

    stopper, counter = EarlyStopping(patience=2), BestCostRecorder()
    for solver in (
        configure(CEMSolver(Flat(), num_samples=8, n_steps=30, topk=2, callbacks=[stopper, counter])),
        configure(ICEMSolver(Flat(), num_samples=8, n_steps=30, topk=2, callbacks=[stopper, counter])),
        configure(GradientSolver(Flat(), n_steps=30, callbacks=[stopper, counter])),
    ):
        out = solver.solve(targets(TARGETS))
        assert len(out["callbacks"]["BestCostRecorder"][0]) == 3, type(solver).__name__  # 1 + patience
    with pytest.raises(ConfigError, match="patience"):
        EarlyStopping(patience=0)


def test_custom_callbacks_and_bad_ones():
    class Elites(Callback):
        name = "elite_ids"

        def compute(self, **state):
            return state["topk_inds"][:, 0].tolist()

    solver = configure(CEMSolver(Bowl(), num_samples=16, n_steps=2, topk=3, callbacks=[Elites()]))
    ids = solver.solve(targets(TARGETS))["callbacks"]["elite_ids"][0]
    assert len(ids) == 2 and all(0 <= i < 16 for step in ids for i in step)
    with pytest.raises(ConfigError, match="callbacks to be a list of stable_worldmodel.solver.callbacks.Callback"):
        CEMSolver(Bowl(), callbacks=[print])
    with pytest.raises(ConfigError, match="reduction"):
        BestCostRecorder(reduction="max")


# -- names and module paths of 0.1.1 --------------------------------------------------------------
def test_module_paths_and_registry_names():
    from stable_worldmodel.solver.discrete_solvers import PGDSolver
    from stable_worldmodel.solver.pgd import PGDSolver as FromPgd

    assert FromPgd is PGDSolver
    ps = make_solver("predictive_sampling", Bowl(), num_samples=4)
    assert isinstance(ps, PredictiveSamplingSolver) and ps.noise_scale == 1.0
    icem = ICEMSolver(Bowl(), num_samples=20, topk=10, alpha=0.2, n_elite_keep=3, return_mean=True)
    assert icem.momentum == 0.2 and icem.n_keep == 3 and icem.return_mean
    assert np.isclose(GradientSolver(Bowl(), n_steps=1, grad_clip=0.5).grad_clip, 0.5)


def test_prepare_init_action_of_011():
    from stable_worldmodel.solver.utils import prepare_init_action

    class Actor:
        def get_action(self, info, horizon=1, prefix_actions=None):
            t = 0 if prefix_actions is None else prefix_actions.shape[1]
            return torch.full((2, horizon, 3), float(t + 1))

    prev = torch.ones(2, 1, 3)
    assert prepare_init_action(Bowl(), {}, None, 4, 2, 3).eq(0).all()  # no actor: zeros
    padded = prepare_init_action(Bowl(), {}, prev, 4, 2, 3)
    assert padded.shape == (2, 4, 3) and padded[:, 0].eq(1).all() and padded[:, 1:].eq(0).all()
    filled = prepare_init_action(Actor(), {}, prev, 4, 2, 3)  # the actor rolls out after the given block
    assert filled[:, 1:].eq(2).all() and filled[:, 0].eq(1).all()
    full = torch.zeros(2, 4, 3)
    assert prepare_init_action(Actor(), {}, full, 4, 2, 3) is full
    with pytest.raises(ConfigError, match=r"init_action of shape \(2, t <= 4, 3\)"):
        prepare_init_action(Bowl(), {}, torch.zeros(3, 1, 3), 4, 2, 3)


def test_ensure_dir_exists_of_011(tmp_path):
    from stable_worldmodel.data.utils import ensure_dir_exists

    ensure_dir_exists(tmp_path / "a" / "b")
    ensure_dir_exists(tmp_path / "a" / "b")
    assert (tmp_path / "a" / "b").is_dir()

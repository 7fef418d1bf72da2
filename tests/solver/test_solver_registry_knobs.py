"""The solver registry is the single source: a solver declares its plan knobs once
(``PlanKnobs``), and ``PlanSettings``, ``swm eval --solver``, ``swm list solver`` and the package's
exports follow from the registry."""

from __future__ import annotations

import pytest

import stable_worldmodel.solver as solver_pkg
from stable_worldmodel.errors import UnknownNameError
from stable_worldmodel.planning.learned import PlanSettings, _make_solver
from stable_worldmodel.solver import _registry, list_solvers
from stable_worldmodel.solver.base import PlanKnobs
from stable_worldmodel.solver.random import RandomSolver


class _Cost:
    def get_cost(self, info, candidates):
        return candidates.sum(dim=(-1, -2))


def test_knobs_map_plan_settings_to_constructor_arguments():
    assert PlanKnobs(elites="topk").kwargs(100, 5, None) == {"num_samples": 100, "n_steps": 5, "topk": 10}
    assert PlanKnobs(elites="topk").kwargs(5, 5, 2)["topk"] == 2
    assert PlanKnobs(samples=None, fixed=(("num_samples", 1),)).kwargs(100, 7, None) == {"num_samples": 1, "n_steps": 7}
    assert PlanKnobs(iterations=None).kwargs(100, 7, None) == {"num_samples": 100}


@pytest.mark.parametrize("name", list_solvers())
def test_every_registered_solver_is_a_plan_choice_built_from_its_knobs(name):
    settings = PlanSettings(solver=name, samples=20, iterations=3)
    solver = _make_solver(_Cost(), settings, "cpu")
    assert type(solver).name == name and solver.n_steps == (1 if name == "random" else 3)
    assert solver.num_samples == (1 if name in ("gd", "pgd", "lagrangian") else 20)
    assert type(solver).__name__ in solver_pkg.__all__  # exported by the package, from the registry's table


def test_a_new_solver_is_one_class_and_one_registration(monkeypatch, swm):
    monkeypatch.setattr(_registry, "_ENTRIES", dict(_registry._ENTRIES))

    @_registry.register_solver("best_of")
    class BestOf(RandomSolver):
        knobs = PlanKnobs(iterations=None, summary="the best of a few random plans")

    assert "best_of" in list_solvers()
    solver = _make_solver(_Cost(), PlanSettings(solver="best_of", samples=8), "cpu")
    assert isinstance(solver, BestOf) and solver.num_samples == 8
    result = swm("list", "solver")
    assert result.exit_code == 0 and "best_of" in result.stdout and "the best of a few random plans" in result.stdout
    with pytest.raises(UnknownNameError, match="Did you mean 'best_of'"):
        PlanSettings(solver="best_off")


def test_swm_eval_help_lists_every_registered_solver(swm):
    result = swm("eval", "--help")
    assert result.exit_code == 0
    text = " ".join(result.stdout.split())
    for name in list_solvers():
        assert name in text

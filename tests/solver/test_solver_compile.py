"""``BaseSolver.compile_cost``: candidates scored through ``torch.compile`` of ``get_cost``, same costs and plans."""

from __future__ import annotations

import gymnasium as gym
import pytest
import torch
import torch._dynamo
from _nets import TINY_JEPA

from stable_worldmodel import wm
from stable_worldmodel.errors import ConfigError
from stable_worldmodel.planning.learned import PlanSettings, _make_solver
from stable_worldmodel.policy import PlanConfig
from stable_worldmodel.solver import make_solver
from stable_worldmodel.solver.base import COMPILED_GRAPHS

#: a width-8 CNN LeWM at 16x16, one predictor layer
TINY = dict(TINY_JEPA, history_size=1)
SAMPLES, HORIZON = 16, 3


@pytest.fixture(autouse=True)
def _one_thread(one_torch_thread):
    """One torch thread (see ../conftest.py)."""


def tiny_lewm() -> torch.nn.Module:
    torch.manual_seed(0)
    model = wm.make("lewm", "tiny", action_dim=2, **TINY).eval()
    # AdaLN-zero starts every block as the identity: random modulations make the actions matter
    for block in model.predictor.transformer.layers:
        torch.nn.init.normal_(block.adaLN_modulation[1].weight, std=0.5)
    for p in model.parameters():
        p.requires_grad_(False)
    return model


def plan_info(b: int = 2) -> dict:
    g = torch.Generator().manual_seed(1)
    return {
        "pixels": torch.rand(b, 1, 3, 16, 16, generator=g) * 2 - 1,
        "goal": torch.rand(b, 1, 3, 16, 16, generator=g) * 2 - 1,
    }


def configured(model, b: int = 2, **kwargs):
    solver = make_solver("cem", model, num_samples=SAMPLES, n_steps=3, topk=4, seed=0, **kwargs)
    solver.configure(
        action_space=gym.spaces.Box(-1.0, 1.0, (b, 2)),
        n_envs=b,
        config=PlanConfig(horizon=HORIZON, receding_horizon=HORIZON, history_len=1, action_block=1),
    )
    return solver


def test_compile_cost_traces_get_cost_with_the_options_given():
    model = tiny_lewm()
    graphs = []

    def recording_backend(gm, example_inputs):
        graphs.append(gm)
        return gm.forward

    solver = configured(model)
    with torch._dynamo.config.patch(recompile_limit=8):
        assert solver.compile_cost(backend=recording_backend) is solver
        assert torch._dynamo.config.recompile_limit == COMPILED_GRAPHS  # several models / shapes stay compiled
    solver.solve(plan_info())
    # one graph encodes the context on the plan's first call, one reuses it; no further graph per call
    assert 1 <= len(graphs) <= 2
    calls_before = len(graphs)
    solver.solve(plan_info())
    assert len(graphs) == calls_before


@pytest.mark.parametrize(
    "backend",
    [
        "aot_eager",  # the captured graph run by torch's own kernels (seconds)
        pytest.param("inductor", marks=pytest.mark.slow),  # compile_cost's default (~25 s on a 2-core CPU)
    ],
)
def test_compiled_costs_and_plans_equal_the_eager_ones(backend):
    model = tiny_lewm()
    eager, compiled = configured(model), configured(model).compile_cost(backend=backend)
    g = torch.Generator().manual_seed(2)
    candidates = torch.rand(2, SAMPLES, HORIZON, 2, generator=g) * 2 - 1
    with torch.inference_mode():
        want = eager._cost(eager._expand(plan_info(), SAMPLES), candidates)
        got = compiled._cost(compiled._expand(plan_info(), SAMPLES), candidates)
    assert want.std() > 1e-3  # the candidates' costs differ: the comparison means something
    torch.testing.assert_close(got, want, rtol=1e-5, atol=1e-5)
    torch.testing.assert_close(compiled.solve(plan_info())["actions"], eager.solve(plan_info())["actions"])


def test_plan_settings_compile_reaches_the_solver_and_the_protocol():
    model = tiny_lewm()
    assert _make_solver(model, PlanSettings(), "cpu")._cost_fn is None
    assert _make_solver(model, PlanSettings(compile=True), "cpu")._cost_fn is not None
    assert PlanSettings(compile=True).as_dict()["compile"] is True
    assert "compile" not in PlanSettings().as_dict()
    with pytest.raises(ConfigError, match="compile to be True or False, got 'yes'"):
        PlanSettings(compile="yes")

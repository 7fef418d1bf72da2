"""Bad solver arguments raise ConfigError in the constructor, naming the bad value and what is accepted."""

from __future__ import annotations

import math

import pytest
import torch
from _analytic import Bowl

from stable_worldmodel.errors import ConfigError
from stable_worldmodel.solver import CEMSolver, GradientSolver, ICEMSolver, MPPISolver, PGDSolver, RandomSolver

NAN, INF = math.nan, math.inf
CLASSES = {"cem": CEMSolver, "icem": ICEMSolver, "mppi": MPPISolver}
CLASSES.update(random=RandomSolver, gd=GradientSolver, pgd=PGDSolver)
DEFAULTS = {"cem": {"num_samples": 16, "topk": 4}, "random": {"num_samples": 16}, "gd": {"n_steps": 2}}
DEFAULTS.update(icem=DEFAULTS["cem"], mppi=DEFAULTS["cem"], pgd=DEFAULTS["gd"])


def build(kind, **kwargs):
    return CLASSES[kind](Bowl(), **{**DEFAULTS[kind], **kwargs})


ALL = list(CLASSES)

COMMON = [
    # (kwargs, fragments of the message)
    ({"batch_size": "a"}, ["batch_size", "integer >= 1 or None", "got 'a'"]),
    ({"batch_size": 1.5}, ["batch_size", "got 1.5"]),
    ({"batch_size": True}, ["batch_size", "got True"]),
    ({"batch_size": -2}, ["batch_size", "got -2"]),
    ({"var_scale": NAN}, ["var_scale", "finite number >= 0", "got nan"]),
    ({"var_scale": INF}, ["var_scale", "got inf"]),
    ({"var_scale": -0.5}, ["var_scale", "got -0.5"]),
    ({"var_scale": "1"}, ["var_scale", "got '1'"]),
    ({"num_samples": 0}, ["num_samples", "integer >= 1", "got 0"]),
    ({"n_steps": -1}, ["n_steps", "integer >= 1", "got -1"]),
    ({"device": "bogus"}, ["device", '"cpu", "cuda", "cuda:0", "mps"', "got 'bogus'"]),
    ({"device": "CPU"}, ["got 'CPU'", "Did you mean 'cpu'"]),
    ({"device": "cuda:x"}, ["got 'cuda:x'"]),
    ({"device": 1.5}, ["device", "got 1.5"]),
    ({"device": True}, ["device", "got True"]),
]
COMMON_IDS = [
    "batch-str",
    "batch-float",
    "batch-bool",
    "batch-negative",
    "var-nan",
    "var-inf",
    "var-negative",
    "var-str",
    "samples-0",
    "steps-negative",
    "device-bogus",
    "device-upper",
    "device-bad-index",
    "device-float",
    "device-bool",
]


@pytest.mark.parametrize("kind", ALL)
@pytest.mark.parametrize("kwargs, fragments", COMMON, ids=COMMON_IDS)
def test_shared_arguments_are_validated_by_every_solver(kind, kwargs, fragments):
    with pytest.raises(ConfigError) as info:
        build(kind, **kwargs)
    message = str(info.value)
    assert message.startswith(f"{CLASSES[kind].__name__} requires"), message
    for fragment in fragments:
        assert fragment in message, (fragment, message)


SPECIFIC = [
    ("cem", {"num_samples": 10, "topk": 20}, ["topk <= num_samples", "topk=20", "num_samples=10", "topk=10 or less"]),
    ("cem", {"num_samples": 10, "topk": None}, ["CEMSolver requires topk to be an integer >= 1", "got None"]),
    ("icem", {"num_samples": 8, "topk": 9}, ["ICEMSolver requires topk <= num_samples", "topk=9"]),
    ("mppi", {"num_samples": 4, "topk": 5}, ["MPPISolver requires topk <= num_samples", "topk=5"]),
    ("cem", {"topk": 0}, ["topk to be an integer >= 1", "got 0"]),
    ("mppi", {"temperature": NAN}, ["temperature", "finite number > 0", "got nan"]),
    ("mppi", {"temperature": INF}, ["temperature", "got inf"]),
    ("mppi", {"temperature": -1.0}, ["temperature", "got -1.0"]),
    ("mppi", {"temperature": 0}, ["temperature", "got 0"]),
    ("icem", {"noise_beta": INF}, ["noise_beta", "finite number >= 0", "got inf"]),
    ("icem", {"noise_beta": -0.5}, ["noise_beta", "got -0.5"]),
    ("icem", {"momentum": NAN}, ["momentum", "in [0, 1)", "got nan"]),
    ("icem", {"elite_keep_frac": 1.0}, ["elite_keep_frac", "in [0, 1)", "got 1.0"]),
    ("gd", {"action_noise": NAN}, ["action_noise", "finite number >= 0", "got nan"]),
    ("gd", {"action_noise": -0.1}, ["action_noise", "got -0.1"]),
    ("gd", {"optimizer_kwargs": {"lr": -0.1}}, ["GradientSolver", "learning rate", ">= 0", "got -0.1"]),
    ("gd", {"optimizer_kwargs": {"lr": NAN}}, ["learning rate", "got nan"]),
    ("gd", {"optimizer_kwargs": {"lr": INF}}, ["learning rate", "got inf"]),
    ("gd", {"optimizer_kwargs": [("lr", 0.1)]}, ["optimizer_kwargs to be a dict", "[('lr', 0.1)]"]),
    ("gd", {"optimizer_cls": "Adam"}, ["optimizer_cls", "got 'Adam'"]),
    ("pgd", {"optimizer_kwargs": {"lr": -1}}, ["PGDSolver", "learning rate", "got -1"]),
    ("pgd", {"action_noise": INF}, ["PGDSolver", "action_noise", "got inf"]),
]


@pytest.mark.parametrize(
    "kind, kwargs, fragments", SPECIFIC, ids=[f"{kind}-{'-'.join(map(str, kw.items()))}" for kind, kw, _ in SPECIFIC]
)
def test_solver_specific_arguments_raise_config_error(kind, kwargs, fragments):
    with pytest.raises(ConfigError) as info:
        build(kind, **kwargs)
    assert isinstance(info.value, ValueError)
    for fragment in fragments:
        assert fragment in str(info.value), (fragment, str(info.value))


@pytest.mark.parametrize(
    "kind, kwargs",
    [
        ("cem", {"batch_size": None}),
        ("cem", {"batch_size": 3, "device": None}),
        ("cem", {"num_samples": 8, "topk": 8}),
        ("mppi", {"device": torch.device("cpu"), "temperature": torch.tensor(0.3)}),
        ("icem", {"device": "cuda", "noise_beta": 0, "momentum": 0.0}),  # CUDA is only needed in configure
        ("random", {"device": "cuda:0"}),
        ("random", {"device": 0}),
        ("gd", {"device": "mps", "optimizer_kwargs": {"lr": 0.0}}),
        ("pgd", {"optimizer_kwargs": {"momentum": 0.9}}),
    ],
)
def test_valid_arguments_are_still_accepted(kind, kwargs):
    solver = build(kind, **kwargs)
    assert solver.n_steps >= 1


def test_topk_defaults_are_checked_against_num_samples():
    with pytest.raises(ConfigError, match=r"topk=30 and num_samples=10"):
        CEMSolver(Bowl(), num_samples=10)  # default topk=30
    assert CEMSolver(Bowl(), num_samples=30).topk == 30

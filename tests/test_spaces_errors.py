"""Bad space arguments raise SpaceError naming the bad value (not Gymnasium's bare ValueError/TypeError)."""

from __future__ import annotations

import logging
import re

import numpy as np
import pytest

from stable_worldmodel.errors import SpaceError, SWMError
from stable_worldmodel.spaces import Box, Dict, Discrete, MultiDiscrete


@pytest.mark.parametrize(
    "make, fragments",
    [
        (lambda: Box(1.0, 0.0, shape=(2,)), ["low <= high", "low=1.0", "high=0.0"]),
        (lambda: Box(low=np.array([0.0, 2.0]), high=np.array([1.0, 1.0])), ["low <= high", "index (1,)", "2.0 > 1.0"]),
        (lambda: Box(np.array([-1.0, np.nan]), np.array([1.0, 1.0])), ["low without NaN", "nan", "np.inf"]),
        (lambda: Box(0.0, np.nan, shape=()), ["high without NaN", "high=nan"]),
        (lambda: Box(np.zeros(2), np.ones(3)), ["Box requires", "don't match"]),
        (lambda: Box("a", 1.0), ["numeric low and high", "'a'"]),
        (lambda: Discrete(0), ["n to be an integer >= 1", "got 0"]),
        (lambda: Discrete(-3), ["n to be an integer >= 1", "got -3"]),
        (lambda: Discrete(n=2.5), ["integer >= 1", "got 2.5"]),
        (lambda: MultiDiscrete([3, 0]), ["every nvec entry", "[3, 0]", "bad entries [0]"]),
        (lambda: MultiDiscrete(nvec=np.array([2, -1, 4])), ["every nvec entry", "bad entries [-1]"]),
        (lambda: MultiDiscrete([2.5, 3]), ["every nvec entry", "bad entries [2.5]"]),
        (lambda: MultiDiscrete(["a", "b"]), ["nvec as an array of integers", "'a'"]),
    ],
    ids=[
        "box-low>high",
        "box-low>high-array",
        "box-nan-low",
        "box-nan-high",
        "box-shapes",
        "box-non-numeric",
        "discrete-0",
        "discrete-negative",
        "discrete-float",
        "multidiscrete-0",
        "multidiscrete-negative",
        "multidiscrete-fraction",
        "multidiscrete-strings",
    ],
)
def test_bad_constructor_arguments_raise_space_error(make, fragments):
    with pytest.raises(SpaceError) as info:
        make()
    message = str(info.value)
    assert isinstance(info.value, (SWMError, ValueError)) and "requires" in message
    for fragment in fragments:
        assert fragment in message, (fragment, message)


def _leaf(fn):
    return Box(0.0, 1.0, shape=(2,), init_value=[0.5, 0.5], constrain_fn=fn)


@pytest.mark.parametrize("call", ["sample", "check", "contains"])
@pytest.mark.parametrize(
    "make, fragments",
    [
        (lambda: _leaf(lambda x: x > 0.2), ["Box(0.0, 1.0, (2,), float32)", "a bool", "ndarray", "shape (2,)"]),
        (lambda: _leaf(lambda x: np.array([True])), ["return a bool", "[ True]", "shape (1,)"]),
        (lambda: Discrete(4, init_value=0, constrain_fn=lambda x: 1), ["Discrete(4)", "return a bool", "got 1 (int)"]),
        (lambda: Discrete(4, init_value=0, constrain_fn=lambda x: None), ["Discrete(4)", "got None (NoneType)"]),
        (
            lambda: Dict({"a": Discrete(3, init_value=0)}, constrain_fn=lambda v: "yes"),
            ["Dict with keys ['a']", "got 'yes' (str)"],
        ),
        (
            lambda: Dict({"a": Discrete(3, init_value=0)}, constrain_fn=lambda v: np.ones(2, bool)),
            ["Dict with keys", "ndarray"],
        ),
    ],
    ids=["box-array", "box-one-element-array", "discrete-int", "discrete-none", "dict-str", "dict-array"],
)
def test_constraint_returning_a_non_bool_raises_space_error_when_called(make, fragments, call):
    space = make()  # accepted at construction: the function is only called when sampling or checking
    with pytest.raises(SpaceError) as info:
        if call == "contains":
            space.contains(space.value)
        else:
            getattr(space, call)()
    message = str(info.value)
    assert "np.all" in message  # the fix
    for fragment in fragments:
        assert fragment in message, (fragment, message)


@pytest.mark.parametrize(
    "fn",
    [lambda x: True, lambda x: np.bool_(False) or np.True_, lambda x: bool(np.all(x >= 0)), lambda x: np.all(x <= 1)],
)
def test_bool_and_numpy_bool_results_are_accepted(fn):
    space = _leaf(fn)
    space.seed(0)
    assert space.check()
    space.sample()


def test_valid_and_documented_cases_still_work(caplog):
    assert Box(0.0, 0.0, shape=()).sample() == 0.0  # low == high is a point, not an error
    assert Box(-np.inf, np.inf, shape=(2,)).sample().shape == (2,)
    assert Discrete(np.int32(1)).sample() == 0
    np.testing.assert_array_equal(MultiDiscrete(np.array([2.0, 3.0])).nvec, [2, 3])
    box = Box(0.0, 1.0, shape=(), init_value=0.75, constrain_fn=lambda x: x < 0.5)
    with caplog.at_level(logging.WARNING, logger="stable_worldmodel.spaces"):
        assert not box.check()  # the init_value breaks the constraint: a warning, not an error
    assert "does not satisfy constrain_fn" in caplog.text


def test_error_class_keeps_value_error_for_callers():
    with pytest.raises(ValueError, match=re.escape("got 0")):
        Discrete(0)

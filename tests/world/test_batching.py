"""Stacking per-env values into batches (world/batching.py)."""

from __future__ import annotations

import numpy as np
import pytest

from stable_worldmodel.world.batching import stack, stack_dicts


@pytest.mark.parametrize(
    "values",
    [
        [np.zeros((2, 3), np.uint8), np.ones((2, 3), np.uint8)],
        [np.float32(1.5), np.float32(2.5), np.float32(3.5)],
        [np.array(True), np.array(False)],
        [np.array([1], np.int32), np.array([2.5], np.float32)],  # promoted as np.stack does
        [np.int64(3), np.float32(2.0)],
        [np.zeros(0), np.zeros(0)],
    ],
)
def test_stack_gives_what_np_stack_gives(values):
    out, expected = stack(values), np.stack(values)
    assert out.dtype == expected.dtype and out.shape == expected.shape
    np.testing.assert_array_equal(out, expected)
    assert out.flags.owndata  # a copy: later writes into the envs' arrays do not reach it


def test_stack_of_different_shapes_fails_as_np_stack_does():
    with pytest.raises(ValueError, match="same shape"):
        stack([np.zeros(2), np.zeros(3)])


def test_stack_dicts_fills_a_key_some_envs_lack():
    out = stack_dicts([{"a": np.float32(1), "b": np.int64(2)}, {"a": np.float32(3)}])
    np.testing.assert_array_equal(out["a"], [1, 3])
    assert out["b"].tolist() == [2, 0] and out["b"].dtype == np.int64
    assert np.isnan(stack_dicts([{"a": np.float32(1)}, {"b": 1}])["a"][1])

"""prepare_info / to_env_actions: numpy infos <-> torch, processors and transforms."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
import torch

from stable_worldmodel.errors import SpaceError
from stable_worldmodel.planning.io import prepare_info, to_env_actions


class Affine:
    """A fitted normalizer (sklearn style): records the shapes it is given."""

    def __init__(self, scale, shift=0.0):
        self.scale, self.shift, self.shapes = scale, shift, []

    def transform(self, x):
        self.shapes.append(x.shape)
        assert isinstance(x, np.ndarray) and x.ndim == 2
        return x * self.scale + self.shift

    def inverse_transform(self, x):
        self.shapes.append(x.shape)
        assert isinstance(x, np.ndarray) and x.ndim == 2
        return (x - self.shift) / self.scale


def infos(b=2, t=3):
    return {
        "state": np.arange(b * t * 4, dtype=np.float64).reshape(b, t, 4),
        "goal_state": np.ones((b, t, 4), np.float32),
        "pixels": np.zeros((b, t, 8, 6, 3), np.uint8),
        "goal": np.full((b, t, 8, 6, 3), 255, np.uint8),
        "name": np.array([["a"] * t] * b),
        "step_idx": np.zeros((b, t), np.int64),
    }


def test_numeric_arrays_become_tensors_and_strings_stay():
    raw = infos()
    out = prepare_info(raw)
    assert torch.is_tensor(out["state"]) and out["state"].dtype == torch.float64 and out["state"].shape == (2, 3, 4)
    assert torch.is_tensor(out["step_idx"]) and out["pixels"].shape == (2, 3, 8, 6, 3)
    assert isinstance(out["name"], np.ndarray) and out["name"][1, 2] == "a"
    assert set(out) == set(raw) and isinstance(raw["state"], np.ndarray)  # input untouched


def test_process_runs_on_2d_numpy_and_goal_keys_fall_back():
    norm = Affine(2.0, 1.0)
    raw = infos()
    out = prepare_info(raw, process={"state": norm})
    assert norm.shapes == [(6, 4), (6, 4)]  # state and goal_state, flattened to (-1, D)
    assert torch.allclose(out["state"], torch.from_numpy(raw["state"] * 2 + 1))
    assert torch.allclose(out["goal_state"], torch.full((2, 3, 4), 3.0))
    assert np.array_equal(raw["state"], infos()["state"])  # not modified in place


def test_transform_gets_image_batches_channels_first():
    seen = []

    def to_float(x):
        seen.append(tuple(x.shape))
        return x.float() / 255

    out = prepare_info(infos(), transform={"pixels": to_float, "step_idx": lambda x: x + 1})
    assert seen == [(6, 3, 8, 6), (6, 3, 8, 6)]  # pixels, then goal through the pixels transform
    assert out["pixels"].shape == (2, 3, 3, 8, 6) and out["pixels"].dtype == torch.float32
    assert torch.all(out["goal"] == 1.0) and torch.all(out["step_idx"] == 1)


def test_process_then_transform_order():
    out = prepare_info(
        {"state": np.ones((1, 1, 2))}, process={"state": Affine(3.0)}, transform={"state": lambda x: x - 1}
    )
    assert torch.allclose(out["state"], torch.full((1, 1, 2), 2.0, dtype=torch.float64))


def test_to_env_actions_shapes_bounds_and_inverse_transform():
    space = gym.spaces.Box(-1.0, 1.0, (3, 2), np.float32)
    action = torch.tensor([[0.5, 4.0], [-0.2, 0.1], [-3.0, 0.0]])
    out = to_env_actions(action, None, space)
    assert out.shape == (3, 2) and out.dtype == np.float32
    assert np.allclose(out, [[0.5, 1.0], [-0.2, 0.1], [-1.0, 0.0]])
    norm = Affine(0.5)
    out = to_env_actions(action.reshape(3, 1, 2), {"action": norm}, space)  # any shape with B x A numbers
    assert norm.shapes == [(3, 2)] and np.allclose(out[1], [-0.4, 0.2])
    steps = to_env_actions(torch.zeros(3, 4, 2) + 0.25, {"action": norm}, space, steps=True)
    assert steps.shape == (3, 4, 2) and np.allclose(steps, 0.5)
    with pytest.raises(SpaceError, match="actions"):
        to_env_actions(torch.zeros(3, 4, 2), None, space)
    with pytest.raises(SpaceError, match="actions"):
        to_env_actions(torch.zeros(3, 3), None, space, steps=True)


def test_to_env_actions_discrete_rounds_and_clips():
    space = gym.vector.utils.batch_space(gym.spaces.Discrete(4), 3)
    out = to_env_actions(torch.tensor([0.6, 7.0, -2.0]), None, space)
    assert out.dtype == space.dtype and out.tolist() == [1, 3, 0]
    steps = to_env_actions(torch.tensor([[1.0, 2.0], [3.0, 9.0], [0.0, 0.0]]), None, space, steps=True)
    assert steps.shape == (3, 2) and steps.tolist() == [[1, 2], [3, 3], [0, 0]]

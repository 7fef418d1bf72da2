"""Wrapper behaviours of the original release (0.0.3, same in upstream 0.1.1) that stay available.

Observed there: ``render()`` returning a dict or list gives several ``pixels.*`` views,
``StackedWrapper`` keeps torch tensors and lists and has ``get_buffer_data``,
``EverythingToInfoWrapper`` refuses colliding info keys and Dict action spaces,
``VariationWrapper`` refuses sub-envs with differing spaces and has ``envs``, and
``MegaWrapper`` runs goal-less envs with its defaults.
"""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
import torch

from stable_worldmodel import keys
from stable_worldmodel.envs.toy import ToyEnv
from stable_worldmodel.wrapper import (
    AddPixelsWrapper,
    EverythingToInfoWrapper,
    MegaWrapper,
    StackedWrapper,
    VariationWrapper,
)


class Plain(gym.Env):
    """A goal-less env; ``render()`` returns one image, a dict or a list of views; ``extra`` is merged into info."""

    metadata = {"render_modes": ["rgb_array"]}

    def __init__(self, views="single", extra=None, action_space=None):
        self.views = views
        self.extra = dict(extra or {})
        self.render_mode = "rgb_array"
        self.observation_space = gym.spaces.Box(-1, 1, (2,), np.float32)
        self.action_space = action_space or gym.spaces.Box(-1, 1, (2,), np.float32)
        self.t = 0

    def reset(self, *, seed=None, options=None):
        super().reset(seed=seed)
        self.t = 0
        return np.zeros(2, np.float32), dict(self.extra)

    def step(self, action):
        self.t += 1
        return np.full(2, self.t, np.float32), 0.0, False, False, dict(self.extra)

    def render(self):
        img = np.full((12, 12, 3), self.t, np.uint8)
        if self.views == "dict":
            return {"top": img, "side": img + 1}
        if self.views == "list":
            return [img, img + 1]
        return img


# -- AddPixelsWrapper / MegaWrapper: several views from render() ------------------------------------
@pytest.mark.parametrize("views, names", [("dict", ["top", "side"]), ("list", ["0", "1"])])
def test_render_returning_several_views(views, names):
    _, info = AddPixelsWrapper(Plain(views), pixels_shape=(8, 8)).reset(seed=0)
    assert keys.PIXELS not in info
    for i, name in enumerate(names):
        assert info[f"{keys.PIXELS}.{name}"].shape == (8, 8, 3)
        assert (info[f"{keys.PIXELS}.{name}"] == i).all()

    _, info = MegaWrapper(Plain(views), image_shape=(8, 8), history_size=2).reset(seed=0)
    for name in names:
        assert info[f"{keys.PIXELS}.{name}"].shape == (2, 8, 8, 3)


# -- StackedWrapper -------------------------------------------------------------------------------
class Mixed(Plain):
    def reset(self, *, seed=None, options=None):
        obs, _ = super().reset(seed=seed)
        return obs, {"t": torch.tensor([0.0]), "l": [0, 1], "n": 0}

    def step(self, action):
        obs, r, te, tr, _ = super().step(action)
        return obs, r, te, tr, {"t": torch.tensor([float(self.t)]), "l": [self.t, 1], "n": self.t}


def test_stacked_keeps_tensors_and_lists():
    env = StackedWrapper(Mixed(), ["t", "l", "n"], history_size=3)
    env.reset(seed=0)
    _, _, _, _, info = env.step(None)
    assert torch.is_tensor(info["t"]) and info["t"].shape == (3, 1)
    torch.testing.assert_close(info["t"], torch.tensor([[0.0], [0.0], [1.0]]))
    assert info["l"] == [[0, 1], [0, 1], [1, 1]]  # a list of the history values
    assert isinstance(info["n"], np.ndarray) and info["n"].tolist() == [0, 0, 1]


def test_stacked_get_buffer_data():
    env = StackedWrapper(Mixed(), ["t", "l", "n"], history_size=2, frameskip=2)
    assert env.get_buffer_data("n") == []  # nothing seen yet
    env.reset(seed=0)
    for _ in range(3):
        _, _, _, _, info = env.step(None)
    assert env.get_buffer_data("n").tolist() == info["n"].tolist() == [1, 3]
    torch.testing.assert_close(env.get_buffer_data("t"), info["t"])
    one = StackedWrapper(Mixed(), "t")
    _, info = one.reset(seed=0)
    assert torch.is_tensor(info["t"]) and info["t"].shape == (1, 1)
    torch.testing.assert_close(one.get_buffer_data("t"), info["t"])


def test_stacked_history_one_adds_the_axis_to_every_kind():
    """history_size=1, the default: an array gains a leading axis without a copy, other values
    as with a longer history, and the buffer holds the newest value after a reset and each step."""

    class Kinds(Mixed):
        def step(self, action):
            obs, r, te, tr, info = super().step(action)
            return obs, r, te, tr, {**info, "a": self.frame, "f": np.float32(self.t)}

        def reset(self, *, seed=None, options=None):
            self.frame = np.zeros((2, 2), np.uint8)
            obs, info = super().reset(seed=seed, options=options)
            return obs, {**info, "a": self.frame, "f": np.float32(0)}

    env = StackedWrapper(Kinds(), None)
    _, info = env.reset(seed=0)
    assert info["a"].shape == (1, 2, 2) and np.shares_memory(info["a"], env.unwrapped.frame)
    for _ in range(2):
        _, _, _, _, info = env.step(None)
    assert info["n"].tolist() == [2] and info["n"].dtype == np.asarray(2).dtype
    assert info["f"].tolist() == [2.0] and info["f"].dtype == np.float32
    assert info["l"] == [[2, 1]] and torch.is_tensor(info["t"]) and info["t"].shape == (1, 1)
    for key in ("n", "f", "a"):
        np.testing.assert_array_equal(env.get_buffer_data(key), info[key])


# -- EverythingToInfoWrapper ----------------------------------------------------------------------
@pytest.mark.parametrize("key", ["reward", "terminated", "action", "step_idx", "id", "observation"])
def test_everything_to_info_refuses_colliding_keys(key):
    env = EverythingToInfoWrapper(Plain(extra={key: 1}))
    with pytest.raises(ValueError, match=repr(key)) as info:
        env.reset(seed=0)
    assert isinstance(info.value, AssertionError)  # 0.0.3 asserted


def test_everything_to_info_refuses_an_observation_key_it_adds():
    class DictObs(Plain):
        def __init__(self):
            super().__init__()
            self.observation_space = gym.spaces.Dict({"reward": gym.spaces.Box(-1, 1, (1,))})

        def reset(self, *, seed=None, options=None):
            return {"reward": np.zeros(1, np.float32)}, {}

    with pytest.raises(AssertionError, match="reward"):
        EverythingToInfoWrapper(DictObs()).reset(seed=0)


def test_everything_to_info_refuses_dict_action_spaces():
    space = gym.spaces.Dict({"move": gym.spaces.Box(-1, 1, (2,), np.float32)})
    with pytest.raises(NotImplementedError, match="Dict") as info:
        EverythingToInfoWrapper(Plain(action_space=space))
    assert isinstance(info.value, ValueError)


# -- VariationWrapper -----------------------------------------------------------------------------
def test_variation_wrapper_refuses_sub_envs_with_differing_spaces():
    vec = gym.vector.SyncVectorEnv([lambda: ToyEnv() for _ in range(2)])
    vec.envs[1].unwrapped.observation_space = gym.spaces.Box(-1, 1, (5,), np.float32)
    for mode in ("same", "different"):
        with pytest.raises(ValueError, match="do not share a common shape and dtype"):
            VariationWrapper(vec, variation_mode=mode)


def test_variation_wrapper_exposes_the_sub_envs():
    vec = gym.vector.SyncVectorEnv([lambda: ToyEnv() for _ in range(2)])
    wrapper = VariationWrapper(vec)
    assert wrapper.envs is vec.envs and len(wrapper.envs) == 2


# -- MegaWrapper on goal-less envs ------------------------------------------------------------------
def test_mega_wrapper_defaults_accept_goal_less_envs():
    env = MegaWrapper(Plain(), image_shape=(8, 8))
    _, info = env.reset(seed=0)
    assert keys.GOAL not in info and info[keys.PIXELS].shape == (1, 8, 8, 3)
    env.step(np.zeros(2, np.float32))
    with pytest.raises(RuntimeError, match="goal"):  # asking for the goal still checks it
        MegaWrapper(Plain(), image_shape=(8, 8), separate_goal=True).reset(seed=0)


# -- the original messages' phrases stay inside ours ------------------------------------------------
def test_check_wrappers_keep_the_original_phrases():
    from stable_worldmodel.wrapper import EnsureGoalInfoWrapper, EnsureImageShape, EnsureInfoKeysWrapper

    with pytest.raises(RuntimeError, match="required info keys missing"):
        EnsureInfoKeysWrapper(Plain(), [r"^pixels$"]).reset(seed=0)
    with pytest.raises(RuntimeError, match="must contain the key 'goal'"):
        EnsureGoalInfoWrapper(Plain(), check_reset=True).reset(seed=0)
    with pytest.raises(RuntimeError, match="should be"):
        EnsureImageShape(AddPixelsWrapper(Plain(), (8, 8)), keys.PIXELS, (4, 4)).reset(seed=0)
    with pytest.raises(ValueError, match="Invalid `variation_mode`"):
        VariationWrapper(gym.vector.SyncVectorEnv([ToyEnv]), variation_mode="sometimes")

"""Behaviour of every wrapper of stable_worldmodel.wrapper on the toy env."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import stable_worldmodel as swm
from stable_worldmodel import keys
from stable_worldmodel.envs.toy import ToyEnv
from stable_worldmodel.errors import ConfigError
from stable_worldmodel.wrapper import (
    AddPixelsWrapper,
    EnsureGoalInfoWrapper,
    EnsureImageShape,
    EnsureInfoKeysWrapper,
    EverythingToInfoWrapper,
    MegaWrapper,
    ResizeGoalWrapper,
    StackedWrapper,
    VariationWrapper,
)


class NoSizeEnv(ToyEnv):
    """A toy env that cannot draw at a requested size (exercises resizing)."""

    set_render_size = None  # type: ignore[assignment]


class MultiviewEnv(ToyEnv):
    def __init__(self, views="dict", **kw):
        super().__init__(**kw)
        self.views = views

    def render_multiview(self):
        img = self.render()
        return {"top": img, "side": img[::-1].copy()} if self.views == "dict" else [img, img[:, ::-1].copy()]


def test_seed_000_name_is_importable():
    import stable_worldmodel.wrappers as w

    assert w.MegaWrapper is MegaWrapper
    assert swm.wrappers.AddPixelsWrapper is AddPixelsWrapper


def test_add_pixels_draws_at_target_size_without_resizing():
    env = AddPixelsWrapper(ToyEnv(), pixels_shape=(32, 48))
    _, info = env.reset(seed=0)
    assert info[keys.PIXELS].shape == (32, 48, 3) and info[keys.PIXELS].dtype == np.uint8
    assert env.unwrapped.render_size == (32, 48)
    assert info[keys.RENDER_TIME] >= 0
    _, _, _, _, info = env.step(np.zeros(2, np.float32))
    assert info[keys.PIXELS].shape == (32, 48, 3)


def test_add_pixels_resizes_other_envs_and_applies_transform():
    env = NoSizeEnv(render_size=(100, 100))
    wrapped = AddPixelsWrapper(env, pixels_shape=(20, 30), torchvision_transform=lambda img: img[..., ::-1].copy())
    _, info = wrapped.reset(seed=0)
    assert info[keys.PIXELS].shape == (20, 30, 3)
    bg = env.variation_space["background"]["color"].value
    assert np.array_equal(info[keys.PIXELS][0, 0], bg[::-1])  # channel flip applied


@pytest.mark.parametrize("views, names", [("dict", ["top", "side"]), ("list", ["0", "1"])])
def test_add_pixels_multiview(views, names):
    env = AddPixelsWrapper(MultiviewEnv(views=views), pixels_shape=(16, 16))
    _, info = env.reset(seed=0)
    for name in names:
        assert info[f"{keys.PIXELS}.{name}"].shape == (16, 16, 3)
    assert keys.PIXELS not in info


def test_everything_to_info_reset_and_step_keys():
    env = EverythingToInfoWrapper(ToyEnv())
    obs, info = env.reset(seed=3)
    assert np.isnan(info[keys.REWARD])
    assert np.isnan(info[keys.ACTION]).all() and info[keys.ACTION].shape == (2,)
    assert info[keys.STEP_IDX] == 0 and info[keys.EPISODE_ID] == 0
    assert info[keys.TERMINATED] is False and info[keys.TRUNCATED] is False
    assert np.array_equal(info[keys.STATE], obs[keys.STATE])
    action = np.array([0.5, -0.5], np.float32)
    _, reward, _, _, info2 = env.step(action)
    assert info2[keys.REWARD] == reward
    assert np.array_equal(info2[keys.ACTION], action)
    assert info2[keys.STEP_IDX] == 1
    assert set(info) == set(info2)
    env.reset(seed=4)
    _, info3 = env.reset(seed=5)
    assert info3[keys.EPISODE_ID] == 2


def test_everything_to_info_variation_keys():
    env = EverythingToInfoWrapper(ToyEnv())
    _, info = env.reset(seed=0, options={"variation": ["agent.color"]})
    assert "variation.agent.color" in info and "variation.goal.color" not in info
    _, _, _, _, info = env.step(np.zeros(2, np.float32))
    assert "variation.agent.color" in info  # kept for the whole episode
    _, info = env.reset(seed=0, options={"variation": ["all"]})
    names = env.unwrapped.variation_space.names()
    assert {f"variation.{n}" for n in names} <= set(info)
    _, info = env.reset(seed=1)  # no option: the factors named last are reported again (observed on 0.0.3)
    assert {f"variation.{n}" for n in names} <= set(info)
    _, info = env.reset(seed=0, options={"variation": []})  # an empty list stops it
    assert not any(k.startswith("variation.") for k in info)
    _, info = env.reset(seed=0)
    assert not any(k.startswith("variation.") for k in info)
    fresh = EverythingToInfoWrapper(ToyEnv())
    assert not any(k.startswith("variation.") for k in fresh.reset(seed=0)[1])


def test_everything_to_info_non_dict_observation():
    env = EverythingToInfoWrapper(gym.make("CartPole-v1"))
    _, info = env.reset(seed=0)
    assert info["observation"].shape == (4,)
    _, _, _, _, info = env.step(1)
    assert info[keys.ACTION].shape == () and info[keys.ACTION] == 1.0


def test_ensure_info_keys_regex_whole_match():
    env = EnsureInfoKeysWrapper(AddPixelsWrapper(ToyEnv(), (8, 8)), [r"^pixels(?:\..*)?$", r"goal_.*"])
    env.reset(seed=0)
    bad = EnsureInfoKeysWrapper(ToyEnv(), ["goal_st"])  # must match a whole key, not a prefix
    with pytest.raises(RuntimeError, match="goal_st"):
        bad.reset(seed=0)
    missing = EnsureInfoKeysWrapper(ToyEnv(), ["pixels"])
    with pytest.raises(RuntimeError, match="pixels"):
        missing.reset(seed=0)


class NoGoalEnv(ToyEnv):
    def _info(self):
        info = super()._info()
        info.pop(keys.GOAL)
        return info


def test_ensure_goal_info_reset_and_step():
    EnsureGoalInfoWrapper(ToyEnv(), check_reset=True, check_step=True).reset(seed=0)
    with pytest.raises(RuntimeError, match="goal"):
        EnsureGoalInfoWrapper(NoGoalEnv(), check_reset=True).reset(seed=0)
    env = EnsureGoalInfoWrapper(NoGoalEnv(), check_reset=False, check_step=True)
    env.reset(seed=0)
    with pytest.raises(RuntimeError, match="goal"):
        env.step(np.zeros(2, np.float32))


def test_ensure_image_shape():
    env = EnsureImageShape(AddPixelsWrapper(ToyEnv(), (8, 8)), keys.PIXELS, (8, 8))
    env.reset(seed=0)
    with pytest.raises(RuntimeError, match=r"\(9, 8\)"):
        EnsureImageShape(AddPixelsWrapper(ToyEnv(), (8, 8)), keys.PIXELS, (9, 8)).reset(seed=0)
    with pytest.raises(ConfigError):
        EnsureImageShape(ToyEnv(), keys.PIXELS, (0, 8))


def test_resize_goal_once_per_goal():
    env = ResizeGoalWrapper(NoSizeEnv(render_size=(64, 64)), pixels_shape=(16, 16))
    _, info = env.reset(seed=0)
    assert info[keys.GOAL].shape == (16, 16, 3)
    for _ in range(5):
        env.step(np.zeros(2, np.float32))
    assert env.resize_count == 1  # the goal did not change: resized once
    env.reset(seed=1)
    assert env.resize_count == 2


@pytest.mark.parametrize("history, skip", [(1, 1), (3, 1), (3, 2)])
def test_stacked_history_axis(history, skip):
    env = StackedWrapper(EverythingToInfoWrapper(ToyEnv()), keys.STEP_IDX, history_size=history, frameskip=skip)
    _, info = env.reset(seed=0)
    assert info[keys.STEP_IDX].shape == (history,)
    assert (info[keys.STEP_IDX] == 0).all()  # filled with the reset value
    assert info[keys.STATE].shape == (2,)  # other keys untouched
    for _ in range(7):
        _, _, _, _, info = env.step(np.zeros(2, np.float32))
    expected = [7 - skip * (history - 1 - i) for i in range(history)]
    assert info[keys.STEP_IDX].tolist() == expected


def test_stacked_validates():
    with pytest.raises(ConfigError, match="history_size"):
        StackedWrapper(ToyEnv(), "x", history_size=0)


def test_mega_wrapper_pipeline():
    env = MegaWrapper(ToyEnv(), image_shape=(24, 24), history_size=2)
    _, info = env.reset(seed=0)
    assert info[keys.PIXELS].shape == (2, 24, 24, 3)
    assert info[keys.GOAL].shape == (2, 24, 24, 3)
    assert info[keys.STATE].shape == (2, 2)
    with pytest.raises(RuntimeError, match="goal"):
        MegaWrapper(NoGoalEnv(), image_shape=(8, 8), separate_goal=True).reset(seed=0)
    MegaWrapper(NoGoalEnv(), image_shape=(8, 8)).reset(seed=0)  # the default accepts goal-less envs
    MegaWrapper(NoGoalEnv(), image_shape=(8, 8), separate_goal=False).reset(seed=0)


def test_variation_wrapper_modes():
    vec = gym.vector.SyncVectorEnv([lambda: ToyEnv() for _ in range(3)])
    same = VariationWrapper(vec, variation_mode="same")
    assert same.single_variation_space is not None
    assert same.variation_space["agent"]["color"].shape == (3, 3)
    different = VariationWrapper(vec, variation_mode="different")
    assert len(different.variation_space) == 3
    with pytest.raises(ValueError, match="variation_mode"):
        VariationWrapper(vec, variation_mode="sometimes")

"""``swm/Piecewise-v0``: upstream's Piecewise (an open room whose zones add a drift) and its expert."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
from env_checks import assert_expert_solves_in_world, assert_factor_changes_episode, assert_render_size

import stable_worldmodel as swm
from stable_worldmodel import keys
from stable_worldmodel.envs.piecewise import PiecewiseEnv, PiecewiseExpert
from stable_worldmodel.envs.piecewise.piecewise_env import DYNAMICS, zone_index
from stable_worldmodel.errors import ConfigError

ENV_ID = "swm/Piecewise-v0"


def make(**kwargs) -> PiecewiseEnv:
    return gym.make(ENV_ID, disable_env_checker=True, **kwargs).unwrapped


def test_factors_are_upstreams():
    env = make()
    names = env.variation_space.names()
    assert len(names) == 21
    for name in ("agent.speed", "target.position", "border.color", "rendering.render_bias_field", "task.min_steps"):
        assert name in names
    assert {f"zones.bias_{i}" for i in range(4)} | {f"zones.color_{i}" for i in range(4)} <= set(names)
    assert len(make(grid_n=3).variation_space.names()) == 13 + 18
    env.reset(seed=0)
    assert np.array_equal(env.variation_space["agent"]["speed"].value, [5.0])
    assert np.array_equal(env.variation_space["zones"]["bias_3"].value, [0.0, 0.0])
    assert env.observation_space.shape == (4,) and env.action_space.shape == (2,)


def test_reset_draws_positions_per_seed_and_takes_upstream_options():
    env = make()
    o1, _ = env.reset(seed=1)
    o2, _ = env.reset(seed=2)
    o1b, info = env.reset(seed=1)
    assert not np.array_equal(o1, o2) and np.array_equal(o1, o1b)
    assert np.array_equal(info[keys.STATE], o1[:2]) and np.array_equal(info[keys.GOAL_STATE], o1[2:])
    obs, info = env.reset(seed=0, options={keys.STATE: [50.0, 60.0], "target_state": [150.0, 160.0]})
    assert np.allclose(obs, [50, 60, 150, 160])
    obs, _ = env.reset(seed=0, options={keys.GOAL_STATE: [100.0, 101.0]})
    assert np.allclose(obs[2:], [100, 101])
    assert info[DYNAMICS].tolist() == [2.0, 5.0] + [0.0] * 8


def test_step_adds_the_zone_bias_and_clamps_at_the_border():
    env = make()
    biases = {"zones.bias_0": [2.0, -1.0], "zones.bias_3": [-4.0, 3.0]}
    env.reset(seed=0, options={keys.STATE: [50.0, 50.0], keys.VARIATION_VALUES: biases})
    assert env.zone(env.agent_position) == 0
    obs, reward, terminated, truncated, _ = env.step(np.array([1.0, 0.5], np.float32))
    assert np.allclose(obs[:2], [50 + 5 + 2, 50 + 2.5 - 1]) and reward == 0.0 and not truncated
    env.reset(seed=0, options={keys.STATE: [150.0, 150.0], keys.VARIATION_VALUES: biases})
    obs, *_ = env.step(np.zeros(2, np.float32))
    assert np.allclose(obs[:2], [146.0, 153.0])  # zone 3 (bottom right)
    env.reset(seed=0, options={keys.STATE: [30.0, 200.0]})
    obs, *_ = env.step(np.array([-5.0, 1.0], np.float32))  # clipped action, then clamped to [21, 203]
    assert np.allclose(obs[:2], [25.0, 203.0])
    assert zone_index(np.array([[14.0, 14.0], [209.0, 14.0], [14.0, 209.0], [300.0, -5.0]]), 2).tolist() == [0, 1, 2, 1]


def test_success_within_16_px_of_the_target():
    env = make()
    env.reset(seed=0, options={keys.STATE: [100.0, 100.0], "target_state": [120.0, 100.0]})
    *_, terminated, _, info = env.step(np.zeros(2, np.float32))
    assert not terminated and info["distance_to_target"] == pytest.approx(20.0)
    *_, terminated, _, info = env.step(np.array([1.0, 0.0], np.float32))
    assert terminated and info["distance_to_target"] == pytest.approx(15.0)
    assert env.eval_state(np.array([0.0, 0.0]), np.array([15.9, 0.0]))[0]
    assert not env.eval_state(np.array([0.0, 0.0]), np.array([16.0, 0.0]))[0]


@pytest.mark.parametrize(
    "factor",
    [
        "agent.color",
        "agent.radius",
        "background.color",
        "border.color",
        "rendering.render_zones",
        "rendering.render_target",
        "rendering.render_bias_field",
    ],
)
def test_visual_factors_change_the_frames(factor):
    def rollout(env, seed, options):
        env.reset(seed=seed, options=options)
        return [env.render()]

    env = make(render_size=(64, 64))
    if factor == "rendering.render_bias_field":  # arrows need a bias to point
        base = {"zones.bias_0": [5.0, 5.0], "zones.bias_1": [5.0, 5.0], "zones.bias_2": [5.0, 5.0]}
        base["zones.bias_3"] = [5.0, 5.0]

        def rollout(env, seed, options):  # noqa: F811 - the biased variant
            values = {**base, **(options or {}).get(keys.VARIATION_VALUES, {})}
            env.reset(seed=seed, options={keys.VARIATION_VALUES: values})
            return [env.render()]

    assert_factor_changes_episode(env, factor, rollout)


def test_zone_colors_show_with_render_zones():
    env = make(render_size=(64, 64))
    on = {"rendering.render_zones": 1}
    env.reset(seed=0, options={keys.VARIATION_VALUES: on})
    a = env.render()
    env.reset(seed=0, options={keys.VARIATION_VALUES: {**on, "zones.color_2": [0, 0, 255]}})
    b = env.render()
    assert (a != b).any(axis=-1)[40:60, 5:30].mean() > 0.5  # the bottom-left zone


def test_render_size_and_goal_image():
    env = make(render_size=(48, 40))
    assert_render_size(env, (48, 40))
    env = make()
    _, info = env.reset(seed=0)
    assert info[keys.GOAL].shape == (224, 224, 3)
    env.reset(seed=0, options={keys.STATE: info[keys.GOAL_STATE]})
    assert np.array_equal(env.render(), info[keys.GOAL])  # the goal image is the agent at the target


def test_bad_arguments_raise_typed_errors():
    with pytest.raises(ConfigError, match="grid_n"):
        PiecewiseEnv(grid_n=0)
    with pytest.raises(ConfigError, match="render_mode"):
        PiecewiseEnv(render_mode="human")
    with pytest.raises(ConfigError, match="state"):
        make().reset(options={keys.STATE: [1.0]})


def test_expert_compensates_the_bias():
    env = make()
    biases = {f"zones.bias_{i}": [3.0, -3.0] for i in range(4)}
    options = {keys.VARIATION_VALUES: biases, keys.STATE: [60.0, 60.0], "target_state": [150.0, 150.0]}
    obs, info = env.reset(seed=4, options=options)
    expert = PiecewiseExpert()
    for _ in range(80):
        infos = {k: np.asarray(info[k])[None, None] for k in (keys.STATE, keys.GOAL_STATE, DYNAMICS)}
        obs, _, terminated, _, info = env.step(expert.get_action(infos)[0])
        if terminated:
            break
    assert terminated


def test_expert_solves_every_episode_in_a_world():
    assert_expert_solves_in_world(ENV_ID, num_envs=4, episodes=8, max_episode_steps=100)


def test_expert_noise_and_repeats_are_seeded():
    infos = {
        keys.STATE: np.array([[[50.0, 50.0]], [[150.0, 60.0]]], np.float32),
        keys.GOAL_STATE: np.array([[[150.0, 150.0]], [[60.0, 60.0]]], np.float32),
        DYNAMICS: np.tile(np.array([2, 5, 0, 0, 0, 0, 0, 0, 0, 0], np.float32), (2, 1, 1)),
        keys.STEP_IDX: np.array([[3], [0]]),
    }
    a = PiecewiseExpert(action_noise=0.3, action_repeat_prob=0.5, seed=7)
    b = PiecewiseExpert(action_noise=0.3, action_repeat_prob=0.5, seed=7)
    for _ in range(3):
        np.testing.assert_array_equal(a.get_action(infos), b.get_action(infos))
    assert np.allclose(PiecewiseExpert().get_action(infos), [[1.0, 1.0], [-1.0, 0.0]])
    with pytest.raises(ConfigError, match="action_repeat_prob"):
        PiecewiseExpert(action_repeat_prob=2.0)
    assert isinstance(swm.envs.expert_policy(ENV_ID), PiecewiseExpert)

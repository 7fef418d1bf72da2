"""Tests of ``swm/ImagePositioning-v1``: rules, factors of variation, rendering and the expert."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
from env_checks import (
    assert_expert_solves_in_world,
    assert_factor_changes_episode,
    assert_render_size,
    count_draws,
    run_actions,
)
from gymnasium.utils.env_checker import check_env

import stable_worldmodel  # noqa: F401  (registers swm/... ids)
from stable_worldmodel import keys
from stable_worldmodel.envs.image_positioning.env import (
    ANGLE_TOLERANCE,
    POSITION_TOLERANCE,
    ImagePositioningEnv,
    wrap_angle,
)
from stable_worldmodel.envs.image_positioning.expert import ImagePositioningExpert
from stable_worldmodel.envs.image_positioning.images import make_sprites
from stable_worldmodel.errors import ConfigError

pytest.importorskip("cv2")


def make_env(**kwargs) -> ImagePositioningEnv:
    return ImagePositioningEnv(render_size=(64, 64), **kwargs)


def rollout(env, seed, options=None, n_steps=4):
    actions = np.random.default_rng(0).uniform(-1, 1, (n_steps, env.action_space.shape[0]))
    return run_actions(env, seed, actions, options)


def test_check_env_passes():
    env = gym.make("swm/ImagePositioning-v1", render_size=(64, 64)).unwrapped  # made: has a spec
    check_env(env, skip_render_check=False)


def test_layout_of_state_goal_and_action():
    env = make_env(n_images=2)
    obs, info = env.reset(seed=0)
    assert env.action_space.shape == (6,)
    assert obs[keys.STATE].shape == obs[keys.PROPRIO].shape == (6,)
    np.testing.assert_array_equal(obs[keys.STATE], obs[keys.PROPRIO])
    v = env.variation_space.value
    np.testing.assert_allclose(obs[keys.STATE].reshape(2, 3)[:, :2], v["start"]["positions"])
    np.testing.assert_allclose(info[keys.GOAL_STATE].reshape(2, 3)[:, :2], v["target"]["positions"])
    np.testing.assert_allclose(info[keys.GOAL_STATE].reshape(2, 3)[:, 2], v["target"]["angles"], atol=1e-6)
    np.testing.assert_array_equal(info[keys.GOAL_PROPRIO], info[keys.GOAL_STATE])
    assert env.eval_state(info[keys.GOAL_STATE], obs[keys.STATE])[0] is False  # defaults are not solved


def test_step_moves_each_image_by_its_own_scaled_delta():
    env = make_env(n_images=2)
    obs, _ = env.reset(seed=0)
    action = np.array([1.0, -0.5, 0.0, 0.0, 0.0, 2.0], np.float32)  # 2.0 is clipped to 1.0
    new, *_ = env.step(action)
    step = env.variation_space.value["step"]
    delta = (new[keys.STATE] - obs[keys.STATE]).reshape(2, 3)
    np.testing.assert_allclose(delta[0], [step["position"], -0.5 * step["position"], 0.0], atol=1e-6)
    np.testing.assert_allclose(delta[1, :2], 0.0, atol=1e-7)
    np.testing.assert_allclose(wrap_angle(delta[1, 2]), step["angle"], atol=1e-6)


def test_positions_clip_to_the_canvas_and_angles_wrap():
    env = make_env(n_images=1)
    env.reset(seed=0, options={"state": np.array([0.99, 0.01, np.pi - 0.01])})
    obs, *_ = env.step(np.array([1.0, -1.0, 1.0]))
    x, y, a = obs[keys.STATE]
    assert (x, y) == (1.0, 0.0)
    assert -np.pi <= a < 0  # crossed +pi and wrapped around
    assert env.observation_space.contains(obs)


def test_success_needs_every_image_within_both_tolerances():
    env = make_env(n_images=2)
    goal = np.array([0.5, 0.5, 0.0, 0.2, 0.2, 1.0])
    assert env.eval_state(goal, goal) == (True, 0.0)
    near = goal + np.array([0.9 * POSITION_TOLERANCE, 0, 0.9 * ANGLE_TOLERANCE, 0, 0, 0])
    assert env.eval_state(goal, near)[0]
    for i, tol in ((0, POSITION_TOLERANCE), (2, ANGLE_TOLERANCE), (4, POSITION_TOLERANCE), (5, ANGLE_TOLERANCE)):
        off = goal.copy()
        off[i] += 1.1 * tol
        success, dist = env.eval_state(goal, off)
        assert not success and dist > 0
    wrapped = goal.copy()
    wrapped[2] = 2 * np.pi - 0.5 * ANGLE_TOLERANCE  # the same angle, one turn later
    assert env.eval_state(goal, wrapped)[0]


def test_reaching_the_goal_terminates():
    env = make_env(n_images=1)
    goal = np.array([0.5, 0.5, 0.0])
    env.reset(seed=0, options={"state": np.array([0.45, 0.5, 0.0]), "goal_state": goal})
    _, reward, terminated, truncated, _ = env.step(np.array([1.0, 0.0, 0.0]))
    assert terminated and not truncated and reward == pytest.approx(0.0, abs=1e-6)


def test_bad_inputs_raise_typed_errors():
    env = make_env()
    with pytest.raises(ConfigError, match="state of shape"):
        env.reset(seed=0, options={"state": np.zeros(4)})
    with pytest.raises(ConfigError, match="n_images"):
        ImagePositioningEnv(n_images=0)


def test_same_seed_same_episode_bit_for_bit():
    env_a, env_b = make_env(), make_env()
    opts = {"variation": ["all"]}
    a, b = rollout(env_a, 7, opts), rollout(env_b, 7, opts)
    for x, y in zip(a, b, strict=False):
        np.testing.assert_array_equal(x, y)
    c = rollout(env_b, 8, opts)
    assert not np.array_equal(a[0], c[0])


def test_image_set_is_procedural_and_seeded():
    a, b, c = make_sprites(3, 3), make_sprites.__wrapped__(3, 3), make_sprites(4, 3)
    assert len(a) == 3 and all(len(s.parts) >= 2 for s in a)  # the marker plus at least one shape
    for x, y in zip(a, b, strict=False):  # a pure function of (seed, n)
        assert x.tile_color == y.tile_color
        for (p, pc), (q, qc) in zip(x.parts, y.parts, strict=False):
            np.testing.assert_array_equal(p, q)
            assert pc == qc
    assert [s.tile_color for s in a] != [s.tile_color for s in c]


def test_rotation_is_visible():
    env = make_env(n_images=1)
    env.reset(seed=0, options={"state": np.array([0.5, 0.5, 0.0])})
    frames = [env.render()]
    for _ in range(3):  # quarter turns: the marker corner makes every one of them visible
        env.reset(seed=0, options={"state": np.array([0.5, 0.5, np.pi / 2 * (len(frames))])})
        frames.append(env.render())
    for i in range(4):
        for j in range(i):
            assert np.abs(frames[i].astype(int) - frames[j]).sum() > 1000


@pytest.mark.parametrize("name", ImagePositioningEnv().variation_space.names())
def test_every_factor_changes_the_episode(name):
    assert_factor_changes_episode(make_env(), name, rollout)


@pytest.mark.parametrize("size", [(64, 64), (48, 80), (224, 224)])
def test_render_size(size):
    assert_render_size(ImagePositioningEnv(render_size=size), size)


def test_goal_image_is_the_target_arrangement_drawn_once():
    env = make_env()
    draws = count_draws(env)
    _, info = env.reset(seed=0)
    _, _, _, _, info2 = env.step(env.action_space.sample())
    assert len(draws) == 1
    np.testing.assert_array_equal(info2[keys.GOAL], info[keys.GOAL])
    env.reset(seed=0, options={"state": info[keys.GOAL_STATE]})
    np.testing.assert_array_equal(env.render(), info[keys.GOAL])


def run_expert(env, seed, options=None, max_steps=100):
    expert = ImagePositioningExpert()
    obs, info = env.reset(seed=seed, options=options)
    for _ in range(max_steps):
        batch = {keys.STATE: obs[keys.STATE][None, None], keys.GOAL_STATE: info[keys.GOAL_STATE][None, None]}
        action = expert.get_action(batch)
        assert action.shape == (1, env.action_space.shape[0]) and action.dtype == np.float32
        obs, _, terminated, truncated, info = env.step(action[0])
        if terminated:
            return True
    return False


def test_expert_reaches_the_goal():
    env = make_env()
    assert run_expert(env, 0)
    assert all(run_expert(env, seed, {"variation": ["all"]}) for seed in range(5))


def test_expert_reads_step_sizes_when_recorded():
    goal = np.array([[0.5, 0.5, 0.0]])
    cur = np.array([[0.45, 0.5, -0.1]])
    infos = {keys.STATE: cur[:, None], keys.GOAL_STATE: goal[:, None]}
    default = ImagePositioningExpert().get_action(infos)
    infos["variation.step.position"] = np.array([[0.05]])
    infos["variation.step.angle"] = np.array([[0.1]])
    exact = ImagePositioningExpert().get_action(infos)
    np.testing.assert_allclose(exact, [[1.0, 0.0, 1.0]], atol=1e-6)
    assert np.all(np.abs(default) < np.abs(exact) + 1e-6) and default[0, 0] < 1.0


@pytest.mark.parametrize("num_envs", [1, 4])
def test_expert_solves_episodes_in_world(num_envs):
    assert_expert_solves_in_world("swm/ImagePositioning-v1", num_envs, episodes=4, max_episode_steps=60)


def test_reset_from_dataset_rows_restores_state_goal_and_factors():
    env = make_env()
    obs, _ = env.reset(seed=5, options={"variation": ["start"]})
    goal = np.tile(np.array([0.5, 0.5, 1.0], np.float32), 3)
    options = env.reset_options_from_dataset(
        {keys.STATE: obs[keys.STATE], "variation.images.seed": np.array(42)}, {keys.STATE: goal}
    )
    obs2, info = env.reset(seed=0, options=options)
    np.testing.assert_allclose(obs2[keys.STATE], obs[keys.STATE], atol=1e-6)
    np.testing.assert_allclose(info[keys.GOAL_STATE], goal, atol=1e-6)
    assert env.variation_space.value["images"]["seed"] == 42

"""Tests of ``swm/VoidRun-v0``: rules, factors of variation, rendering and the expert."""

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
from stable_worldmodel.envs.voidrun.env import DOWN, LEFT, RIGHT, UP, VoidRunEnv, shortest_path_lengths
from stable_worldmodel.envs.voidrun.expert import VoidRunExpert

pytest.importorskip("cv2")

N = 8


def make_env(**kwargs) -> VoidRunEnv:
    return VoidRunEnv(render_size=(64, 64), **kwargs)


def open_floor(agent=(0, 0), goal=(N - 1, N - 1), holes=()) -> np.ndarray:
    """A state vector with the agent and goal at the given cells and the listed cells missing."""
    mask = np.ones((N, N), np.float32)
    for x, y in holes:
        mask[y, x] = 0
    return np.concatenate([np.asarray(agent, np.float32), np.asarray(goal, np.float32), mask.reshape(-1)])


def rollout(env, seed, options=None, actions=(RIGHT, DOWN, RIGHT, DOWN, RIGHT, DOWN)):
    return run_actions(env, seed, actions, options)


def test_check_env_passes():
    env = gym.make("swm/VoidRun-v0", render_size=(64, 64)).unwrapped  # made: has a spec
    check_env(env, skip_render_check=False)


def test_observation_layout_and_spaces():
    env = make_env()
    obs, info = env.reset(seed=0)
    assert env.action_space.n == 4
    assert obs[keys.STATE].shape == (4 + N * N,) and obs[keys.PROPRIO].shape == (2,)
    np.testing.assert_array_equal(obs[keys.PROPRIO], [1, 1])  # default start
    np.testing.assert_array_equal(obs[keys.STATE][2:4], [N - 2, N - 2])  # default goal
    np.testing.assert_array_equal(info[keys.GOAL_PROPRIO], [N - 2, N - 2])
    np.testing.assert_array_equal(info[keys.GOAL_STATE][:2], [N - 2, N - 2])
    np.testing.assert_array_equal(info[keys.GOAL_STATE][4:], obs[keys.STATE][4:])
    assert env.observation_space.contains(obs)


def test_reset_layout_leaves_a_path_and_keeps_start_and_goal():
    env = make_env()
    env.reset(seed=0, options={"variation_values": {"floor.holes": 0.35}})
    for seed in range(20):
        obs, _ = env.reset(seed=seed, options={"variation_values": {"floor.holes": 0.35}})
        mask = obs[keys.STATE][4:].reshape(N, N) > 0.5
        assert mask[1, 1] and mask[N - 2, N - 2]
        assert mask[0, 1] and mask[2, 1] and mask[1, 0] and mask[1, 2]  # the start's neighbours
        assert shortest_path_lengths(mask, (N - 2, N - 2))[1, 1] > 0
    assert (~mask).sum() > 5  # holes were made


@pytest.mark.parametrize("action,delta", [(LEFT, (-1, 0)), (RIGHT, (1, 0)), (DOWN, (0, 1)), (UP, (0, -1))])
def test_action_numbering(action, delta):
    env = make_env()
    env.reset(seed=0, options={"state": open_floor(agent=(3, 3))})
    obs, reward, terminated, truncated, _ = env.step(action)
    np.testing.assert_array_equal(obs[keys.PROPRIO], np.add((3, 3), delta))
    assert (reward, terminated, truncated) == (0.0, False, False)


def test_floor_breaks_behind_the_agent_with_prob_break():
    env = make_env()
    for p, expected in ((1.0, 0.0), (0.0, 1.0)):
        env.reset(seed=0, options={"state": open_floor(agent=(3, 3)), "variation_values": {"prob_break": p}})
        obs, *_ = env.step(RIGHT)
        mask = obs[keys.STATE][4:].reshape(N, N)
        assert mask[3, 3] == expected  # the cell left behind
        assert mask[3, 4] == 1.0 and mask.sum() == N * N - (1 - expected)
    # about half of the cells break at the default prob_break = 0.5
    broken = []
    for seed in range(40):
        env.reset(seed=seed, options={"state": open_floor(agent=(3, 3))})
        obs, *_ = env.step(RIGHT)
        broken.append(obs[keys.STATE][4 + 3 * N + 3] == 0)
    assert 0.25 < np.mean(broken) < 0.75


def test_stepping_back_onto_a_broken_cell_is_a_fall_not_a_success():
    env = make_env()
    env.reset(seed=0, options={"state": open_floor(agent=(3, 3)), "variation_values": {"prob_break": 1.0}})
    env.step(RIGHT)
    obs, reward, terminated, truncated, _ = env.step(LEFT)
    assert (terminated, truncated, reward) == (False, True, -1.0)
    np.testing.assert_array_equal(obs[keys.PROPRIO], [3, 3])
    # the episode is over: further steps change nothing
    obs2, reward2, terminated2, truncated2, _ = env.step(UP)
    np.testing.assert_array_equal(obs2[keys.STATE], obs[keys.STATE])
    assert (terminated2, truncated2, reward2) == (False, True, 0.0)


@pytest.mark.parametrize("agent,action", [((0, 3), LEFT), ((N - 1, 3), RIGHT), ((3, 0), UP), ((3, N - 1), DOWN)])
def test_walking_off_the_grid_is_a_fall(agent, action):
    env = make_env()
    env.reset(seed=0, options={"state": open_floor(agent=agent, goal=(4, 4))})
    obs, reward, terminated, truncated, _ = env.step(action)
    assert (terminated, truncated, reward) == (False, True, -1.0)
    assert env.observation_space.contains(obs)  # the agent hangs one cell outside the grid
    assert env.eval_state(env._info()[keys.GOAL_STATE], obs[keys.STATE])[0] is False


def test_initial_hole_is_a_fall():
    env = make_env()
    env.reset(seed=0, options={"state": open_floor(agent=(2, 2), holes=[(3, 2)])})
    _, _, terminated, truncated, _ = env.step(RIGHT)
    assert (terminated, truncated) == (False, True)


def test_reaching_the_goal_is_success():
    env = make_env()
    _, info = env.reset(seed=0, options={"state": open_floor(agent=(5, 6), goal=(6, 6))})
    obs, reward, terminated, truncated, _ = env.step(RIGHT)
    assert (terminated, truncated, reward) == (True, False, 1.0)
    assert env.eval_state(info[keys.GOAL_STATE], obs[keys.STATE]) == (True, 0.0)
    assert env.eval_state(info[keys.GOAL_STATE], open_floor(agent=(4, 5))) == (False, 3.0)


def test_goal_state_option_moves_the_goal():
    env = make_env()
    goal_state = open_floor(agent=(2, 5))
    obs, info = env.reset(seed=0, options={"goal_state": goal_state})
    np.testing.assert_array_equal(info[keys.GOAL_PROPRIO], [2, 5])
    np.testing.assert_array_equal(obs[keys.STATE][2:4], [2, 5])
    assert obs[keys.STATE][4 + 5 * N + 2] == 1.0  # the goal cell is intact


def test_bad_inputs_raise_typed_errors():
    from stable_worldmodel.errors import ConfigError

    env = make_env()
    env.reset(seed=0)
    with pytest.raises(ConfigError, match="action"):
        env.step(7)
    with pytest.raises(ConfigError, match="state of shape"):
        env.reset(seed=0, options={"state": np.zeros(5)})
    with pytest.raises(ConfigError, match="grid_size"):
        VoidRunEnv(grid_size=3)


def test_same_seed_same_episode_bit_for_bit():
    env_a, env_b = make_env(), make_env()
    opts = {"variation": ["all"]}
    a = rollout(env_a, 7, opts)
    b = rollout(env_b, 7, opts)
    for x, y in zip(a, b, strict=False):
        np.testing.assert_array_equal(x, y)
    c = rollout(env_b, 8, opts)
    assert not np.array_equal(a[1], c[1])


@pytest.mark.parametrize("name", VoidRunEnv().variation_space.names())
def test_every_factor_changes_the_episode(name):
    assert_factor_changes_episode(make_env(), name, rollout)


@pytest.mark.parametrize("size", [(64, 64), (48, 80), (224, 224)])
def test_render_size(size):
    assert_render_size(VoidRunEnv(render_size=size), size)


def test_render_shows_breaking_and_goal_image_is_cached():
    env = make_env()
    draws = count_draws(env)
    _, info = env.reset(seed=0, options={"state": open_floor(agent=(3, 3)), "variation_values": {"prob_break": 1.0}})
    before = env.render()
    _, _, _, _, info2 = env.step(RIGHT)
    after = env.render()
    assert not np.array_equal(before, after)
    np.testing.assert_array_equal(info2[keys.GOAL], info[keys.GOAL])
    assert len(draws) == 3  # the goal image once, then two renders


def test_goal_image_shows_agent_on_goal():
    env = make_env()  # prob_break = 0: the floor after the step is the floor at reset
    _, info = env.reset(
        seed=0, options={"state": open_floor(agent=(5, 6), goal=(6, 6)), "variation_values": {"prob_break": 0.0}}
    )
    env.step(RIGHT)
    np.testing.assert_array_equal(env.render(), info[keys.GOAL])


def run_expert(env, seed, options=None, max_steps=100):
    expert = VoidRunExpert()
    obs, _ = env.reset(seed=seed, options=options)
    for _ in range(max_steps):
        action = expert.get_action({keys.STATE: obs[keys.STATE][None, None]})
        assert action.shape == (1,) and action.dtype == np.int64
        obs, _, terminated, truncated, _ = env.step(action[0])
        if terminated or truncated:
            return bool(terminated)
    return False


def test_expert_reaches_the_goal():
    env = make_env()
    assert all(run_expert(env, seed) for seed in range(5))
    assert all(run_expert(env, seed, {"variation": ["all"]}) for seed in range(5))


def test_expert_is_batched_and_avoids_holes():
    # agent at (2, 2), goal at (2, 5), a wall of holes across x = 1..3 at y = 3
    walls = [(1, 3), (2, 3), (3, 3)]
    s = open_floor(agent=(2, 2), goal=(2, 5), holes=walls)
    s2 = open_floor(agent=(6, 1), goal=(2, 1))
    actions = VoidRunExpert().get_action({keys.STATE: np.stack([s, s2])[:, None]})
    assert actions.shape == (2,)
    assert actions[0] in (LEFT, RIGHT) and actions[1] == LEFT


@pytest.mark.parametrize("num_envs", [1, 4])
def test_expert_solves_episodes_in_world(num_envs):
    assert_expert_solves_in_world("swm/VoidRun-v0", num_envs, episodes=4, max_episode_steps=60)


def test_sampled_start_and_goal_never_coincide():
    env = make_env()
    for seed in range(60):
        obs, _ = env.reset(seed=seed, options={"variation": ["agent.start", "goal.position"]})
        assert not np.array_equal(obs[keys.STATE][:2], obs[keys.STATE][2:4])


def test_reset_from_dataset_rows_restores_state_goal_and_factors():
    env = make_env()
    obs, _ = env.reset(seed=5, options={"variation": ["all"]})
    start_row = {keys.STATE: obs[keys.STATE], "variation.agent.color": np.array([1, 2, 3], np.uint8)}
    goal_row = {keys.STATE: open_floor(agent=(4, 6))}
    options = env.reset_options_from_dataset(start_row, goal_row)
    obs2, info = env.reset(seed=0, options=options)
    np.testing.assert_array_equal(obs2[keys.STATE][:2], obs[keys.STATE][:2])
    np.testing.assert_array_equal(obs2[keys.STATE][4:], obs[keys.STATE][4:])
    np.testing.assert_array_equal(info[keys.GOAL_PROPRIO], [4, 6])
    np.testing.assert_array_equal(env.variation_space.value["agent"]["color"], [1, 2, 3])


def test_start_set_onto_the_goal_succeeds_at_the_first_step():
    env = make_env()
    env.reset(seed=0, options={"variation_values": {"agent.start": [3, 3], "goal.position": [3, 3]}})
    _, reward, terminated, truncated, _ = env.step(LEFT)
    assert (terminated, truncated) == (True, False)

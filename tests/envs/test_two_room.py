"""Tests of ``swm/TwoRoom-v2``: layout, walls and doors, success rule, state restore and the expert.

The contract shared with SimplePointMaze (check_env, determinism, factors, rendering, World) is in
``test_point_envs.py``.
"""

from __future__ import annotations

import numpy as np
import pytest

from stable_worldmodel import keys
from stable_worldmodel.envs.two_room.env import BORDER, SUCCESS_DISTANCE, TwoRoomEnv
from stable_worldmodel.envs.two_room.expert import TwoRoomExpert

pytest.importorskip("cv2")


def make_env() -> TwoRoomEnv:
    env = TwoRoomEnv()
    env.set_render_size((64, 64))
    return env


def place(env, agent, goal=(60.0, 60.0), **values):
    """Reset with the agent and goal at given positions (and factors set to ``values``)."""
    values = {"agent.position": agent, "goal.position": goal, **values}
    return env.reset(seed=0, options={"variation_values": values})


def test_state_layout_and_default_geometry():
    env = make_env()
    obs, info = env.reset(seed=0)
    state, goal_state = obs[keys.STATE], info[keys.GOAL_STATE]
    assert state.shape == (10,) and state.dtype == np.float32
    np.testing.assert_array_equal(state[2:], [32, 2, 32, 6, 0, 0, 0, 0])  # wall x, half thickness, one door
    np.testing.assert_array_equal(goal_state[2:], state[2:])
    assert len(env.variation_space.names()) == 16


def test_start_and_goal_in_opposite_rooms_per_seed():
    env = make_env()
    starts = []
    for seed in range(30):
        obs, info = env.reset(seed=seed)
        start, goal = obs[keys.STATE][:2], info[keys.GOAL_STATE][:2]
        assert np.sign(start[0] - 32) == -np.sign(goal[0] - 32)
        starts.append(start[0] < 32)
    assert 5 < sum(starts) < 25  # both rooms are used as start


def test_wall_blocks_off_the_door():
    env = make_env()
    obs, _ = place(env, agent=[20.0, 10.0])  # left room, far above the door (y in 26..38)
    for _ in range(20):
        obs, *_ = env.step([1.0, 0.0])
    np.testing.assert_allclose(obs[keys.STATE][:2], [32 - 2 - 2, 10.0])  # wall face minus the radius
    for _ in range(3):  # pushing diagonally slides along the wall, still on the left
        obs, *_ = env.step([1.0, 1.0])
    np.testing.assert_allclose(obs[keys.STATE][:2], [28.0, 16.0])


def test_door_lets_the_agent_through_only_where_it_fits():
    env = make_env()
    obs, _ = place(env, agent=[20.0, 32.0 + 6 - 2 - 0.1])  # the disk fits in the gap (26, 38)
    for _ in range(10):
        obs, *_ = env.step([1.0, 0.0])
    assert obs[keys.STATE][0] > 34 + 2
    obs, _ = place(env, agent=[20.0, 32.0 + 6 - 2 + 0.1])  # 0.1 too low: the wall's end stops it
    for _ in range(10):
        obs, *_ = env.step([1.0, 0.0])
    assert obs[keys.STATE][0] == pytest.approx(28.0)


def test_border_keeps_the_agent_inside():
    env = make_env()
    obs, _ = place(env, agent=[10.0, 10.0])
    for _ in range(10):
        obs, *_ = env.step([-1.0, -1.0])
    np.testing.assert_allclose(obs[keys.STATE][:2], [BORDER + 2, BORDER + 2])


def test_positions_inside_the_wall_are_pushed_out():
    env = make_env()
    obs, _ = place(env, agent=[31.0, 10.0])
    np.testing.assert_allclose(obs[keys.STATE][:2], [28.0, 10.0])


def test_success_rule_and_reward():
    env = make_env()
    place(env, agent=[50.0, 50.0], goal=[50.0 + SUCCESS_DISTANCE + 1.0, 50.0])
    _, reward, terminated, truncated, _ = env.step([0.0, 0.0])
    assert reward == pytest.approx(-(SUCCESS_DISTANCE + 1.0)) and not terminated and not truncated
    _, reward, terminated, _, _ = env.step([1.0, 0.0])  # moves 2: distance 3 < 4
    assert terminated and reward == pytest.approx(-(SUCCESS_DISTANCE - 1.0))
    assert env.eval_state(np.zeros(10), np.full(10, 2.0))[0]  # distance sqrt(8) < 4
    assert env.eval_state(np.zeros(10), np.array([4.0, 0.0]))[1] == 4.0


def test_state_option_restores_position_and_layout():
    env = make_env()
    obs, info = env.reset(seed=5, options={"variation": ["wall", "door"]})
    state, goal_state = obs[keys.STATE], info[keys.GOAL_STATE]
    assert not np.allclose(state[2:], [32, 2, 32, 6, 0, 0, 0, 0])  # not the default geometry
    fresh = make_env()
    obs2, info2 = fresh.reset(seed=99, options={"state": state, "goal_state": goal_state})
    np.testing.assert_allclose(obs2[keys.STATE], state, atol=1e-5)
    np.testing.assert_allclose(info2[keys.GOAL_STATE], goal_state, atol=1e-5)
    opts = fresh.reset_options_from_dataset({keys.STATE: state}, {keys.STATE: goal_state})
    np.testing.assert_allclose(fresh.reset(seed=1, options=opts)[0][keys.STATE], state, atol=1e-5)


@pytest.mark.parametrize("options", [None, {"variation": ["all"]}])
def test_expert_reaches_the_goal(options):
    env, expert = make_env(), TwoRoomExpert()
    for seed in range(4):
        obs, info = env.reset(seed=seed, options=options)
        for _ in range(100):
            action = expert.get_action(
                {keys.STATE: obs[keys.STATE][None, None], keys.GOAL_STATE: info[keys.GOAL_STATE][None, None]}
            )
            assert action.shape == (1, 2) and action.dtype == np.float32
            obs, _, terminated, _, info = env.step(action[0])
            if terminated:
                break
        assert terminated, f"seed {seed}"


def test_position_only_state_keeps_the_default_geometry():
    env = make_env()
    obs, _ = env.reset(seed=0, options={"state": np.array([12.0, 20.0], np.float32)})
    np.testing.assert_array_equal(obs[keys.STATE], [12, 20, 32, 2, 32, 6, 0, 0, 0, 0])

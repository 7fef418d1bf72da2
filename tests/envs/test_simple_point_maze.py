"""Tests of ``swm/SimplePointMaze-v1``: maze, dynamics, collisions, success rule, state restore and the expert.

The contract shared with TwoRoom (check_env, determinism, factors, rendering, World) is in
``test_point_envs.py``.
"""

from __future__ import annotations

import numpy as np
import pytest

from stable_worldmodel import keys
from stable_worldmodel.envs.planar import grow_boxes, is_free
from stable_worldmodel.envs.simple_point_maze.env import ACCEL, SUCCESS_DISTANCE, SimplePointMazeEnv
from stable_worldmodel.envs.simple_point_maze.expert import SimplePointMazeExpert
from stable_worldmodel.envs.simple_point_maze.layout import LAYOUTS, Maze

pytest.importorskip("cv2")


def make_env() -> SimplePointMazeEnv:
    env = SimplePointMazeEnv()
    env.set_render_size((64, 64))
    return env


def place(env, agent, goal=(5.5, 5.5), **values):
    values = {"agent.position": agent, "goal.position": goal, **values}
    return env.reset(seed=0, options={"variation_values": values})


def test_state_layout():
    env = make_env()
    obs, info = env.reset(seed=0)
    assert obs[keys.STATE].shape == (5,) and obs[keys.PROPRIO].shape == (4,)
    np.testing.assert_array_equal(obs[keys.STATE][2:], [0, 0, 0])  # at rest, layout 0
    np.testing.assert_array_equal(obs[keys.PROPRIO], obs[keys.STATE][:4])
    np.testing.assert_array_equal(info[keys.GOAL_STATE][2:], [0, 0, 0])
    np.testing.assert_array_equal(info[keys.GOAL_PROPRIO], info[keys.GOAL_STATE][:4])
    assert env.observation_space.contains(obs)


def test_layouts_are_square_walled_and_connected():
    for maze in LAYOUTS:
        assert maze.grid.shape == (7, 7) and maze.grid[0].all() and maze.grid[-1].all()
        assert maze.grid[:, 0].all() and maze.grid[:, -1].all()
        assert maze.distances.max() < 10**6  # every free cell reaches every other
    with pytest.raises(ValueError, match="square"):
        Maze(("###", "#.#"))


def test_bfs_path_is_shortest_and_4_connected():
    maze = LAYOUTS[1]  # the snake: from the top-left cell to the bottom-right one
    path = maze.path((1, 1), (5, 5))
    assert len(path) == 17 and path[0] == (1, 1) and path[-1] == (5, 5)
    assert all(abs(a[0] - b[0]) + abs(a[1] - b[1]) == 1 for a, b in zip(path, path[1:], strict=False))
    assert not any(maze.grid[c] for c in path)


def test_start_and_goal_are_distinct_free_cells_per_seed():
    env = make_env()
    for seed in range(20):
        obs, info = env.reset(seed=seed)
        start, goal = obs[keys.STATE][:2], info[keys.GOAL_STATE][:2]
        maze = LAYOUTS[0]
        assert not maze.is_wall(start) and not maze.is_wall(goal)
        d = maze.distances[maze.index[maze.cell(start)], maze.index[maze.cell(goal)]]
        assert d >= 3


def test_dynamics_friction_force_and_speed_cap():
    env = make_env()
    place(env, agent=[1.5, 1.5], **{"dynamics.friction": 0.5, "dynamics.max_speed": 0.35})
    obs, *_ = env.step([1.0, 0.0])
    np.testing.assert_allclose(obs[keys.STATE][:4], [1.5 + ACCEL, 1.5, ACCEL, 0.0], atol=1e-6)
    obs, *_ = env.step([0.0, 0.0])  # coasting: friction halves the speed
    np.testing.assert_allclose(obs[keys.STATE][2:4], [ACCEL / 2, 0.0], atol=1e-6)
    place(env, agent=[1.5, 5.5], **{"dynamics.friction": 0.05, "dynamics.max_speed": 0.15})
    for _ in range(12):
        obs, *_ = env.step([1.0, 1.0])
        assert np.linalg.norm(obs[keys.STATE][2:4]) <= 0.15 + 1e-6
    assert obs[keys.STATE][1] == pytest.approx(6.0 - 0.2) and obs[keys.STATE][3] == 0.0  # on the bottom wall
    assert 0.1 < obs[keys.STATE][2] < 0.15  # it slides along it


def test_walls_stop_the_agent_and_its_normal_velocity():
    env = make_env()
    obs, _ = place(env, agent=[1.5, 3.5])  # layout 0: column 1 is free, (3, 2) is a wall
    for _ in range(15):
        obs, *_ = env.step([1.0, 0.0])
    np.testing.assert_allclose(obs[keys.STATE][:4], [2.0 - 0.2, 3.5, 0.0, 0.0], atol=1e-6)


def test_random_actions_never_overlap_a_wall():
    env = make_env()
    rng = np.random.default_rng(0)
    for seed in range(3):
        obs, _ = env.reset(seed=seed, options={"variation": ["all"]})
        radius = float(env.variation_space["agent"]["radius"].value)
        maze = LAYOUTS[int(obs[keys.STATE][4])]
        boxes = grow_boxes(maze.wall_boxes, radius - 1e-6)
        lo, hi = np.zeros(2), np.full(2, 7.0)
        for _ in range(300):
            obs, *_ = env.step(rng.uniform(-1, 1, 2))
            assert is_free(obs[keys.STATE][:2], boxes, lo, hi)


def test_positions_in_walls_move_to_the_nearest_free_cell():
    env = make_env()
    obs, _ = place(env, agent=[2.4, 2.5])  # inside the wall cell (2, 2)
    np.testing.assert_allclose(obs[keys.STATE][:2], [1.5, 2.5])


def test_success_rule_and_reward():
    env = make_env()
    place(env, agent=[1.5, 5.5], goal=[1.5 + SUCCESS_DISTANCE + 0.05, 5.5])
    _, reward, terminated, _, _ = env.step([0.0, 0.0])
    assert not terminated and reward == pytest.approx(-(SUCCESS_DISTANCE + 0.05))
    _, reward, terminated, _, _ = env.step([1.0, 0.0])
    assert terminated and reward == pytest.approx(-(SUCCESS_DISTANCE + 0.05 - ACCEL))
    assert env.eval_state(np.zeros(5), np.array([0.3, 0.3, 0, 0, 0]))[0]
    assert not env.eval_state(np.zeros(5), np.array([0.5, 0.0, 0, 0, 0]))[0]


def test_state_option_restores_position_velocity_and_layout():
    env = make_env()
    obs, info = env.reset(seed=2, options={"variation_values": {"maze.layout": 1}})
    for _ in range(3):
        obs, *_ = env.step([1.0, 0.5])
    fresh = make_env()
    opts = fresh.reset_options_from_dataset({keys.STATE: obs[keys.STATE]}, {keys.STATE: info[keys.GOAL_STATE]})
    obs2, info2 = fresh.reset(seed=7, options=opts)
    np.testing.assert_allclose(obs2[keys.STATE], obs[keys.STATE], atol=1e-6)
    np.testing.assert_allclose(info2[keys.GOAL_STATE], info[keys.GOAL_STATE], atol=1e-6)
    np.testing.assert_allclose(fresh.step([0.0, 1.0])[0][keys.STATE], env.step([0.0, 1.0])[0][keys.STATE], atol=1e-5)


@pytest.mark.parametrize("layout", range(len(LAYOUTS)))
def test_expert_reaches_the_goal(layout):
    env, expert = make_env(), SimplePointMazeExpert()
    for seed in range(3):
        obs, info = env.reset(seed=seed, options={"variation": ["all"], "variation_values": {"maze.layout": layout}})
        for _ in range(150):
            action = expert.get_action(
                {keys.STATE: obs[keys.STATE][None, None], keys.GOAL_STATE: info[keys.GOAL_STATE][None, None]}
            )
            assert action.shape == (1, 2) and action.dtype == np.float32
            obs, _, terminated, _, info = env.step(action[0])
            if terminated:
                break
        assert terminated, f"layout {layout} seed {seed}"

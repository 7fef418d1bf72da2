"""OGBench mazes (swm/OGBMaze-v0): OGBench's maps, tasks and physics, seeded resets, factors,
the success rule, teleports, the ball maze, the point expert, errors. Tiny frames keep it short."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

from stable_worldmodel.envs.mujoco_render import setup_gl  # noqa: E402

setup_gl()  # before mujoco is imported (headless EGL)
pytest.importorskip("mujoco")
pytest.importorskip("ogbench")

from ogbench.locomaze.maze import make_maze_env  # noqa: E402

from stable_worldmodel import keys  # noqa: E402
from stable_worldmodel.envs.ogbench.maze_env import MazeEnv  # noqa: E402
from stable_worldmodel.envs.ogbench.maze_expert import OGBMazeExpert  # noqa: E402
from stable_worldmodel.envs.ogbench.maze_layout import BALL_TASKS, MAPS, TASKS, MazeLayout  # noqa: E402
from stable_worldmodel.errors import ConfigError, UnknownNameError  # noqa: E402

SIZE = 16
FACTORS = ["agent.color", "floor.color", "floor.pixel_encoding", "light.intensity", "wall.color"]


def small(**kwargs) -> MazeEnv:
    return MazeEnv(width=SIZE, height=SIZE, render_quality="low", **kwargs)


@pytest.fixture(scope="module")
def point():
    env = small()
    yield env
    env.close()


@pytest.fixture(scope="module")
def ant():
    env = small(loco_env_type="ant", maze_type="medium")
    yield env
    env.close()


# -- OGBench's maze ---------------------------------------------------------------------------
@pytest.mark.parametrize("maze_type", list(MAPS))
def test_maps_and_tasks_are_ogbenchs(maze_type):
    ogb = make_maze_env("point", "maze", maze_type=maze_type)
    layout = MazeLayout(maze_type)
    np.testing.assert_array_equal(layout.grid, ogb.maze_map.astype(bool))
    assert [(t["init_ij"], t["goal_ij"]) for t in ogb.task_infos] == list(TASKS[maze_type])
    for ij in layout.free_cells():
        np.testing.assert_allclose(layout.ij_to_xy(ij), ogb.ij_to_xy(ij))
        assert layout.xy_to_ij(layout.ij_to_xy(ij) + 1.9) == ogb.xy_to_ij(layout.ij_to_xy(ij) + 1.9)


def test_ball_tasks_are_ogbenchs():
    for maze_type, tasks in BALL_TASKS.items():
        ogb = make_maze_env("ant", "ball", maze_type=maze_type)
        assert [(t["agent_init_ij"], t["ball_init_ij"], t["goal_ij"]) for t in ogb.task_infos] == list(tasks)


@pytest.mark.parametrize("loco", ["point", "ant"])
def test_physics_match_ogbench(loco):
    """Same state, same actions: the same trajectory as OGBench's own maze env (and the same walls)."""
    env = small(loco_env_type=loco)
    ogb = make_maze_env(loco, "maze", maze_type="large")
    env.reset(seed=0)
    ogb.reset()
    assert env._model.ngeom == ogb.model.ngeom and env._model.nq == ogb.model.nq
    ogb.set_state(env._data.qpos.copy(), env._data.qvel.copy())
    rng = np.random.default_rng(0)
    for _ in range(10):
        a = rng.uniform(-1, 1, env.action_space.shape).astype(np.float32)
        ob, *_ = env.step(a)
        ob_ogb, *_ = ogb.step(a)
        np.testing.assert_allclose(ob, ob_ogb, atol=1e-9)
    env.close()


def test_registered_defaults_are_upstreams(point):
    assert point.env_name == "PointMaze" and point.maze_type == "large" and point.action_space.shape == (2,)
    assert point.observation_space.shape == (2,)
    assert sorted(point.variation_space.names()) == FACTORS
    v = point.variation_space.value
    np.testing.assert_allclose(v["agent"]["color"], [0.7, 0.5, 0.3])
    np.testing.assert_allclose(v["wall"]["color"], [1, 1, 1])
    np.testing.assert_allclose(v["light"]["intensity"], [1.0])
    assert int(v["floor"]["pixel_encoding"]) == 0


# -- resets -----------------------------------------------------------------------------------
def test_seed_fixes_task_start_and_goal_and_leaves_global_random_alone(point):
    state = np.random.get_state()
    _, a = point.reset(seed=5)
    task = point.cur_task_id
    _, b = point.reset(seed=5)
    assert np.random.get_state()[1].tolist() == state[1].tolist()
    np.testing.assert_array_equal(a[keys.STATE], b[keys.STATE])
    np.testing.assert_array_equal(a[keys.GOAL_STATE], b[keys.GOAL_STATE])
    assert point.cur_task_id == task
    seen = {point.reset(seed=s)[1][keys.GOAL_STATE][:2].round(3).tobytes() for s in range(6)}
    assert len(seen) == 6  # tasks and jitter differ across seeds


def test_task_start_goal_follow_ogbench_rules(point):
    L = point.maze_layout
    for task_id in range(1, 6):
        _, info = point.reset(seed=task_id, options={"task_id": task_id})
        start, goal = TASKS["large"][task_id - 1]
        assert np.abs(info[keys.STATE][:2] - L.ij_to_xy(start)).max() <= 1.0 + 1e-9
        assert np.abs(info[keys.GOAL_STATE][:2] - L.ij_to_xy(goal)).max() <= 1.0 + 1e-9
        assert info["success"] == 0.0 and info["env_name"] == "PointMaze"
        np.testing.assert_allclose(info["target"], info[keys.GOAL_STATE][:2])  # the point's observation is its xy
    _, info = point.reset(seed=0, options={"task_info": {"init_xy": (0.0, 0.0), "goal_xy": (8.0, 0.0)}})
    assert point.cur_task_id is None and np.abs(info[keys.STATE][:2]).max() <= 1.0


def test_state_and_goal_state_options(point):
    _, info = point.reset(seed=1)
    start, goal = info[keys.STATE], info[keys.GOAL_STATE]
    _, again = point.reset(seed=9, options={keys.STATE: start, keys.GOAL_STATE: goal})
    np.testing.assert_allclose(again[keys.STATE], start)
    np.testing.assert_allclose(again[keys.GOAL_STATE][:2], goal[:2])
    opts = point.reset_options_from_dataset(
        {"qpos": start[:2], "qvel": start[2:]}, {"qpos": goal[:2], "qvel": goal[2:]}
    )
    np.testing.assert_allclose(opts[keys.STATE], start)


# -- factors ----------------------------------------------------------------------------------
def test_every_factor_changes_the_picture_and_defaults_come_back():
    env = MazeEnv(maze_type="arena", width=64, height=64, render_quality="low")  # the point is ~2 px wide
    default = env.reset(seed=0)[1][keys.GOAL]
    changes = {
        "agent.color": [0.0, 1.0, 0.0],
        "wall.color": [1.0, 0.0, 0.0],
        "floor.color": [[1.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
        "floor.pixel_encoding": 1,
        "light.intensity": [0.2],
    }
    for name, value in changes.items():
        goal = env.reset(seed=0, options={"variation_values": {name: value}})[1][keys.GOAL]
        assert np.abs(goal.astype(int) - default).max() > 50, name
    np.testing.assert_array_equal(env.reset(seed=0)[1][keys.GOAL], default)  # texture re-uploaded
    env.close()


def test_factors_are_resampled_only_when_asked(point):
    point.reset(seed=0)
    default = point.variation_space.value
    point.reset(seed=0, options={"variation": ["all"]})
    drawn = point.variation_space.value
    assert not np.allclose(default["agent"]["color"], drawn["agent"]["color"])
    point.reset(seed=1)
    np.testing.assert_allclose(point.variation_space.value["agent"]["color"], default["agent"]["color"])


def test_pixel_observations_follow_the_render_size():
    env = MazeEnv(ob_type="pixels", maze_type="arena", width=24, height=20, render_quality="low")
    obs, info = env.reset(seed=0)
    assert obs.shape == (20, 24, 3) and env.observation_space.contains(obs) and info[keys.GOAL].shape == (20, 24, 3)
    env.set_render_size((12, 12))
    obs, info = env.reset(seed=0)
    assert obs.shape == (12, 12, 3) == env.observation_space.shape and info[keys.GOAL].shape == (12, 12, 3)
    assert "target" in info and info["target"].shape == (12, 12, 3)
    env.close()


# -- success ----------------------------------------------------------------------------------
def test_success_terminates_with_reward_one(point):
    _, info = point.reset(seed=2)
    goal = info[keys.GOAL_STATE]
    _, info = point.reset(seed=2, options={keys.STATE: goal})
    _, reward, terminated, truncated, info = point.step(np.zeros(2, np.float32))
    assert terminated and not truncated and reward == 1.0 and info["success"] == 1.0
    assert point.eval_state(goal, goal) == (True, 0.0)
    near, far = goal.copy(), goal.copy()
    near[0] += 0.9
    far[0] += 1.1
    assert point.eval_state(goal, near)[0] and not point.eval_state(goal, far)[0]


def test_single_task_mode_and_pre_timing():
    env = small(maze_type="medium", reward_task_id=0, success_timing="pre", terminate_at_goal=False)
    _, info = env.reset(seed=3)
    assert env.cur_task_id == 1  # OGBench's default task
    _, reward, terminated, _, _ = env.step(np.zeros(2, np.float32))
    assert reward == -1.0 and not terminated
    env.reset(seed=3, options={keys.STATE: info[keys.GOAL_STATE]})
    _, reward, terminated, _, _ = env.step(np.ones(2, np.float32))  # 'pre': judged before the move
    assert reward == 0.0 and not terminated
    env.close()


def test_ant_tolerance_and_clipped_actions(ant):
    _, info = ant.reset(seed=0)
    goal = info[keys.GOAL_STATE]
    moved = goal.copy()
    moved[0] += 0.6
    assert ant.eval_state(goal, moved) == (False, pytest.approx(0.6))  # 0.5 m for the ant
    assert info[keys.PROPRIO].shape == (29,) and ant.env_name == "AntMaze"
    obs, *_ = ant.step(np.full(8, 50.0, np.float32))
    assert np.all(np.isfinite(obs))


def test_teleport_moves_the_agent_to_an_outbound_pad():
    env = small(maze_type="teleport")
    L = env.maze_layout
    _, info = env.reset(seed=0)
    state = info[keys.STATE].copy()
    state[:2] = L.ij_to_xy((4, 6))
    env.reset(seed=0, options={keys.STATE: state})
    _, _, _, _, info = env.step(np.zeros(2, np.float32))
    outs = [L.ij_to_xy(ij) for ij in ((1, 7), (6, 1), (6, 10))]
    assert min(np.linalg.norm(info[keys.STATE][:2] - o) for o in outs) < 0.5
    env.close()


def test_ball_maze_succeeds_on_the_ball():
    env = small(loco_env_type="ant", maze_env_type="ball", maze_type="arena")
    _, info = env.reset(seed=0)
    assert env.env_name == "AntSoccer" and info[keys.PROPRIO].shape == (29,) and info[keys.STATE].shape == (42,)
    goal = info[keys.GOAL_STATE]
    moved_agent = goal.copy()
    moved_agent[:2] += 5.0  # the agent away, the ball on the goal: still a success
    assert env.eval_state(goal, moved_agent)[0]
    moved_ball = goal.copy()
    moved_ball[env._model.nq - 7] += 1.0
    assert not env.eval_state(goal, moved_ball)[0]
    env.close()


# -- expert -----------------------------------------------------------------------------------
def _run_expert(env, policy, seed: int, steps: int = 1000) -> tuple[bool, int]:
    _, info = env.reset(seed=seed)
    for t in range(steps):
        batch = {k: np.asarray(info[k])[None, None] for k in (keys.STATE, keys.GOAL_STATE)}
        _, _, terminated, _, info = env.step(policy.get_action(batch)[0])
        if terminated:
            return True, t + 1
    return False, steps


@pytest.mark.parametrize("maze_type,seeds", [("medium", range(3)), ("large", range(2)), ("teleport", range(2))])
def test_expert_reaches_the_goal(maze_type, seeds):
    env = small(maze_type=maze_type)
    policy = OGBMazeExpert()
    policy.set_env(env)  # the expert reads the maze from the env
    assert policy._env_layouts(1)[0].maze_type == maze_type
    for seed in seeds:
        ok, steps = _run_expert(env, policy, seed)
        assert ok and steps < 600, (maze_type, seed, steps)
    env.close()


def test_expert_refuses_the_ant(ant):
    _, info = ant.reset(seed=0)
    batch = {k: np.asarray(info[k])[None, None] for k in (keys.STATE, keys.GOAL_STATE)}
    with pytest.raises(ConfigError, match="pretrained"):
        OGBMazeExpert().get_action(batch)


# -- errors -----------------------------------------------------------------------------------
def test_bad_arguments_name_what_is_accepted(point):
    with pytest.raises(ConfigError, match="Did you mean 'point'"):
        MazeEnv(loco_env_type="pointt")
    with pytest.raises(ConfigError, match="maze_type in"):
        MazeEnv(maze_type="huge")
    with pytest.raises(ConfigError, match="'ant' for maze_env_type 'ball'"):
        MazeEnv(maze_env_type="ball", maze_type="arena")
    with pytest.raises(UnknownNameError, match="reset_noise_scale"):
        MazeEnv(loco_env_type="point", reset_noise_scale=0.1)
    with pytest.raises(ConfigError, match="camera_name"):
        MazeEnv(camera_name="nope")
    with pytest.raises(ConfigError, match=r"task_id' in \[1, 5\]"):
        point.reset(seed=0, options={"task_id": 6})
    with pytest.raises(ConfigError, match="4 finite numbers"):
        point.reset(seed=0, options={keys.STATE: np.zeros(3)})
    with pytest.raises(UnknownNameError, match="wall.color"):
        point.reset(seed=0, options={"variation": ["wall.colour"]})
    with pytest.raises(ConfigError, match="reset"):
        MazeEnv().step(np.zeros(2))


def test_missing_mujoco_extra_names_the_pip_command():
    code = (
        "import sys; sys.modules['ogbench'] = None\n"
        "import gymnasium as gym, stable_worldmodel\n"
        "try:\n    gym.make('swm/OGBMaze-v0')\nexcept Exception as e:\n    print(type(e).__name__, e)\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120).stdout
    assert "DependencyNotInstalled" in out and 'pip install "stable-worldmodel[mujoco]"' in out

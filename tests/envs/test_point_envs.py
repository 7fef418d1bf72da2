"""The env contract shared by ``swm/TwoRoom-v2`` and ``swm/SimplePointMaze-v1`` (both built on ``PointEnv``).

Env-specific rules (walls, doors, maze, dynamics, success distances) are tested in
``test_two_room.py`` and ``test_simple_point_maze.py``.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest
from env_checks import run_actions
from gymnasium.utils.env_checker import check_env

import stable_worldmodel as swm
from stable_worldmodel import keys

pytest.importorskip("cv2")

TWO_ROOM, MAZE = "swm/TwoRoom-v2", "swm/SimplePointMaze-v1"
# Per env: fixed start/goal, an action sequence, and one non-default value per factor
# (the test below fails when a factor is added without one).
CASES = {
    TWO_ROOM: {
        "base": {"agent.position": [10.0, 30.0], "goal.position": [54.0, 30.0]},
        "actions": [[1.0, 0.3]] * 6 + [[-0.5, 1.0]] * 4,
        "alternatives": {
            "agent.color": [0, 0, 255],
            "agent.radius": 2.9,
            "agent.position": [20.0, 40.0],
            "agent.speed": 2.9,
            "goal.color": [255, 0, 255],
            "goal.radius": 2.1,
            "goal.position": [50.0, 10.0],
            "wall.color": [200, 120, 0],
            "wall.position": 36.0,
            "wall.thickness": 6.0,
            "border.color": [0, 90, 200],
            "door.number": 3,
            "door.size": 19.0,
            "door.position": [20.0, 14.0, 48.0],
            "door.color": [255, 255, 0],
            "background.color": [120, 180, 120],
        },
    },
    MAZE: {
        "base": {"agent.position": [1.5, 1.5], "goal.position": [5.5, 5.5]},
        "actions": [[1.0, 0.0]] * 8 + [[0.0, 1.0]] * 8,
        "alternatives": {
            "maze.layout": 2,
            "wall.color": [200, 120, 0],
            "floor.color": [120, 180, 120],
            "agent.color": [0, 0, 255],
            "agent.radius": 0.3,
            "agent.position": [3.5, 1.5],
            "goal.color": [255, 0, 255],
            "goal.radius": 0.4,
            "goal.position": [1.5, 5.5],
            "dynamics.friction": 0.5,
            "dynamics.max_speed": 0.15,
        },
    },
}
FACTORS = [(env_id, name) for env_id, case in CASES.items() for name in sorted(case["alternatives"])]


def make(env_id: str, size=(64, 64), **kwargs):
    env = gym.make(env_id, **kwargs).unwrapped
    env.set_render_size(size)
    return env


def rollout(env, env_id: str, seed: int = 0, options=None):
    """Frames (T+1, H, W, 3) and states (T+1, D) of the case's action sequence."""
    actions = [np.asarray(a, np.float32) for a in CASES[env_id]["actions"]]
    return run_actions(env, seed, actions, options)[:2]


@pytest.mark.parametrize("env_id", CASES)
def test_check_env_passes(env_id):
    env = gym.make(env_id, render_size=(64, 64)).unwrapped
    check_env(env, skip_render_check=False)


@pytest.mark.parametrize("env_id", CASES)
def test_observations_and_goal_infos(env_id):
    env = make(env_id)
    obs, info = env.reset(seed=0)
    assert env.observation_space.contains(obs)
    dim = env.proprio_dim
    np.testing.assert_array_equal(obs[keys.PROPRIO], obs[keys.STATE][:dim])
    np.testing.assert_array_equal(info[keys.GOAL_PROPRIO], info[keys.GOAL_STATE][:dim])
    assert env.observation_space[keys.STATE].contains(info[keys.GOAL_STATE])
    np.testing.assert_array_equal(env.variation_space["agent"]["position"].value, obs[keys.STATE][:2])
    np.testing.assert_array_equal(env.variation_space["goal"]["position"].value, info[keys.GOAL_STATE][:2])


@pytest.mark.parametrize("env_id", CASES)
@pytest.mark.parametrize("options", [None, {"variation": ["all"]}])
def test_same_seed_same_episode_and_different_seeds_differ(env_id, options):
    env_a, env_b = make(env_id), make(env_id)
    frames_a, states_a = rollout(env_a, env_id, seed=3, options=options)
    frames_b, states_b = rollout(env_b, env_id, seed=3, options=options)
    np.testing.assert_array_equal(frames_a, frames_b)
    np.testing.assert_array_equal(states_a, states_b)
    frames_c, _ = rollout(env_b, env_id, seed=4, options=options)
    assert not np.array_equal(frames_a, frames_c)


@pytest.mark.parametrize("env_id", CASES)
def test_every_factor_has_a_test_value(env_id):
    assert set(CASES[env_id]["alternatives"]) == set(make(env_id).variation_space.names())


@pytest.mark.parametrize("env_id,name", FACTORS)
def test_every_factor_changes_the_episode(env_id, name):
    # TwoRoom draws the goal disk only with render_target=True (its default hides it)
    shows_goal = {"render_target": True} if env_id == "swm/TwoRoom-v2" and name.startswith("goal.") else {}
    env, case = make(env_id, **shows_goal), CASES[env_id]
    frames, states = rollout(env, env_id, options={"variation_values": case["base"]})
    values = {**case["base"], name: case["alternatives"][name]}
    frames2, states2 = rollout(env, env_id, options={"variation_values": values})
    assert not (np.array_equal(frames, frames2) and np.array_equal(states, states2))
    value = env.variation_space.value
    for part in name.split("."):
        value = value[part]
    np.testing.assert_allclose(value, case["alternatives"][name], rtol=1e-6)  # set as asked (positions are legal)


@pytest.mark.parametrize("env_id", CASES)
def test_variation_all_resamples_and_unknown_names_fail(env_id):
    env = make(env_id)
    env.reset(seed=0)
    default = env.render()
    env.reset(seed=0, options={"variation": ["all"]})
    assert not np.array_equal(default, env.render())
    with pytest.raises(swm.errors.UnknownNameError, match="Did you mean"):
        env.reset(seed=0, options={"variation": ["agent.colour"]})


@pytest.mark.parametrize("env_id", CASES)
def test_render_size_and_cached_goal_image(env_id):
    env = gym.make(env_id).unwrapped
    _, info = env.reset(seed=0)
    assert env.render().shape == (224, 224, 3) and info[keys.GOAL].shape == (224, 224, 3)
    env.set_render_size((64, 48))
    _, info = env.reset(seed=0)
    frame = env.render()
    assert frame.shape == (64, 48, 3) and frame.dtype == np.uint8 and info[keys.GOAL].shape == (64, 48, 3)
    info2 = env.step(np.zeros(2, np.float32))[-1]
    np.testing.assert_array_equal(info[keys.GOAL], info2[keys.GOAL])
    assert info[keys.GOAL] is not info2[keys.GOAL]
    gx, gy = info[keys.GOAL_STATE][:2] / env.world_size * [48, 64]  # the agent is drawn at the goal
    np.testing.assert_array_equal(info[keys.GOAL][int(gy), int(gx)], env.variation_space["agent"]["color"].value)


@pytest.mark.parametrize("env_id", CASES)
def test_expert_noise_is_seeded_and_bounded(env_id):
    env = make(env_id)
    obs, info = env.reset(seed=0)
    infos = {
        keys.STATE: np.tile(obs[keys.STATE], (3, 1, 1)),
        keys.GOAL_STATE: np.tile(info[keys.GOAL_STATE], (3, 1, 1)),
    }
    a = swm.envs.expert_policy(env_id, noise=0.5, seed=1).get_action(infos)
    np.testing.assert_array_equal(a, swm.envs.expert_policy(env_id, noise=0.5, seed=1).get_action(infos))
    clean = swm.envs.expert_policy(env_id).get_action(infos)
    assert a.shape == clean.shape == (3, 2) and a.dtype == np.float32
    assert not np.array_equal(a, clean) and np.abs(a).max() <= 1
    np.testing.assert_array_equal(clean[0], clean[1])


@pytest.mark.parametrize("env_id", CASES)
@pytest.mark.parametrize("num_envs,mode", [(1, "sync"), (8, "sync"), pytest.param(8, "auto", marks=pytest.mark.slow)])
def test_world_evaluates_the_expert(env_id, num_envs, mode):
    with swm.World(
        env_id, num_envs=num_envs, image_shape=(64, 64), max_episode_steps=150, verbose=0, vectorization_mode=mode
    ) as world:
        world.set_policy(swm.envs.expert_policy(env_id))
        assert world.evaluate(episodes=8, seed=0)["success_rate"] == 100.0
        assert world.infos[keys.PIXELS].shape == (num_envs, 1, 64, 64, 3)
        assert world.infos[keys.GOAL].shape == (num_envs, 1, 64, 64, 3)


@pytest.mark.parametrize(
    "module,names",
    [("two_room", "TwoRoomEnv TwoRoomExpert"), ("simple_point_maze", "SimplePointMazeEnv SimplePointMazeExpert")],
)
def test_package_exports_lazily_without_cv2(module, names):
    code = (
        f"import sys, stable_worldmodel.envs.{module} as m; assert 'cv2' not in sys.modules; "
        f"assert [getattr(m, n).__name__ for n in {names.split()!r}] == {names.split()!r}"
    )
    subprocess.run([sys.executable, "-c", code], check=True, cwd=Path(__file__).parents[2])


def test_two_room_hides_the_goal_and_its_goal_image_is_the_frame_at_the_goal():
    env = make("swm/TwoRoom-v2")
    obs, info = env.reset(seed=3)
    shown = make("swm/TwoRoom-v2", render_target=True)
    shown.reset(seed=3)
    assert not np.array_equal(env.render(), shown.render())  # the goal disk is drawn only when asked
    at_goal = make("swm/TwoRoom-v2")
    at_goal.reset(seed=3, options={"state": info[keys.GOAL_STATE]})
    np.testing.assert_array_equal(at_goal.render(), info[keys.GOAL])

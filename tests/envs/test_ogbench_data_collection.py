"""OGBench Cube / Scene in ``mode="data_collection"`` (upstream 0.1.1's collection scripts): one
subtask at a time, OGBench's target infos, subtask success, ``set_new_target`` and the expert
chaining subtasks. Tiny frames, ``render_quality="low"``."""

from __future__ import annotations

import numpy as np
import pytest

from stable_worldmodel.envs.mujoco_render import setup_gl

setup_gl()  # before mujoco is imported (headless EGL)
pytest.importorskip("mujoco")
pytest.importorskip("ogbench")

import stable_worldmodel as swm  # noqa: E402
from stable_worldmodel import keys  # noqa: E402
from stable_worldmodel.envs.ogbench.cube_env import CubeEnv  # noqa: E402
from stable_worldmodel.envs.ogbench.expert_policy import ExpertPolicy  # noqa: E402
from stable_worldmodel.envs.ogbench.scene_env import SceneEnv  # noqa: E402
from stable_worldmodel.errors import ConfigError  # noqa: E402

SIZE = (16, 16)
DC = {"mode": "data_collection", "render_quality": "low", "terminate_at_goal": False, "visualize_info": False}
# upstream 0.1.1's data-collection info entries (observed; "/" written "." here) beyond task mode's
TARGET_KEYS = ("privileged.target_task", "privileged.target_block", "privileged.target_block_pos")
SCENE_TARGET_KEYS = (
    "privileged.target_button",
    "privileged.target_button_state",
    "privileged.target_button_top_pos",
    "privileged.target_drawer_pos",
    "privileged.target_drawer_handle_pos",
    "privileged.target_window_pos",
    "privileged.target_window_handle_pos",
)
ZERO = np.zeros(5, np.float32)


def _env(cls, **kwargs):
    env = cls(**DC, **kwargs)
    env.set_render_size(SIZE)
    return env


@pytest.fixture(scope="module")
def double():
    env = _env(CubeEnv, env_type="double")
    yield env
    env.close()


@pytest.fixture(scope="module")
def scene():
    env = _env(SceneEnv)
    yield env
    env.close()


def _cube_pos(env, info, i):
    return np.asarray(info[f"privileged.block_{i}_pos"])


def test_ogb_data_collection_infos_as_upstream(double):
    obs, info = double.reset(seed=0)
    for key in TARGET_KEYS + ("privileged.target_block_yaw",):
        assert key in info, key
    assert info["privileged.target_task"] == "cube" and info["success"] is False
    np.testing.assert_array_equal(info["target"], np.zeros_like(obs))  # upstream: no goal observation
    target = int(info["privileged.target_block"])
    other = 1 - target
    np.testing.assert_allclose(info["privileged.target_block_pos"], info[f"privileged.target_block_{target}_pos"])
    np.testing.assert_allclose(info[f"privileged.target_block_{other}_pos"], [0.0, 0.0, -0.3])  # out of play
    assert info[keys.GOAL].shape == (*SIZE, 3)
    _, reward, terminated, truncated, step_info = double.step(ZERO)
    assert set(step_info) == set(info) and (reward, terminated, truncated) == (0.0, False, False)


def test_ogb_data_collection_is_reproducible_and_draws_targets_from_the_seed(double):
    runs = []
    for _ in range(2):
        _, info = double.reset(seed=3)
        targets = [np.asarray(info["privileged.target_block_pos"]).copy()]
        for _ in range(3):
            _, new = double.set_new_target(p_stack=0.5)
            targets.append(np.asarray(new["privileged.target_block_pos"]).copy())
        runs.append((info[keys.GOAL_STATE], np.stack(targets)))
    np.testing.assert_array_equal(runs[0][0], runs[1][0])
    np.testing.assert_array_equal(runs[0][1], runs[1][1])
    assert len({tuple(np.round(t, 6)) for t in runs[0][1]}) > 1  # each new target is a new draw
    _, other = double.reset(seed=4)
    assert not np.array_equal(other[keys.GOAL_STATE], runs[0][0])


def test_ogb_data_collection_success_is_the_current_subtask(double):
    _, info = double.reset(seed=1)
    nq = double.unwrapped._model.nq
    goal = np.asarray(info[keys.GOAL_STATE])
    # the goal state is the scene with the subtask done: only the target cube moved, onto its target
    target = int(info["privileged.target_block"])
    np.testing.assert_allclose(goal[:nq][double._cube_qpos[target] :][:3], info["privileged.target_block_pos"])
    double.set_state(goal[:nq], goal[nq:])
    _, reward, _, _, step = double.step(ZERO)
    assert step["success"] and reward == 1.0
    _, new = double.set_new_target(p_stack=0.0)  # never stacked: a fresh goal position
    assert not np.allclose(new["privileged.target_block_pos"], info["privileged.target_block_pos"])
    _, reward, _, _, step = double.step(ZERO)
    assert not step["success"] and reward == 0.0


def test_ogb_data_collection_stacking_target_rests_on_the_other_cube(double):
    for seed in range(20):  # a seed whose first target stacks (p_stack 0.5 at reset, as OGBench)
        _, info = double.reset(seed=seed)
        target = int(info["privileged.target_block"])
        below = _cube_pos(double, info, 1 - target)
        pos = np.asarray(info["privileged.target_block_pos"])
        if np.allclose(pos[:2], below[:2]):
            assert pos[2] == pytest.approx(below[2] + 0.04)  # two default half-sizes
            return
    pytest.fail("no stacking target in 20 seeds")


def test_ogb_data_collection_scene_subtasks(scene):
    _, info = scene.reset(seed=2)
    for key in TARGET_KEYS + SCENE_TARGET_KEYS:
        assert key in info, key
    seen = set()
    for _ in range(12):
        _, info = scene.set_new_target()
        task = str(info["privileged.target_task"])
        seen.add(task)
        goal = np.asarray(info[keys.GOAL_STATE])
        buttons = [int(info[f"privileged.button_{k}_state"]) for k in range(2)]
        if task == "button":
            k = int(info["privileged.target_button"])
            assert int(info["privileged.target_button_state"]) == 1 - buttons[k]
            assert int(goal[-2 + k]) == 1 - buttons[k]  # the goal state has the button toggled
        elif task in ("drawer", "window"):
            now, want = float(info[f"privileged.{task}_pos"][0]), float(info[f"privileged.target_{task}_pos"][0])
            assert want in ((0.0, -0.16) if task == "drawer" else (0.0, 0.2))
            assert abs(want - now) > 0.04  # open a closed one, close an open one
    assert seen <= {"cube", "button", "drawer", "window"} and len(seen) >= 3


def test_ogb_data_collection_errors(double):
    with pytest.raises(ConfigError, match="data_collection"):
        CubeEnv(mode="datacollection", render_quality="low")
    with pytest.raises(ConfigError, match="goal_state"):
        double.reset(seed=0, options={keys.GOAL_STATE: np.zeros(54)})
    double.reset(seed=0)
    with pytest.raises(ConfigError, match="p_stack"):
        double.set_new_target(p_stack=1.5)


def test_ogb_data_collection_expert_chains_subtasks_in_a_world():
    world = swm.World(
        "swm/OGBCube-v0", num_envs=1, image_shape=SIZE, verbose=0, vectorization_mode="sync", env_type="single", **DC
    )
    world.set_policy(ExpertPolicy(action_noise=0.0, seed=0))
    world.reset(seed=0)
    targets, successes = set(), 0
    for _ in range(140):
        world.step()
        targets.add(tuple(np.round(world.infos["privileged.target_block_pos"][0, -1], 4)))
        successes += int(np.asarray(world.infos["success"])[0, -1])
    world.close()
    assert successes > 0 and len(targets) >= 2  # the first subtask solved, then a new one asked for

"""The Fetch family (``swm/Fetch<Task>[Dense|Dict]-v3``, extra ``robotics``): Gymnasium-Robotics'
rules, factors, success rule, goal scene, state restore, shared renderers, experts, missing extra."""

from __future__ import annotations

import importlib.util
import sys

import gymnasium as gym
import numpy as np
import pytest
from env_checks import assert_factor_changes_episode

from stable_worldmodel import keys
from stable_worldmodel._optional import is_available

pytestmark = pytest.mark.skipif(
    not (is_available("gymnasium_robotics") and is_available("mujoco")), reason="extra 'robotics' not installed"
)

FAST = {"render_quality": "low", "resolution": 16}


def make(task: str = "Push", **kwargs):
    from stable_worldmodel.envs.fetch.env import FetchEnv

    return FetchEnv(f"Fetch{task}-v4", **{**FAST, **kwargs})


def actions(n: int) -> np.ndarray:
    return np.random.default_rng(0).uniform(-1, 1, (30, 4)).astype(np.float32)[:n]


# Gymnasium-Robotics 1.4.2's Fetch<Task>-v4 (its joint-type check patched so that it builds under mujoco
# 3.17), reset with the seed, then the actions above: flat observation [:6] at steps 0 and 5, desired goal
GYMNASIUM_ROBOTICS = {
    ("Reach", 0): (
        [1.341814, 0.749101, 0.534723, 0.000384, 0.000011, 0.000007],
        [1.419665, 0.761371, 0.534708, 0.0, 0.0, 0.016803],
        [1.382902, 0.680037, 0.397014],
    ),
    ("Push", 0): (
        [1.362703, 0.749101, 0.416013, 1.225143, 0.604059, 0.424892],
        [1.431933, 0.768116, 0.449738, 1.225143, 0.604059, 0.424892],
        [1.456832, 0.872927, 0.424892],
    ),
    ("PickAndPlace", 1): (
        [1.341914, 0.749101, 0.534723, 1.34546, 0.88424, 0.424892],
        [1.417654, 0.760895, 0.535014, 1.34546, 0.88424, 0.424892],
        [1.235161, 0.883696, 0.797358],
    ),
    ("Slide", 0): (
        [1.012831, 0.749155, 0.415503, 0.921197, 0.65246, 0.419999],
        [1.08176, 0.767947, 0.449793, 0.921197, 0.65246, 0.419999],
        [1.600965, 0.996807, 0.419999],
    ),
}


@pytest.mark.parametrize(("task", "seed"), list(GYMNASIUM_ROBOTICS))
def test_episode_is_gymnasium_robotics_episode(task, seed):
    env = make(task)
    start, after, goal = GYMNASIUM_ROBOTICS[(task, seed)]
    obs, info = env.reset(seed=seed)
    np.testing.assert_allclose(obs[:6], start, atol=2e-6)
    np.testing.assert_allclose(obs[-3:], goal, atol=2e-6)
    for a in actions(5):
        obs, reward, terminated, truncated, info = env.step(a)
    np.testing.assert_allclose(obs[:6], after, atol=2e-6)
    assert not terminated and not truncated and reward in (-1.0, 0.0)
    assert obs.shape == (13 if task == "Reach" else 28,) and obs.dtype == np.float32
    np.testing.assert_array_equal(info[keys.STATE], obs)
    assert info["env_name"] == f"Fetch{task}-v4"


def test_ids_reward_types_and_dict_observation():
    import stable_worldmodel  # noqa: F401 - registers the ids

    dense = gym.make("swm/FetchReachDense-v3", disable_env_checker=True, **FAST)
    assert dense.spec.max_episode_steps == 50
    dense.reset(seed=0)
    _, reward, *_ = dense.step(np.zeros(4, np.float32))
    env = dense.unwrapped
    dist = np.linalg.norm(env._sim.observation()[1] - env._goal)
    assert reward == pytest.approx(-dist) and reward < -0.05

    d = gym.make("swm/FetchPushDict-v3", disable_env_checker=True, **FAST).unwrapped
    obs, info = d.reset(seed=0)
    assert set(obs) == {"observation", "achieved_goal", "desired_goal", keys.STATE} and keys.STATE not in info
    assert obs["observation"].shape == (25,) and obs["achieved_goal"].dtype == np.float64
    np.testing.assert_allclose(obs[keys.STATE], np.concatenate([obs["observation"], obs["desired_goal"]]), atol=1e-6)
    np.testing.assert_array_equal(obs["achieved_goal"], obs["observation"][3:6])
    assert d.observation_space.contains(obs)


def test_success_rule_and_eval_state():
    env = make("Reach")
    _, info = env.reset(seed=0)
    state, goal = info[keys.STATE].astype(np.float64), info[keys.STATE][-3:].astype(np.float64)
    assert env.eval_state(info[keys.GOAL_STATE], info[keys.GOAL_STATE])[0]
    for offset, success in ((0.049, True), (0.051, False)):
        moved = state.copy()
        moved[:3] = goal + [offset, 0.0, 0.0]
        ok, dist = env.eval_state(info[keys.GOAL_STATE], moved)
        assert ok is success and dist == pytest.approx(offset)
        assert env.eval_state(goal, moved)[0] is success  # upstream's goal_state: the 3-number desired goal
    assert info["is_success"] == float(env.eval_state(info[keys.GOAL_STATE], state)[0])
    with pytest.raises(ValueError, match="13 finite numbers"):
        env.eval_state(goal, state[:5])


@pytest.mark.parametrize("task", ["Reach", "Push", "PickAndPlace"])
def test_goal_scene_reaches_the_goal(task):
    env = make(task, resolution=64)
    space = env.variation_space["goal"]["start_position"]
    target = np.clip([1.3, 0.8, 0.62], space.low, space.high)  # Push: a goal on the table
    _, info = env.reset(seed=3, options={"variation_values": {"goal.start_position": target}})
    goal = info[keys.STATE][-3:]
    np.testing.assert_allclose(goal, target, atol=1e-6)
    achieved = slice(0, 3) if task == "Reach" else slice(3, 6)
    np.testing.assert_allclose(info[keys.GOAL_STATE][achieved], goal, atol=2e-3)
    np.testing.assert_array_equal(info[keys.GOAL_STATE][-3:], goal)
    np.testing.assert_array_equal(info[keys.GOAL_PROPRIO], info[keys.GOAL_STATE][:-3])
    if task != "Push":  # Reach, and the block held in the air: the gripper is on the goal
        np.testing.assert_allclose(info[keys.GOAL_PROPRIO][:3], target, atol=2e-3)
    assert env.eval_state(info[keys.GOAL_STATE], info[keys.GOAL_STATE])[0]
    assert info[keys.GOAL].shape == (64, 64, 3) and not np.array_equal(info[keys.GOAL], env.render())


def test_start_from_a_recorded_state():
    env = make("PickAndPlace")
    env.reset(seed=1)
    for a in actions(8):
        _, _, _, _, info = env.step(a)
    recorded, goal_row = info[keys.STATE].copy(), info[keys.STATE].copy()
    options = env.reset_options_from_dataset({keys.STATE: recorded}, {keys.STATE: goal_row})
    obs, info = env.reset(seed=5, options=options)
    np.testing.assert_allclose(obs[:3], recorded[:3], atol=2e-3)  # gripper
    np.testing.assert_allclose(obs[3:6], recorded[3:6], atol=1e-6)  # object
    np.testing.assert_allclose(obs[9:11], recorded[9:11], atol=1e-6)  # fingers
    np.testing.assert_allclose(obs[-3:], recorded[3:6], atol=1e-6)  # the goal row's achieved goal
    with pytest.raises(ValueError, match="28 finite numbers"):
        env.reset(options={keys.STATE: recorded[:10]})


LOOKS = ["table.color", "object.color", "background.color", "light.intensity", "camera.angle_delta"]
PHYSICS = ["object.size", "object.mass", "object.friction"]
POSITIONS = ["agent.start_position", "goal.start_position", "block.start_position", "block.angle"]


def _frames(env, seed, options):
    env.set_render_size((64, 64))  # the block is ~1.5 px wide at 64 px (Gymnasium-Robotics' far view)
    env.reset(seed=seed, options={keys.VARIATION: [], **(options or {})})
    return [env.render()]


def _push_states(env, seed, options):
    from stable_worldmodel.envs.fetch.expert import push

    _, info = env.reset(seed=seed, options={keys.VARIATION: [], **(options or {})})
    states = [info[keys.STATE]]
    for _ in range(14):
        _, _, _, _, info = env.step(push(info[keys.STATE][None].astype(np.float64))[0])
        states.append(info[keys.STATE])
    return [np.stack(states), info[keys.GOAL]]


def test_factors_change_the_episode():
    env = make("Push")
    assert len(env.variation_space.names()) == 12 and len(make("Reach").variation_space.names()) == 6
    for name in LOOKS:
        assert_factor_changes_episode(env, name, _frames, tries=3)
    for name in PHYSICS + POSITIONS:
        assert_factor_changes_episode(env, name, _push_states, tries=3)


def test_default_resets_resample_the_looks_only():
    env = make("Push")
    _, a = env.reset(seed=0)
    _, b = env.reset(seed=0, options={keys.VARIATION: []})
    np.testing.assert_array_equal(a[keys.STATE], b[keys.STATE])  # same episode, other looks
    assert not np.array_equal(a[keys.GOAL], b[keys.GOAL])
    value = env.variation_space.value
    assert value["object"]["mass"][0] == 2.0 and value["block"]["angle"][0] == 0.0


def test_size_mass_friction_reach_the_model():
    env = make("Slide")
    env.reset(seed=0, options={keys.VARIATION_VALUES: {"object.size": [0.03], "object.mass": [3.0]}})
    m, g = env._sim.model, env._sim.object_geom
    np.testing.assert_allclose(m.geom_size[g, :2], [0.03, 0.024])
    assert m.body_mass[m.geom_bodyid[g]] == 3.0 and m.geom_friction[g, 0] == pytest.approx(0.1)
    obs, _ = env.reset(seed=0, options={keys.VARIATION_VALUES: {"object.friction": [0.2]}})
    assert m.geom_friction[g, 0] == 0.2 and m.geom_size[g, 0] == 0.025
    assert obs[5] == pytest.approx(env._sim.height_offset)  # back to the default size: resting height too


def test_interleaved_envs_keep_their_own_background():
    red, blue = make("Reach"), make("Reach")
    red.reset(seed=0, options={keys.VARIATION_VALUES: {"background.color": [1.0, 0.0, 0.0]}})
    blue.reset(seed=0, options={keys.VARIATION_VALUES: {"background.color": [0.0, 0.0, 1.0]}})
    for env, channel in ((red, 0), (blue, 2), (red, 0)):
        sky = env.render()[0, 0]  # top-left corner: sky
        assert sky[channel] > 200 and sky.sum() - sky[channel] < 60, sky
    red.close()
    assert blue.render().shape == (16, 16, 3)  # the shared renderer outlives one of its envs


def test_long_runs_get_a_renderer_of_their_own(monkeypatch):
    from stable_worldmodel.envs.fetch import env as fetch_env

    monkeypatch.setattr(fetch_env, "SHARED_FRAMES", 2)
    env = make("Reach")
    env.reset(seed=0)  # frame 1: the goal image
    shared = env.render()  # frame 2
    own = env.render()  # frame 3: its own renderer
    np.testing.assert_array_equal(shared, own)
    mine = [k for k in fetch_env._RENDERERS if len(k) > 5 and k[-1] == id(env)]
    assert len(mine) == 1
    env.close()
    assert mine[0] not in fetch_env._RENDERERS


def test_render_size_and_bad_arguments():
    from stable_worldmodel.errors import ConfigError, UnknownNameError

    env = make("Reach")
    env.set_render_size((12, 20))
    _, info = env.reset(seed=0)
    assert env.render().shape == (12, 20, 3) and info[keys.GOAL].shape == (12, 20, 3)
    with pytest.raises(ConfigError, match=r"requires render_size \(H, W\) of positive ints"):
        env.set_render_size((0, 8))
    with pytest.raises(UnknownNameError, match="FetchReach-v4"):
        make("Raech")
    with pytest.raises(ConfigError, match="render_quality"):
        make("Reach", render_quality="ultra")
    with pytest.raises(ConfigError, match="4 finite action values"):
        env.step(np.zeros(3))
    with pytest.raises(KeyError, match="block.angle"):
        make("Push").reset(options={keys.VARIATION: ["block.angel"]})


@pytest.mark.parametrize("task", ["Reach", "Push", "PickAndPlace"])
def test_expert_succeeds(task):
    from stable_worldmodel.envs.fetch.expert import FetchExpert

    expert = FetchExpert(f"swm/Fetch{task}-v3")
    env = make(task)
    for seed in (0, 1):
        _, info = env.reset(seed=seed)
        for _ in range(50):
            action = expert.get_action({keys.STATE: info[keys.STATE][None, None]})[0]
            _, _, _, _, info = env.step(action)
        assert info["is_success"] == 1.0, (task, seed)


def test_missing_extra_names_the_pip_command(monkeypatch):
    from stable_worldmodel import _optional
    from stable_worldmodel.envs.fetch import env as fetch_env
    from stable_worldmodel.errors import DependencyNotInstalled

    find_spec = importlib.util.find_spec
    monkeypatch.setattr(
        importlib.util, "find_spec", lambda name, *a: None if name == "gymnasium_robotics" else find_spec(name, *a)
    )
    assert _optional.missing_extra(("continuous", "robotics")) == "robotics"
    with pytest.raises(DependencyNotInstalled, match=r'pip install "stable-worldmodel\[robotics\]"'):
        fetch_env.setup_robotics()
    monkeypatch.delitem(sys.modules, "stable_worldmodel.envs.fetch.env")  # made again: imported again
    with pytest.raises(DependencyNotInstalled, match="gymnasium_robotics") as caught:
        gym.make("swm/FetchPush-v3", disable_env_checker=True)
    assert "\n" not in str(caught.value)

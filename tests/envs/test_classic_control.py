"""Tests of the classic-control envs (``swm/*Control-v*``): Gymnasium's dynamics, factors, goals,
success rules, frames, reset options and the scripted experts."""

from __future__ import annotations

import subprocess
import sys

import gymnasium as gym
import numpy as np
import pytest
from env_checks import assert_render_size, factor_value

import stable_worldmodel as swm
from stable_worldmodel import keys
from stable_worldmodel._optional import missing_extra
from stable_worldmodel.envs import get_entry
from stable_worldmodel.envs.classic_control.acrobot import AcrobotControlEnv
from stable_worldmodel.envs.classic_control.cartpole import CartPoleControlEnv
from stable_worldmodel.envs.classic_control.expert import ClassicControlExpert
from stable_worldmodel.envs.classic_control.mountain_car import (
    MountainCarContinuousControlEnv,
    MountainCarControlEnv,
)
from stable_worldmodel.envs.classic_control.pendulum import PendulumControlEnv
from stable_worldmodel.errors import ConfigError, SpaceError, UnknownNameError

ENVS = {
    "swm/CartPoleControl-v1": (CartPoleControlEnv, "CartPole-v1"),
    "swm/MountainCarControl-v0": (MountainCarControlEnv, "MountainCar-v0"),
    "swm/MountainCarContinuousControl-v0": (MountainCarContinuousControlEnv, "MountainCarContinuous-v0"),
    "swm/AcrobotControl-v1": (AcrobotControlEnv, "Acrobot-v1"),
    "swm/PendulumControl-v1": (PendulumControlEnv, "Pendulum-v1"),
}
IDS = list(ENVS)
DEFAULTS = {keys.VARIATION: []}  # resample nothing: the default factors


def make(env_id: str, size=(16, 16)):
    return ENVS[env_id][0](render_size=size)


def actions_for(env, n: int, seed: int = 0) -> list:
    """``n`` seeded samples of ``env.action_space``."""
    env.action_space.seed(seed)
    return [env.action_space.sample() for _ in range(n)]


# -- registry ---------------------------------------------------------------------------------
def test_registered_with_gymnasium_limits_tags_and_no_extra():
    limits = {IDS[0]: 500, IDS[1]: 200, IDS[2]: 999, IDS[3]: 500, IDS[4]: 200}
    for env_id, steps in limits.items():
        entry = get_entry(env_id)
        assert entry.max_episode_steps == steps and gym.spec(env_id).max_episode_steps == steps
        assert "classic_control" in entry.tags and missing_extra(entry.tags) is None  # Gymnasium only
        assert entry.expert is not None
    assert set(swm.envs.list_envs(tag="classic_control")) == set(IDS)
    assert "swm/AcrobotControl-v1" in swm.envs.list_envs(tag="discrete")
    assert "swm/PendulumControl-v1" in swm.envs.list_envs(tag="continuous")


def test_package_import_is_lazy():
    code = (
        "import sys, stable_worldmodel.envs.classic_control as cc; "
        "print(any(m.startswith('stable_worldmodel.envs.classic_control.') for m in sys.modules))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert out.stdout.split() == ["False"], out.stderr


# -- dynamics: Gymnasium's at the default factors ---------------------------------------------
@pytest.mark.parametrize("env_id", IDS)
def test_same_start_and_dynamics_as_gymnasium_at_default_factors(env_id):
    env, ref = make(env_id), gym.make(ENVS[env_id][1]).unwrapped
    for seed in (0, 1):
        obs, info = env.reset(seed=seed, options=DEFAULTS)
        ref_obs, _ = ref.reset(seed=seed)
        np.testing.assert_allclose(obs, ref_obs, atol=1e-6)
        assert info["env_name"] == ENVS[env_id][1]
        for a in actions_for(ref, 40, seed):
            obs, reward, terminated, truncated, _ = env.step(a)
            ref_obs, ref_reward, ref_terminated, *_ = ref.step(a)
            np.testing.assert_allclose(obs, ref_obs, atol=1e-4)  # the factors are float32 (upstream's)
            if terminated or truncated or ref_terminated:
                break
            assert reward == pytest.approx(ref_reward, rel=1e-4, abs=1e-4)


# -- factors --------------------------------------------------------------------------------
FACTORS = {
    "swm/CartPoleControl-v1": ["gravity", "masscart", "masspole", "length", "force_mag", "tau"],
    "swm/MountainCarControl-v0": ["gravity", "force", "max_speed"],
    "swm/MountainCarContinuousControl-v0": ["power", "max_speed", "gravity"],
    "swm/AcrobotControl-v1": [
        "link_length_1",
        "link_mass_1",
        "link_mass_2",
        "link_com_pos_1",
        "link_com_pos_2",
        "link_moi",
    ],
    "swm/PendulumControl-v1": ["g", "m", "l", "max_torque", "max_speed", "dt"],
}
VISUALS = {  # what changes the frames (link_length_2 enters only the picture, as in Gymnasium)
    "swm/CartPoleControl-v1": ["bg", "cart", "pole", "axle", "physics.length"],
    "swm/MountainCarControl-v0": ["bg", "fg"],
    "swm/MountainCarContinuousControl-v0": ["bg", "fg"],
    "swm/AcrobotControl-v1": ["bg", "line", "link", "joint", "physics.link_length_2", "physics.link_length_1"],
    "swm/PendulumControl-v1": ["bg", "rod", "hub", "physics.l"],
}
# a start (observation layout) and an action that excite every physical factor within a few steps
EXCITE = {
    "swm/CartPoleControl-v1": (None, 1),
    "swm/MountainCarControl-v0": ([-0.7, 0.034], 2),
    "swm/MountainCarContinuousControl-v0": ([-0.7, 0.034], np.array([1.0], np.float32)),
    "swm/AcrobotControl-v1": (None, 2),
    "swm/PendulumControl-v1": ([np.cos(1.0), np.sin(1.0), 3.9], np.array([2.0], np.float32)),
}


def _rollout_at(env, env_id, name, which, steps=6):
    """States and frames of ``steps`` steps with factor ``name`` at its low or high bound (others default)."""
    space = env.variation_space[name]
    value = (space.low if which == "low" else space.high).astype(space.dtype)
    start, action = EXCITE[env_id]
    options = {**DEFAULTS, keys.VARIATION_VALUES: {name: value}}
    if start is not None:
        options[keys.STATE] = start
    obs, _ = env.reset(seed=3, options=options)
    states, frames = [obs], [env.render()]
    for _ in range(steps):
        obs, *_ = env.step(action)
        states.append(obs)
        frames.append(env.render())
    return np.stack(states), np.stack(frames)


def test_factor_names_as_upstream():
    for env_id in IDS:
        names = make(env_id).variation_space.names()
        expected = {f"physics.{n}" for n in FACTORS[env_id]}
        expected |= {n if "." in n else f"visuals.{n}" for n in VISUALS[env_id]}
        assert sorted(names) == sorted(expected) and len(names) >= 5


@pytest.mark.parametrize("env_id", IDS)
def test_every_factor_changes_the_dynamics_or_the_frames(env_id):
    env = make(env_id, (32, 32))
    for name in FACTORS[env_id]:
        low, high = (_rollout_at(env, env_id, f"physics.{name}", w)[0] for w in ("low", "high"))
        assert not np.allclose(low, high), f"physics.{name} changed no state"
    for name in VISUALS[env_id]:
        full = name if "." in name else f"visuals.{name}"
        low, high = (_rollout_at(env, env_id, full, w)[1] for w in ("low", "high"))
        assert not np.array_equal(low[0], high[0]), f"{full} changed no frame"


def test_reset_resamples_every_factor_unless_told_otherwise():
    env = make("swm/CartPoleControl-v1")
    default = factor_value(env, "physics.gravity")
    env.reset(seed=0)  # upstream: every factor resampled, seeded by the reset seed
    first = {n: factor_value(env, n) for n in env.variation_space.names()}
    assert not np.array_equal(first["physics.gravity"], default)
    env.reset(seed=0)
    assert all(np.array_equal(factor_value(env, n), v) for n, v in first.items())
    env.reset(seed=0, options=DEFAULTS)
    assert np.array_equal(factor_value(env, "physics.gravity"), default)
    env.reset(seed=0, options={keys.VARIATION: ["physics.tau"]})
    assert np.array_equal(factor_value(env, "physics.gravity"), default)
    assert not np.array_equal(factor_value(env, "physics.tau"), [0.02])
    with pytest.raises(UnknownNameError, match="physics.gravity"):
        env.reset(seed=0, options={keys.VARIATION: ["physics.gravty"]})


# -- goals and success ----------------------------------------------------------------------
@pytest.mark.parametrize("env_id", IDS)
def test_goal_info_and_goal_image(env_id):
    env = make(env_id, (24, 32))
    obs, info = env.reset(seed=2, options={keys.VARIATION: ["all"]})
    assert env.observation_space.contains(obs)
    np.testing.assert_array_equal(info[keys.STATE], obs)
    np.testing.assert_array_equal(info[keys.PROPRIO], obs)
    np.testing.assert_array_equal(info[keys.GOAL_PROPRIO], info[keys.GOAL_STATE])
    assert info[keys.GOAL].shape == (24, 32, 3) and info[keys.GOAL].dtype == np.uint8
    assert env.eval_state(info[keys.GOAL_STATE], info[keys.GOAL_STATE])[0]
    # the goal image is the frame of the goal state
    goal = info[keys.GOAL].copy()
    env.reset(seed=2, options={keys.VARIATION: ["all"], keys.STATE: info[keys.GOAL_STATE]})
    np.testing.assert_allclose(env.render().astype(int), goal.astype(int), atol=2)


def test_cartpole_goal_success_and_fall():
    env = make("swm/CartPoleControl-v1")
    _, info = env.reset(seed=0, options=DEFAULTS)
    gx = info[keys.GOAL_STATE][0]
    assert 0.5 <= abs(gx) <= 1.5 and np.array_equal(info[keys.GOAL_STATE][1:], [0, 0, 0])
    assert env.eval_state([gx, 0, 0, 0], [gx + 0.05, 0.1, 0.02, 0.3])[0]
    assert not env.eval_state([gx, 0, 0, 0], [gx + 0.2, 0, 0, 0])[0]
    assert not env.eval_state([gx, 0, 0, 0], [gx, 0, 0.1, 0])[0]
    # start next to the goal: reached after one step -> terminated
    env.reset(seed=0, options={**DEFAULTS, keys.STATE: [gx, 0, 0, 0]})
    _, reward, terminated, truncated, _ = env.step(0)
    assert (reward, terminated, truncated) == (1.0, True, False)
    # a falling pole is a failure: truncated, not terminated
    env.reset(seed=0, options={**DEFAULTS, keys.STATE: [0, 0, 0.2, 1.0]})
    _, _, terminated, truncated, _ = env.step(1)
    assert (terminated, truncated) == (False, True)


def test_mountain_car_flag_rule_and_other_goals():
    env = make("swm/MountainCarControl-v0")
    _, info = env.reset(seed=0, options=DEFAULTS)
    np.testing.assert_array_equal(info[keys.GOAL_STATE], [0.5, 0.0])
    assert env.eval_state([0.5, 0], [0.55, 0.01]) == (True, 0.0)
    assert not env.eval_state([0.5, 0], [0.55, -0.01])[0]  # Gymnasium's goal velocity
    assert not env.eval_state([0.5, 0], [0.45, 0.01])[0]
    assert env.eval_state([-0.9, 0.02], [-0.87, -0.03])[0]  # another goal: the position within 0.05
    assert not env.eval_state([-0.9, 0.02], [-0.8, 0.02])[0]
    env.reset(seed=0, options={**DEFAULTS, keys.STATE: [0.49, 0.02]})
    assert env.step(2)[2]
    cont = make("swm/MountainCarContinuousControl-v0")
    _, info = cont.reset(seed=0, options=DEFAULTS)
    assert info[keys.GOAL_STATE][0] == pytest.approx(0.45)
    assert cont.eval_state(info[keys.GOAL_STATE], [0.451, 0.0])[0]  # float32 goal: still the flag rule
    cont.reset(seed=0, options={**DEFAULTS, keys.STATE: [0.44, 0.02]})
    _, reward, terminated, *_ = cont.step([0.5])
    assert terminated and reward == pytest.approx(100.0 - 0.025)


def test_acrobot_height_rule():
    env = make("swm/AcrobotControl-v1")
    _, info = env.reset(seed=0, options=DEFAULTS)
    goal = info[keys.GOAL_STATE]
    np.testing.assert_allclose(goal, [0, 1, 0, 1, 0, 0], atol=1e-7)  # first link level, second upright

    def obs(t1, t2):
        return [np.cos(t1), np.sin(t1), np.cos(t2), np.sin(t2), 0, 0]

    assert env.eval_state(goal, obs(np.pi, 0.0)) == (True, 0.0)  # upright: tip at height 2
    assert not env.eval_state(goal, obs(0.0, 0.0))[0]  # hanging: height -2
    assert env.eval_state(goal, obs(0.0, 0.0))[1] == pytest.approx(3.0)
    assert env.eval_state(obs(np.pi, 0.0), obs(np.pi - 0.1, 0.0))[0] is False  # a higher goal


def test_pendulum_goal_and_termination():
    env = make("swm/PendulumControl-v1")
    _, info = env.reset(seed=0, options=DEFAULTS)
    np.testing.assert_array_equal(info[keys.GOAL_STATE], [1, 0, 0])
    assert env.eval_state([1, 0, 0], [np.cos(0.05), np.sin(0.05), 0.4])[0]
    assert not env.eval_state([1, 0, 0], [np.cos(0.05), np.sin(0.05), 0.6])[0]
    assert not env.eval_state([1, 0, 0], [np.cos(0.2), -np.sin(0.2), 0.0])[0]
    env.reset(seed=0, options={**DEFAULTS, keys.STATE: [1, 0, 0]})
    assert env.step([0.0])[2]


# -- options, errors, rendering ---------------------------------------------------------------
def test_state_and_goal_options_and_dataset_reset():
    env = make("swm/AcrobotControl-v1")
    start = np.array([np.cos(0.3), np.sin(0.3), np.cos(-0.2), np.sin(-0.2), 0.5, -1.0], np.float32)
    obs, info = env.reset(seed=0, options={keys.STATE: start, keys.GOAL_STATE: start})
    np.testing.assert_allclose(obs, start, atol=1e-6)
    np.testing.assert_allclose(info[keys.GOAL_STATE], start, atol=1e-6)
    opts = env.reset_options_from_dataset(
        {keys.STATE: start, "variation.physics.link_moi": np.array([1.3], np.float32)}, {keys.STATE: start}
    )
    env.reset(seed=0, options=opts)
    assert factor_value(env, "physics.link_moi")[0] == pytest.approx(1.3)
    assert factor_value(env, "physics.link_mass_1")[0] == 1.0  # not recorded: the default, not a draw


@pytest.mark.parametrize("env_id", IDS)
def test_bad_inputs_raise_typed_errors(env_id):
    env = make(env_id)
    env.reset(seed=0)
    with pytest.raises(ConfigError, match="reset option 'state'"):
        env.reset(seed=0, options={keys.STATE: [1.0] * 9})
    with pytest.raises(ConfigError, match="eval_state requires goal_state"):
        env.eval_state(np.zeros(9), np.zeros(env.FEATURES))
    bad = 7 if isinstance(env.action_space, gym.spaces.Discrete) else [np.nan]
    with pytest.raises(SpaceError, match="step requires"):
        env.step(bad)
    with pytest.raises(ConfigError, match="render_mode"):
        ENVS[env_id][0](render_mode="human")


@pytest.mark.parametrize("env_id", IDS)
def test_render_size(env_id):
    assert_render_size(ENVS[env_id][0](render_size=(40, 56)), (40, 56))
    assert make(env_id, (16, 16)).render_size == (16, 16)
    assert ENVS[env_id][0]().render().shape[:2] == ENVS[env_id][0].RENDER_SIZE  # Gymnasium's screen


# -- experts --------------------------------------------------------------------------------
@pytest.mark.parametrize("env_id", IDS)
def test_expert_succeeds_at_default_factors(env_id):
    env = make(env_id, (8, 8))
    expert = ClassicControlExpert(env_id)
    limit = get_entry(env_id).max_episode_steps
    for seed in range(4):
        _, info = env.reset(seed=seed, options=DEFAULTS)
        for _ in range(limit):
            batch = {k: np.asarray(info[k])[None, None] for k in (keys.STATE, keys.GOAL_STATE)}
            action = expert.get_action(batch)[0]
            assert env.action_space.contains(action)
            _, _, terminated, truncated, info = env.step(action)
            if terminated or truncated:
                break
        assert terminated, f"{env_id} seed {seed}"


def test_expert_in_world_with_resampled_factors():
    world = swm.World("swm/CartPoleControl-v1", num_envs=4, image_shape=(16, 16), max_episode_steps=500, verbose=0)
    world.set_policy(swm.envs.expert_policy("swm/CartPoleControl-v1"))
    result = world.evaluate(episodes=4, seed=0, options={keys.VARIATION: ["all"]})
    world.close()
    assert result["success_rate"] == 100.0


def test_expert_noise_and_bad_arguments():
    infos = {keys.STATE: np.zeros((64, 1, 3)), keys.GOAL_STATE: np.tile([1.0, 0, 0], (64, 1, 1))}
    a = ClassicControlExpert("swm/PendulumControl-v1", noise=0.5, seed=0).get_action(infos)
    assert a.shape == (64, 1) and a.dtype == np.float32 and np.all(np.abs(a) <= 2.0) and a.std() > 0
    d = ClassicControlExpert("swm/AcrobotControl-v1", noise=1.0, seed=0).get_action(
        {keys.STATE: np.zeros((64, 1, 6)), keys.GOAL_STATE: np.zeros((64, 1, 6))}
    )
    assert d.dtype == np.int64 and set(np.unique(d)) <= {0, 1, 2} and len(np.unique(d)) > 1
    with pytest.raises(UnknownNameError, match="swm/CartPoleControl-v1"):
        ClassicControlExpert("swm/CartPoleControl-v0")
    with pytest.raises(ConfigError, match="noise"):
        ClassicControlExpert("swm/CartPoleControl-v1", noise=-1.0)

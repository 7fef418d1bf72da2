"""``swm/PFRocketLanding-v0``: PyFlyt's rocket landing with factors (extra ``pyflyt``) and its expert."""

from __future__ import annotations

import subprocess
import sys

import gymnasium as gym
import numpy as np
import pytest
from env_checks import assert_render_size

from stable_worldmodel import keys
from stable_worldmodel._optional import is_available, missing_extra
from stable_worldmodel.envs import get_entry

ENV_ID = "swm/PFRocketLanding-v0"
pytestmark = pytest.mark.skipif(
    not (is_available("PyFlyt") and is_available("pybullet")), reason="extra 'pyflyt' not installed"
)
OFF = np.zeros(7)  # engine off, controls centred


def make(**kwargs):
    return gym.make(ENV_ID, disable_env_checker=True, **kwargs).unwrapped


def run(env, actions, seed=0, options=None):
    obs, info = env.reset(seed=seed, options=options)
    for a in actions:
        obs, reward, terminated, truncated, info = env.step(a)
        if terminated or truncated:
            break
    return obs, terminated, truncated, info


def test_spaces_start_and_goal():
    env = make(render_mode=None)
    assert env.observation_space.shape == (17,) and env.action_space.shape == (7,)
    assert len(env.variation_space.names()) == 16
    obs, info = env.reset(seed=0)
    assert obs[2] == pytest.approx(225.0 - 100.0 * 10 / 120, abs=0.5)  # 0.9 * ceiling, after 10 settling steps
    assert obs[5] == pytest.approx(-100.0, abs=1.0) and obs[6] == pytest.approx(1.0)
    assert obs[13] == pytest.approx(0.05, abs=1e-3)
    np.testing.assert_allclose(obs[14:17], -obs[:3])  # the pad at the origin
    goal = info[keys.GOAL_STATE]
    assert goal[:3].tolist() == pytest.approx([0.0, 0.0, 2.576]) and goal[6] == 1.0
    assert info[keys.PROPRIO].shape == (14,) and info[keys.GOAL_PROPRIO].shape == (14,)
    assert env.eval_state(goal, goal) == (True, 0.0)
    moving = goal.copy()
    moving[5] = -3.0
    assert not env.eval_state(goal, moving)[0]
    env.close()


def test_free_fall_crashes_as_a_truncated_failure():
    env = make(render_mode=None)
    obs, terminated, truncated, info = run(env, [OFF] * 400)
    assert truncated and not terminated and info["fatal_collision"] and not info["env_complete"]
    env.close()


def test_the_expert_lands_and_landing_terminates():
    from stable_worldmodel.envs.rocket_landing import RocketLandingExpert

    env, expert = make(render_mode=None), RocketLandingExpert()
    obs, info = env.reset(seed=0)
    for _ in range(600):
        obs, reward, terminated, truncated, info = env.step(expert.get_action({keys.STATE: obs[None, None]})[0])
        if terminated or truncated:
            break
    assert terminated and not truncated and info["env_complete"] and info["pad_contact"] == 1.0
    assert env.eval_state(info[keys.GOAL_STATE], obs)[0]
    env.close()


@pytest.mark.parametrize(
    ("factor", "value"),
    [
        ("environment.gravity", 12.0),
        ("environment.wind", [5.0, -5.0]),
        ("environment.start_speed", 20.0),
        ("environment.start_height_ratio", 0.7),
        ("environment.start_horizontal_offset", [10.0, -5.0]),
        ("environment.start_tilt", [0.2, 0.0]),
        ("rocket.body_mass", 115.0),
        ("rocket.fuel_ratio", 0.2),
    ],
)
def test_physical_factors_change_the_flight(factor, value):
    env = make(render_mode=None)
    burn = np.array([0.0, 0.0, 0.0, 1.0, 0.5, 0.0, 0.0])
    ref, *_ = run(env, [burn] * 20)
    out, *_ = run(env, [burn] * 20, options={keys.VARIATION_VALUES: {factor: value}})
    assert not np.allclose(ref, out)
    env.close()


def test_pad_position_moves_the_goal_and_the_pad_offset():
    env = make(render_mode=None)
    obs, info = env.reset(seed=0, options={keys.VARIATION_VALUES: {"pad.position": [10.0, -4.0]}})
    assert info[keys.GOAL_STATE][:2].tolist() == [10.0, -4.0]
    np.testing.assert_allclose(obs[14:16], [10.0 - obs[0], -4.0 - obs[1]])
    _, info = env.reset(seed=0, options={keys.GOAL_STATE: [3.0, 2.0, 2.576]})
    assert info[keys.GOAL_STATE][:2].tolist() == [3.0, 2.0]
    env.close()


@pytest.mark.parametrize(
    "factor", ["rocket.body_color", "environment.sky_color", "environment.ground_color", "pad.color"]
)
def test_colors_change_the_frames(factor):
    env = make(render_size=(48, 48))
    _, info = env.reset(seed=0)
    ref = [env.render(), info[keys.GOAL]]
    _, info = env.reset(seed=0, options={keys.VARIATION_VALUES: {factor: [255, 0, 255]}})
    out = [env.render(), info[keys.GOAL]]
    assert any(not np.array_equal(a, b) for a, b in zip(ref, out, strict=True))
    env.close()


def test_render_size_and_state_option():
    env = make(render_size=(40, 56))
    assert_render_size(env, (40, 56))
    obs, *_ = run(env, [np.array([0.3, 0.0, 0.0, 1.0, 0.2, 0.5, 0.0])] * 15)
    again, _ = env.reset(seed=1, options={keys.STATE: obs})
    np.testing.assert_allclose(again[:3], obs[:3] + obs[3:6] * 10 / 120, atol=0.2)  # then 10 settling steps
    env.close()


def test_registry_entry_and_missing_extra():
    entry = get_entry(ENV_ID)
    assert "pyflyt" in entry.tags and entry.expert.endswith("RocketLandingExpert") and entry.tool_steps == 1200
    assert missing_extra(entry.tags) is None
    code = (
        "import sys; sys.modules['PyFlyt'] = None\n"
        "import gymnasium as gym, stable_worldmodel\n"
        "from stable_worldmodel.errors import DependencyNotInstalled\n"
        "try:\n"
        f"    gym.make({ENV_ID!r})\n"
        "except DependencyNotInstalled as e:\n"
        "    print('typed:', e)\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert "typed:" in out.stdout and 'pip install "stable-worldmodel[pyflyt]"' in out.stdout, out.stderr


def test_quiet_and_no_numba_compilation():
    code = (
        "import gymnasium as gym, stable_worldmodel\n"
        f"env = gym.make({ENV_ID!r}, render_mode=None).unwrapped\n"
        "env.reset(seed=0)\n"
        "from PyFlyt.core.abstractions.lifting_surfaces import LiftingSurface\n"
        "import sys\n"
        "sys.stderr.write(type(LiftingSurface._jitted_compute_aero_data).__name__)\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert out.stdout == "" and out.stderr == "function", (out.stdout, out.stderr)

"""ALE through ale-py (extra "ale"): the lazy ALE/<Game>-v5 ids, ale-py's own envs behind them,
World on these goal-less envs, the Atari-100k wrappers, the missing-extra message."""

from __future__ import annotations

import subprocess
import sys

import gymnasium as gym
import numpy as np
import pytest

import stable_worldmodel as swm
from stable_worldmodel import keys
from stable_worldmodel._optional import is_available
from stable_worldmodel.envs.ale.registration import ALE_IDS, GAMES, V5_KWARGS, ale_id

ALE = pytest.mark.skipif(not is_available("ale_py"), reason="extra 'ale' not installed")


def _python(code: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-W", "always", "-c", code], capture_output=True, text=True, timeout=120)


def test_ids_are_registered_without_ale_py_and_read_as_ale_pys():
    assert ale_id("space_invaders") == "ALE/SpaceInvaders-v5" and ale_id("tic_tac_toe_3d") == "ALE/TicTacToe3D-v5"
    assert len(ALE_IDS) == len(GAMES) == 104
    for env_id in ("ALE/Pong-v5", "ALE/Breakout-v5", "ALE/MontezumaRevenge-v5"):
        spec = gym.spec(env_id)
        assert {k: v for k, v in spec.kwargs.items() if k != "game"} == V5_KWARGS and spec.max_episode_steps is None
    assert swm.envs.get_entry("ALE/Pong-v5").env_id == "ALE/Pong-v5"  # known to World through Gymnasium
    assert "ALE/Pong-v5" not in swm.envs.list_envs()  # no factors, no goal: not an swm world


@ALE
def test_game_list_is_ale_pys():
    import ale_py.roms

    assert set(GAMES) == set(ale_py.roms.get_all_rom_ids()) - {"combat", "joust", "maze_craze", "warlords"}


@ALE
def test_first_make_hands_over_to_ale_py_without_warnings():
    out = _python(
        "import sys, gymnasium as gym, stable_worldmodel\n"
        "assert 'ale_py' not in sys.modules\n"
        "assert gym.spec('ALE/Pong-v5').entry_point.startswith('stable_worldmodel')\n"
        "env = gym.make('ALE/Pong-v5')\n"
        "spec = gym.spec('ALE/Pong-v5')\n"
        "print(type(env.unwrapped).__module__, spec.entry_point, 'PongNoFrameskip-v4' in gym.registry)\n"
        "import ale_py; gym.register_envs(ale_py)\n"
    )
    assert out.stdout.split() == ["ale_py.env", "ale_py.env:AtariEnv", "True"], out.stderr
    assert "Overriding environment" not in out.stderr


@ALE
def test_importing_ale_py_after_us_gives_no_warnings():
    out = _python(
        "import importlib.util, gymnasium as gym, stable_worldmodel\n"
        "assert importlib.util.find_spec('ale_py') is not None  # a look-up imports nothing and keeps our ids\n"
        "assert gym.spec('ALE/Pong-v5').entry_point.startswith('stable_worldmodel')\n"
        "import ale_py\n"
        "print(gym.spec('ALE/Pong-v5').entry_point, type(ale_py.__spec__.loader).__name__)\n"
        "gym.make('ALE/Pong-v5').reset(seed=0)\n"
    )
    assert out.stdout.split() == ["ale_py.env:AtariEnv", "SourceFileLoader"], out.stderr
    assert "Overriding environment" not in out.stderr


def test_missing_ale_py_gives_the_pip_command():
    out = _python(
        "import sys; sys.modules['ale_py'] = None\n"
        "import gymnasium as gym, stable_worldmodel as swm\n"
        "for make in (lambda: gym.make('ALE/Pong-v5'), lambda: swm.World('ALE/Pong-v5', 1, image_shape=(8, 8))):\n"
        "    try:\n        make()\n    except Exception as e:\n        print(type(e).__name__, '|', e)\n"
    )
    lines = out.stdout.strip().splitlines()
    assert len(lines) == 2, out.stderr
    for line in lines:
        assert line.startswith("DependencyNotInstalled |") and 'pip install "stable-worldmodel[ale]"' in line


@ALE
@pytest.mark.parametrize("env_id", ["ALE/Pong-v5", "ALE/Breakout-v5"])
def test_ale_env_is_seeded(env_id):
    def rollout():
        env = gym.make(env_id)
        env.action_space.seed(0)
        obs, _ = env.reset(seed=3)
        frames = [obs]
        for _ in range(20):
            obs, *_ = env.step(env.action_space.sample())
            frames.append(obs)
        env.close()
        return np.stack(frames)

    a, b = rollout(), rollout()
    assert a.shape == (21, 210, 160, 3) and a.dtype == np.uint8
    np.testing.assert_array_equal(a, b)


@ALE
def test_world_runs_ale_goal_less():
    world = swm.World("ALE/Pong-v5", num_envs=2, image_shape=(16, 16), verbose=0, vectorization_mode="sync")
    world.set_policy(swm.policy.RandomPolicy(seed=0))
    world.reset(seed=0)
    for _ in range(3):
        world.step()
    assert world.infos[keys.PIXELS].shape == (2, 1, 16, 16, 3) and keys.GOAL not in world.infos
    assert world.infos[keys.ACTION].shape[:2] == (2, 1)
    world.close()


@ALE
def test_atari_100k_wrappers():
    from stable_worldmodel.envs.ale import make_atari_env

    def first_frames(seed):
        env = make_atari_env("ALE/Breakout-v5", seed=seed, img_size=32)
        obs, _ = env.reset(seed=seed)
        return env, obs

    env, obs = first_frames(1)
    assert env.action_space.n == 18 and obs.shape == (32, 32, 3)  # full action set, resized frames
    np.testing.assert_array_equal(first_frames(1)[1], obs)  # the no-op count comes from the seed
    env.action_space.seed(0)
    rewards, ended = set(), False
    for _ in range(2000):  # random play loses a life quickly: the episode ends there
        _, reward, terminated, truncated, _ = env.step(env.action_space.sample())
        rewards.add(reward)
        if terminated or truncated:
            ended = env.unwrapped.ale.lives() > 0
            break
    assert ended and rewards <= {-1.0, 0.0, 1.0}
    env.close()

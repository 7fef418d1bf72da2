"""One smoke test over every registered env, plus the registry itself."""

from __future__ import annotations

import re
import subprocess
import sys

import gymnasium as gym
import numpy as np
import pytest
from env_checks import run_actions
from gymnasium.utils.env_checker import check_env

import stable_worldmodel as swm
from stable_worldmodel import keys
from stable_worldmodel._optional import missing_extra
from stable_worldmodel.envs import get_entry, list_envs, register_env
from stable_worldmodel.envs.base import SupportsDatasetReset, SupportsEvalState, SupportsRenderSize
from stable_worldmodel.errors import UnknownNameError

#: families whose first step compiles for a minute (craftax's JAX games): their smoke tests run with -m slow
SLOW_TAGS = {"craftax"}


#: ids that are another reward or observation layout of the same simulation: one World test of the family runs
#: by default (each still gets its smoke test); the rest with -m slow
SAME_SIMULATION = re.compile(r"swm/Fetch\w+(Dense|Dict)-v3")


def _param(env_id: str, world: bool = False):
    tags = set(get_entry(env_id).tags)
    if missing_extra(tags):
        return pytest.param(env_id, marks=pytest.mark.skip(reason=f"extra {missing_extra(tags)!r} not installed"))
    if tags & SLOW_TAGS or (world and SAME_SIMULATION.fullmatch(env_id)):
        return pytest.param(env_id, marks=pytest.mark.slow)
    return env_id


ENVS = [_param(e) for e in list_envs()]
WORLD_ENVS = [_param(e, world=True) for e in list_envs()]


def fast(env_id: str) -> dict:
    """Constructor kwargs that keep the smoke tests quick: MuJoCo envs (and Fetch) render without shadows
    (render_quality 'low', ~8x faster on a CPU renderer; the picture is not what these test)."""
    return {"render_quality": "low"} if {"mujoco", "robotics"} & set(get_entry(env_id).tags) else {}


def test_registry_lists_the_seed_envs():
    for env_id in (
        "swm/PushT-v1",
        "swm/PushT-Discrete-v1",
        "swm/TwoRoom-v2",
        "swm/SimplePointMaze-v0",
        "swm/ImagePositioning-v1",
        "swm/VoidRun-v0",
    ):
        assert env_id in ENVS and env_id in gym.registry
        assert isinstance(gym.registry[env_id].entry_point, str)  # nothing imported to register
    assert "swm/PushT-v1" in list_envs(tag="paper") and "swm/VoidRun-v0" not in list_envs(tag="paper")


def test_registering_imports_no_env_code():
    code = (
        "import sys, stable_worldmodel; "
        "print(any(m.startswith('stable_worldmodel.envs.pusht.') for m in sys.modules), 'pymunk' in sys.modules)"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert out.stdout.split() == ["False", "False"]


def test_unknown_id_suggests():
    with pytest.raises(UnknownNameError, match="swm/VoidRun-v0"):
        get_entry("swm/VoidRunn-v0")


def test_register_env_is_idempotent_and_usable():
    from stable_worldmodel.envs import _registry

    try:
        register_env("swm/ToyCopy-v0", "stable_worldmodel.envs.toy.env:ToyEnv", tags=("toy",))
        register_env("swm/ToyCopy-v0", "stable_worldmodel.envs.toy.env:ToyEnv", tags=("toy",))
        assert "swm/ToyCopy-v0" in list_envs(tag="toy")
        gym.make("swm/ToyCopy-v0").reset(seed=0)
    finally:  # leave the registry as the other tests expect it
        _registry._ENTRIES.pop("swm/ToyCopy-v0", None)
        gym.registry.pop("swm/ToyCopy-v0", None)


@pytest.mark.parametrize("env_id", ENVS)
def test_env_smoke(env_id):
    env = gym.make(env_id, disable_env_checker=True, **fast(env_id)).unwrapped
    check_env(env, skip_render_check=False)
    assert isinstance(env, SupportsRenderSize) and isinstance(env, SupportsEvalState)
    assert isinstance(env, SupportsDatasetReset)
    assert len(env.variation_space.names()) >= 5
    _, info = env.reset(seed=0)
    assert set(info) >= {keys.GOAL, keys.GOAL_STATE, keys.GOAL_PROPRIO}

    def rollout():
        e = gym.make(env_id, disable_env_checker=True, **fast(env_id))
        e.unwrapped.set_render_size((32, 32))
        e.action_space.seed(0)
        actions = [e.action_space.sample() for _ in range(5)]
        frames, states, goal = run_actions(e, 3, actions, options={"variation": ["all"]})
        assert goal.shape == (32, 32, 3)
        return states, frames

    (s1, f1), (s2, f2) = rollout(), rollout()
    np.testing.assert_array_equal(s1, s2)
    np.testing.assert_array_equal(f1, f2)
    assert f1.shape[1:] == (32, 32, 3) and f1.dtype == np.uint8


@pytest.mark.parametrize("num_envs", [1, 3])  # 3: batched, without paying 8 MuJoCo scenes per env
@pytest.mark.parametrize("env_id", WORLD_ENVS)
def test_env_in_world_with_its_expert(env_id, num_envs):
    world = swm.World(
        env_id, num_envs=num_envs, image_shape=(16, 16), verbose=0, vectorization_mode="sync", **fast(env_id)
    )
    has_expert = get_entry(env_id).expert is not None  # DMControl domains without a scripted one: random
    world.set_policy(swm.envs.expert_policy(env_id) if has_expert else swm.policy.RandomPolicy(seed=0))
    world.reset(seed=0)
    for _ in range(3):
        world.step()
    assert world.infos[keys.PIXELS].shape == (num_envs, 1, 16, 16, 3)
    assert world.infos[keys.GOAL].shape == (num_envs, 1, 16, 16, 3)
    assert world.single_action_space.contains(world.infos[keys.ACTION][0, -1].astype(world.single_action_space.dtype))
    world.close()

"""Names research code of release 0.0.3 / upstream 0.1.1 imports from ``stable_worldmodel.envs``."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import stable_worldmodel as swm
from stable_worldmodel import keys
from stable_worldmodel.errors import ConfigError, UnknownNameError


def test_register_and_worlds_as_in_0_0_3():
    assert "swm/PushT-v1" in swm.envs.WORLDS and "swm/TwoRoom-v2" in swm.envs.WORLDS
    swm.envs.register(id="swm/CompatToy-v0", entry_point="stable_worldmodel.envs.toy.env:ToyEnv")
    assert "swm/CompatToy-v0" in swm.envs.WORLDS and "swm/CompatToy-v0" in gym.registry
    world = swm.World("swm/CompatToy-v0", num_envs=1, image_shape=(8, 8), max_episode_steps=3, verbose=0)
    world.set_policy(swm.policy.RandomPolicy(seed=0))
    world.reset(seed=0)
    assert world.infos[keys.PIXELS].shape == (1, 1, 8, 8, 3)


def test_unknown_env_id_suggests_ours_once_and_stays_short():
    with pytest.raises(UnknownNameError) as err:
        swm.World("swm/Pusht-v1", num_envs=1, image_shape=(8, 8))
    message = str(err.value)
    assert "Did you mean" in message and "'swm/PushT-v1'" in message
    assert message.count("'swm/PushT-v1'") == 1
    assert "'CartPole-v1'" not in message and "ALE/" not in message  # no dump of every Gymnasium id
    assert "swm/<Name>DMControl-v0 (12)" in message and len(message) < 900  # families of many ids: one entry


def _distance_to_block(world, steps):
    out = []
    for _ in range(steps):
        world.step()
        s = world.infos[keys.STATE][:, -1]
        out.append(np.abs(s[:, 0:2] - s[:, 2:4]).max())
    return out


@pytest.mark.parametrize("env_id", ["swm/PushT-v2", "swm/PushT-Discrete-v2"])
def test_pusht_weak_policy_keeps_the_agent_near_the_block(env_id):
    from stable_worldmodel.envs.pusht import WeakPolicy

    world = swm.World(env_id, num_envs=2, image_shape=(16, 16), max_episode_steps=40, verbose=0)
    world.set_policy(WeakPolicy(dist_constraint=60, seed=0))
    world.reset(seed=0)
    late = _distance_to_block(world, 30)[-10:]
    assert max(late) <= 60 + 5  # the agent is drawn into the square around the block
    actions = world.policy.get_action(world.infos)
    assert actions.shape == (2, 2)
    if "Discrete" in env_id:
        assert actions.dtype == np.int64
    else:
        assert np.abs(actions).max() <= 1.0


def test_weak_policy_is_seeded_and_checks_its_env():
    from stable_worldmodel.envs.pusht import WeakPolicy

    with pytest.raises(ConfigError, match="dist_constraint"):
        WeakPolicy(dist_constraint=0)
    world = swm.World("swm/TwoRoom-v2", num_envs=1, image_shape=(8, 8), verbose=0)
    with pytest.raises(ConfigError, match="requires a PushT environment, got 'swm/TwoRoom-v2'"):
        world.set_policy(WeakPolicy())
    runs = []
    for _ in range(2):
        world = swm.World("swm/PushT-v1", num_envs=2, image_shape=(8, 8), max_episode_steps=5, verbose=0)
        world.set_policy(WeakPolicy(seed=3))
        runs.append(world.evaluate(episodes=2, seed=0, eval_keys=[keys.STATE])[keys.STATE])
    np.testing.assert_array_equal(runs[0], runs[1])


def test_two_room_expert_policy_under_its_upstream_name():
    from stable_worldmodel.envs.two_room import ExpertPolicy

    world = swm.World("swm/TwoRoom-v2", num_envs=4, image_shape=(8, 8), max_episode_steps=100, verbose=0)
    world.set_policy(ExpertPolicy(seed=0))
    assert world.evaluate(episodes=4, seed=0)["success_rate"] == 100.0
    sticky = ExpertPolicy(action_noise=0.5, action_repeat_prob=1.0, seed=0)
    world.set_policy(sticky)
    world.reset(seed=0)
    first = sticky.get_action(world.infos)
    world.step()
    np.testing.assert_array_equal(sticky.get_action(world.infos), first)  # always repeated
    with pytest.raises(ConfigError, match="action_repeat_prob"):
        ExpertPolicy(action_repeat_prob=2)

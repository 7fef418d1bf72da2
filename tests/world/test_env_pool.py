"""``world.env_pool.EnvPool``, public in upstream 0.1.1: batched reset/step of in-process envs,
per-env arguments, masks, infos stacked ``(N, 1, ...)`` and updated in place (behaviour observed
on 0.1.1); ``autoreset`` is ours."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

from stable_worldmodel.errors import ConfigError
from stable_worldmodel.world.env_pool import EnvPool

TOY = "swm/Toy-v0"


def pool(n=3, **kwargs):
    return EnvPool([lambda: gym.make(TOY, max_episode_steps=4) for _ in range(n)], **kwargs)


def test_batched_spaces_and_variation_space():
    p = pool()
    assert p.num_envs == 3 and p.action_space.shape == (3, *p.single_action_space.shape)
    assert p.action_space is p.action_space  # built once: seeding it sticks
    assert p.observation_space["state"].shape == (3, 2)  # a Dict space, batched per key
    assert p.single_variation_space is p.variation_space and p.variation_space is not None


def test_reset_seeds_each_env_and_stacks_infos():
    p = pool()
    _, infos = p.reset(seed=10)
    assert p.seeds.tolist() == [10, 11, 12]
    goal = infos["goal_state"]
    assert isinstance(goal, np.ndarray) and goal.shape == (3, 1, 2)
    single = gym.make(TOY, max_episode_steps=4)
    _, info = single.reset(seed=11)
    np.testing.assert_array_equal(goal[1, 0], info["goal_state"])  # env 1 got seed 10 + 1
    _, again = p.reset(seed=[3, 4, 5], options=[None, None, None])
    assert again is not infos and p.seeds.tolist() == [3, 4, 5]


def test_masked_reset_and_step_touch_only_the_chosen_envs():
    p = pool()
    _, infos = p.reset(seed=0)
    before, before_goal = infos["goal_proprio"].copy(), infos["goal_state"].copy()
    actions = np.stack([p.single_action_space.sample() for _ in range(3)])
    _, rewards, term, trunc, after = p.step(actions, mask=[True, False, True])
    assert after is infos  # updated in place
    np.testing.assert_array_equal(after["goal_proprio"][1], before[1])
    assert rewards.dtype == np.float32 and rewards[1] == 0 and not term[1] and not trunc[1]
    _, infos = p.reset(seed=[None, 7, None], mask=np.array([False, True, False]))
    assert p.seeds.tolist() == [0, 7, 2]
    _, fresh = gym.make(TOY).reset(seed=7)
    np.testing.assert_array_equal(infos["goal_state"][1, 0], fresh["goal_state"])
    np.testing.assert_array_equal(infos["goal_state"][0], before_goal[0])
    with pytest.raises(ConfigError, match="mask of 3 booleans"):
        p.step(actions, mask=[True, False])


def test_autoreset_starts_a_new_episode_at_the_end():
    p = pool(2, autoreset=True)
    p.reset(seed=0)
    actions = np.stack([p.single_action_space.sample() for _ in range(2)])
    for _ in range(4):  # max_episode_steps=4: the 4th step truncates
        _, _, term, trunc, infos = p.step(actions)
    assert (term | trunc).all()
    assert [env.get_wrapper_attr("_elapsed_steps") for env in p.envs] == [0, 0]  # a new episode began


def test_bad_arguments_are_typed_errors():
    with pytest.raises(ConfigError, match="non-empty list of env factories"):
        EnvPool([])
    p = pool()
    with pytest.raises(ConfigError, match="reset\\(\\) before step\\(\\)"):
        p.step(np.zeros((3, 2)))
    with pytest.raises(ConfigError, match="first reset to reset every env"):
        p.reset(mask=[True, False, True])
    with pytest.raises(ConfigError, match="one seed per env \\(3\\), got 2"):
        p.reset(seed=[1, 2])


def test_apply_callables_of_011_on_one_env():
    """``stable_worldmodel.world.world._apply_callables(env, callables, init_state)`` as 0.1.1's."""
    from stable_worldmodel.world.world import _apply_callables

    class Env:
        def __init__(self):
            self.calls = []

        def set_state(self, pos=None, speed=None):
            self.calls.append((pos, speed))

    env, state = Env(), {"state": np.array([1.0, 2.0])}
    specs = [
        {"method": "set_state", "args": {"pos": {"value": "state"}, "speed": {"value": 3, "in_dataset": False}}},
        {"method": "missing_method", "args": {}},  # skipped
        {"method": "set_state", "args": {"pos": {"value": "not_in_state"}}},  # the argument is left out
    ]
    _apply_callables(env, specs, state)
    assert env.calls[0][0].tolist() == [1.0, 2.0] and env.calls[0][1] == 3 and env.calls[1] == (None, None)
    assert env.calls[0][0] is not state["state"]  # a copy

"""World on the toy env: construction, reset/step, history, per-env options, evaluate, modes."""

from __future__ import annotations

import numpy as np
import pytest

import stable_worldmodel as swm
from stable_worldmodel import keys
from stable_worldmodel.errors import ConfigError, UnknownNameError
from stable_worldmodel.policy import RandomPolicy

TOY = "swm/Toy-v0"


def make(num_envs=2, **kw):
    kw.setdefault("vectorization_mode", "sync")
    kw.setdefault("verbose", 0)
    return swm.World(TOY, num_envs=num_envs, image_shape=(16, 16), **kw)


def test_unknown_env_suggests_closest():
    with pytest.raises(UnknownNameError, match="swm/PushT-v1"):
        swm.World("swm/PushTT-v1", num_envs=1, image_shape=(16, 16))


@pytest.mark.parametrize("bad", [dict(num_envs=0), dict(history_size=0), dict(image_shape=(0, 3)), dict(frame_skip=-1)])
def test_bad_arguments(bad):
    args = dict(num_envs=1, image_shape=(16, 16))
    args.update(bad)
    with pytest.raises(ConfigError):
        swm.World(TOY, **args)


def test_spaces_and_infos_layout():
    world = make(3, history_size=2)
    assert world.num_envs == 3
    assert world.single_action_space.shape == (2,)
    assert world.action_space.shape == (3, 2)
    assert world.single_variation_space is not None
    assert world.variation_space["agent"]["color"].shape == (3, 3)
    world.reset(seed=0)
    assert world.infos[keys.PIXELS].shape == (3, 2, 16, 16, 3)
    assert world.infos[keys.PIXELS].dtype == np.uint8
    assert world.infos[keys.GOAL].shape == (3, 2, 16, 16, 3)
    assert world.infos[keys.STATE].shape == (3, 2, 2)
    assert world.infos[keys.REWARD].shape == (3, 2)
    assert np.isnan(world.infos[keys.ACTION]).all()
    world.set_policy(RandomPolicy(seed=1))
    world.step()
    assert world.terminateds.shape == (3,) and world.rewards.shape == (3,)
    assert world.infos[keys.STEP_IDX][:, -1].tolist() == [1, 1, 1]
    world.close()


def test_step_requires_policy_and_reset():
    world = make(1)
    with pytest.raises(RuntimeError, match="set_policy"):
        world.step()
    world.set_policy(RandomPolicy())
    with pytest.raises(RuntimeError, match="reset"):
        world.step()


def test_reset_int_and_list_seeds():
    world = make(2)
    world.reset(seed=10)
    a = world.infos[keys.STATE].copy()
    world.reset(seed=[10, 11])
    assert np.array_equal(a, world.infos[keys.STATE])
    world.reset(seed=[11, 10])
    assert np.array_equal(a[::-1], world.infos[keys.STATE])
    with pytest.raises(ConfigError, match="one seed per env"):
        world.reset(seed=[1, 2, 3])


def test_reset_without_seed_is_reproducible_from_world_seed():
    a, b = make(2, seed=5), make(2, seed=5)
    a.reset()
    b.reset()
    assert np.array_equal(a.infos[keys.STATE], b.infos[keys.STATE])
    a.reset()
    assert not np.array_equal(a.infos[keys.STATE], b.infos[keys.STATE])


def test_per_env_options():
    world = make(3)
    colors = [[255, 0, 0], [0, 255, 0], [0, 0, 255]]
    options = [{"variation": ["agent.color"], "variation_values": {"agent.color": c}} for c in colors]
    world.reset(seed=0, options=options)
    assert world.infos["variation.agent.color"][:, -1].tolist() == colors
    with pytest.raises(ConfigError, match="one options dict per env"):
        world.reset(options=options[:2])


def test_history_and_frame_skip():
    world = make(1, history_size=3, frame_skip=2)
    world.set_policy(RandomPolicy(seed=0))
    world.reset(seed=0)
    for _ in range(6):
        world.step()
    assert world.infos[keys.STEP_IDX][0].tolist() == [2, 4, 6]


def test_reset_envs_subset_keeps_other_rows():
    world = make(3)
    world.set_policy(RandomPolicy(seed=0))
    world.reset(seed=0)
    world.step()
    before = world.infos[keys.STATE].copy()
    kept = world.infos
    world.reset_envs([1], seeds=[99])
    assert np.array_equal(world.infos[keys.STATE][[0, 2]], before[[0, 2]])
    assert world.infos[keys.STEP_IDX][:, -1].tolist() == [1, 0, 1]
    assert np.array_equal(kept[keys.STATE], before)  # a batch the caller kept is not modified


def test_determinism_same_seed_same_infos():
    def run():
        world = make(2, seed=3)
        world.set_policy(RandomPolicy(seed=7))
        world.reset(seed=42)
        out = []
        for _ in range(5):
            world.step()
            out.append({k: v.copy() for k, v in world.infos.items() if k != keys.RENDER_TIME})
        return out

    for x, y in zip(run(), run(), strict=False):
        assert x.keys() == y.keys()
        for k in x:
            np.testing.assert_array_equal(x[k], y[k])


def test_sync_and_async_give_identical_infos():
    def run(mode):
        world = make(4, vectorization_mode=mode)
        assert world.envs.mode == mode
        world.set_policy(RandomPolicy(seed=7))
        world.reset(seed=1, options={"variation": ["all"]})
        out = [world.infos]
        for _ in range(4):
            world.step()
            out.append(world.infos)
        world.reset_envs([2, 0], seeds=[5, 6])
        out.append(world.infos)
        world.close()
        return out

    for x, y in zip(run("sync"), run("async"), strict=False):
        assert x.keys() == y.keys()
        for k in x:
            if k != keys.RENDER_TIME:
                np.testing.assert_array_equal(x[k], y[k], err_msg=k)


def test_call_and_call_each():
    for mode in ("sync", "async"):
        world = make(2, vectorization_mode=mode)
        assert world.envs.call("render_size") == [(16, 16), (16, 16)]
        out = world.envs.call_each("eval_state", [(np.zeros(2), np.zeros(2)), (np.zeros(2), np.ones(2))])
        assert out[0][0] is True and out[1][0] is False
        world.close()


class CountingPolicy(RandomPolicy):
    def __init__(self):
        super().__init__(seed=0)
        self.calls = 0

    def get_action(self, infos, **kw):
        self.calls += 1
        return super().get_action(infos)


def test_evaluate_counts_and_seeds():
    world = make(3, max_episode_steps=5)
    world.set_policy(CountingPolicy())
    res = world.evaluate(episodes=7, seed=100, eval_keys=[keys.STATE])
    assert res["episode_successes"].shape == (7,)
    assert res["seeds"].tolist() == list(range(100, 107))
    assert res["episode_count"] == 7
    assert res[keys.STATE].shape == (7, 2)
    assert 0.0 <= res["success_rate"] <= 100.0
    assert res["success_rate"] == pytest.approx(res["episode_successes"].mean() * 100)
    res2 = world.evaluate(episodes=7, seed=100)
    np.testing.assert_array_equal(res["episode_successes"], res2["episode_successes"])
    unseeded = world.evaluate(episodes=5)
    assert len(set(unseeded["seeds"].tolist())) == 5


def test_evaluate_expert_succeeds_truncation_fails():
    world = make(2, max_episode_steps=60)
    world.set_policy(swm.envs.expert_policy(TOY))
    assert world.evaluate(episodes=4, seed=0)["success_rate"] == 100.0
    world = make(2, max_episode_steps=1)
    world.set_policy(swm.envs.expert_policy(TOY))
    res = world.evaluate(episodes=4, seed=0)
    assert res["success_rate"] == 0.0  # one step is never enough: truncated = failure


def test_evaluate_fewer_episodes_than_envs():
    world = make(4, max_episode_steps=3)
    world.set_policy(RandomPolicy(seed=0))
    res = world.evaluate(episodes=2, seed=0)
    assert res["episode_successes"].shape == (2,)


def test_evaluate_unknown_eval_key():
    world = make(1, max_episode_steps=3)
    world.set_policy(RandomPolicy(seed=0))
    with pytest.raises(KeyError, match="stat"):
        world.evaluate(episodes=1, eval_keys=["stat"])


def test_describe_mentions_spaces():
    text = make(1).describe()
    assert TOY in text and "action" in text


def test_goal_shape_of_seed_000():
    world = make(1, goal_shape=(8, 12))
    world.reset(seed=0)
    assert world.infos[keys.PIXELS].shape == (1, 1, 16, 16, 3)
    assert world.infos[keys.GOAL].shape == (1, 1, 8, 12, 3)


def test_evaluate_dump_every_writes_finished_episodes(_stablewm_home):
    import json

    world = make(2, max_episode_steps=4)
    world.set_policy(RandomPolicy(seed=0))
    world.evaluate(episodes=5, seed=7, dump_every=2)
    dump = json.loads((_stablewm_home / "evaluations" / "swm_Toy-v0_7.json").read_text())
    assert dump["episodes_total"] == 5
    assert dump["episodes_done"] == len(dump["seeds"]) == len(dump["successes"]) == 4  # last dump after 4
    assert set(dump["seeds"]) <= set(range(7, 12))


class _ExplodingStep:
    """A wrapper factory whose env fails on the third step."""

    def __call__(self, env):
        import gymnasium as gym

        class Exploding(gym.Wrapper):
            calls = 0

            def step(self, action):
                Exploding.calls += 1
                if Exploding.calls == 3:
                    raise ValueError("boom in the env")
                return self.env.step(action)

        return Exploding(env)


@pytest.mark.parametrize("mode", ["sync", "async"])
def test_env_errors_surface_with_their_message(mode):
    world = make(2, vectorization_mode=mode, extra_wrappers=[_ExplodingStep()])
    world.set_policy(RandomPolicy(seed=0))
    world.reset(seed=0)
    world.step()
    with pytest.raises((ValueError, RuntimeError), match="boom in the env"):
        for _ in range(3):
            world.step()
    world.close()


def test_async_world_close_stops_workers():
    world = make(2, vectorization_mode="async")
    procs = list(world.envs._procs)
    assert all(p.is_alive() for p in procs)
    world.close()
    assert not any(p.is_alive() for p in procs)
    world.close()  # idempotent


@pytest.mark.parametrize("policy", ["random", "noisy expert"])
def test_evaluate_with_a_seed_repeats_exactly_on_the_same_world_and_policy(policy):
    if policy == "random":
        world = make(2, max_episode_steps=8)
        world.set_policy(RandomPolicy(seed=1))
    else:
        world = swm.World("swm/TwoRoom-v2", num_envs=2, image_shape=(16, 16), max_episode_steps=8, verbose=0)
        world.set_policy(swm.envs.expert_policy("swm/TwoRoom-v2", noise=2.0, seed=0))
    first = world.evaluate(episodes=3, seed=5, eval_keys=[keys.STATE])
    world.evaluate(episodes=2)  # moves the policy's stream on
    again = world.evaluate(episodes=3, seed=5, eval_keys=[keys.STATE])
    np.testing.assert_array_equal(first[keys.STATE], again[keys.STATE])
    other = world.evaluate(episodes=3, seed=6, eval_keys=[keys.STATE])
    assert not np.array_equal(first[keys.STATE], other[keys.STATE])


def test_evaluate_upstream_keywords(tmp_path):
    world = make(2, max_episode_steps=4)
    world.set_policy(RandomPolicy(seed=0))
    res = world.evaluate(episodes=3, seed=1, video=tmp_path / "v")
    assert res["episode_count"] == 3
    assert sorted(p.name for p in (tmp_path / "v").iterdir()) == ["episode_0.mp4", "episode_1.mp4", "episode_2.mp4"]
    assert world.evaluate(episodes=None, seed=1)["episode_count"] == 2  # None: one per env
    with pytest.raises(ConfigError, match="reset_mode"):
        world.evaluate(episodes=2, reset_mode="sometimes")
    with pytest.raises(ConfigError, match="one episode per env"):
        world.evaluate(episodes=3, reset_mode="wait")
    with pytest.raises(ConfigError, match="requires episodes_idx, start_steps"):
        world.evaluate(dataset="x", goal_offset=1, eval_budget=2)


def test_evaluate_with_a_dataset_is_evaluate_from_dataset(tmp_path):
    from stable_worldmodel.envs.toy.env import ToyExpert

    world = make(2, max_episode_steps=40)
    world.set_policy(ToyExpert())
    world.record_dataset("toy", episodes=2, seed=3, cache_dir=tmp_path)
    ds = swm.data.HDF5Dataset("toy", cache_dir=tmp_path)
    res = world.evaluate(dataset=ds, episodes_idx=[0, 1], start_steps=[0, 1], goal_offset=3, eval_budget=10)
    assert res["episode_successes"].tolist() == [True, True]


def test_upstream_world_arguments_do_not_reach_the_env():
    calls = []

    def pre(env):
        calls.append(("pre", type(env).__name__))
        return env

    def extra(env):
        calls.append(("extra", type(env).__name__))
        return env

    world = swm.World(
        TOY,
        num_envs=1,
        image_shape=(8, 8),
        pre_wrappers=[pre],
        extra_wrappers=[extra],
        image_resample="nearest",
        vectorization_mode="sync",
        verbose=0,
    )
    assert [c[0] for c in calls] == ["pre", "extra"] and calls[1][
        1
    ] == "MegaWrapper"  # extra wraps MegaWrapper, as 0.0.3
    world.set_policy(RandomPolicy(seed=0))
    world.reset(seed=0)
    bare = swm.World(TOY, num_envs=1, add_pixels=False, vectorization_mode="sync", verbose=0)
    bare.set_policy(RandomPolicy(seed=0))
    bare.reset(seed=0)
    bare.step()
    assert keys.PIXELS not in bare.infos and keys.STATE in bare.infos
    with pytest.raises(ConfigError, match="requires image_shape"):
        swm.World(TOY, num_envs=1)


class _GoalLess(__import__("gymnasium").Env):
    """An env with no goal at all (like most Gymnasium envs)."""

    def __init__(self, render_mode=None):
        import gymnasium as gym

        self.observation_space = gym.spaces.Box(-1, 1, (2,), np.float32)
        self.action_space = gym.spaces.Box(-1, 1, (2,), np.float32)
        self.render_mode = render_mode

    def reset(self, *, seed=None, options=None):
        super().reset(seed=seed)
        return np.zeros(2, np.float32), {}

    def step(self, action):
        return np.zeros(2, np.float32), 0.0, False, False, {}

    def render(self):
        return np.zeros((8, 8, 3), np.uint8)


def test_goal_less_env_works_with_the_default_goal_conditioned():
    swm.envs.register(id="swm/CompatGoalLess-v0", entry_point=_GoalLess)
    world = swm.World("swm/CompatGoalLess-v0", num_envs=1, image_shape=(8, 8), vectorization_mode="sync", verbose=0)
    world.set_policy(RandomPolicy(seed=0))
    world.reset(seed=0)
    world.step()
    assert keys.GOAL not in world.infos and world.infos[keys.PIXELS].shape == (1, 1, 8, 8, 3)


def test_render_bound_envs_are_the_mujoco_ones():
    from stable_worldmodel.world.world import render_bound

    assert render_bound("swm/OGBCube-v0") and render_bound("swm/CartpoleDMControl-v0")
    assert not render_bound(TOY) and not render_bound("swm/PushT-v1") and not render_bound("no/such-env")

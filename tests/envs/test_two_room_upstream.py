"""``swm/TwoRoom-v1`` keeps upstream 0.1.1's meaning (issue 13); ours is ``swm/TwoRoom-v2``.

Reference numbers were recorded once from 0.1.1's env by ``data/record_two_room_v1.py``; these
tests replay them: same factor draws for a seed, same trajectories, frames within 1 level.
"""

from __future__ import annotations

from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest

import stable_worldmodel as swm
from stable_worldmodel import keys
from stable_worldmodel.envs.two_room import ExpertPolicy, TwoRoomExpert, TwoRoomV1Env, TwoRoomV1Expert
from stable_worldmodel.errors import ConfigError

REF = np.load(Path(__file__).parent / "data" / "two_room_v1_upstream.npz")
CASES = {
    "default": None,
    "doors": {
        "variation": [
            "agent.position",
            "target.position",
            "door.number",
            "door.size",
            "door.position",
            "agent.radius",
            "agent.speed",
        ]
    },
    "all": {"variation": ["all"]},
    "horizontal": {
        "variation": ["target.position"],
        "variation_values": {"wall.axis": 0, "agent.position": [60.0, 40.0]},
    },
}
RUNS = [(case, seed) for case in CASES for seed in (0, 3)]
FACTORS = {  # name -> (type, shape, low, high, default) as upstream 0.1.1 builds them
    "agent.color": ("RGBBox", (3,), 0, 255, [255, 0, 0]),
    "agent.radius": ("Box", (1,), 7.0, 14.0, [7.0]),
    "agent.position": ("Box", (2,), 14.0, 209.0, [60.0, 112.0]),
    "agent.speed": ("Box", (1,), 1.75, 10.5, [5.0]),
    "target.color": ("RGBBox", (3,), 0, 255, [0, 255, 0]),
    "target.radius": ("Box", (1,), 7.0, 14.0, [7.0]),
    "target.position": ("Box", (2,), 14.0, 209.0, [164.0, 112.0]),
    "wall.color": ("RGBBox", (3,), 0, 255, [0, 0, 0]),
    "wall.thickness": ("Discrete", (), 7, 41, 10),
    "wall.axis": ("Discrete", (), 0, 1, 1),
    "wall.border_color": ("RGBBox", (3,), 0, 255, [0, 0, 0]),
    "door.color": ("RGBBox", (3,), 0, 255, [255, 255, 255]),
    "door.number": ("Discrete", (), 1, 3, 1),
    "door.size": ("MultiDiscrete", (3,), 1, 21, [14, 14, 14]),
    "door.position": ("MultiDiscrete", (3,), 0, 223, [49, 49, 49]),
    "background.color": ("RGBBox", (3,), 0, 255, [255, 255, 255]),
    "rendering.render_target": ("Discrete", (), 0, 1, 0),
    "task.min_steps": ("Discrete", (), 15, 114, 25),
}


def make(**kwargs) -> gym.Env:
    return gym.make("swm/TwoRoom-v1", disable_env_checker=True, **kwargs)


def test_registration_and_spaces():
    env = make()
    assert isinstance(env.unwrapped, TwoRoomV1Env)
    assert env.spec.max_episode_steps is None  # upstream registers no limit (swm tools cut at 100 steps)
    assert env.observation_space.shape == (10,) and env.observation_space.dtype == np.float32
    assert env.observation_space.low.min() == 0 and env.observation_space.high.max() == 224
    assert env.action_space.shape == (2,)
    np.testing.assert_array_equal(env.action_space.low, [-1, -1])
    gym.make("swm/TwoRoom-v2", disable_env_checker=True)  # ours lives on as v2


def test_factor_names_ranges_defaults():
    vs = make().unwrapped.variation_space
    assert sorted(vs.names()) == sorted(FACTORS)
    for name, (kind, shape, low, high, default) in FACTORS.items():
        group, leaf = name.split(".")
        space = vs[group][leaf]
        assert type(space).__name__ == kind, name
        if kind == "Discrete":
            assert (int(space.start), int(space.start + space.n - 1)) == (low, high), name
        elif kind == "MultiDiscrete":
            assert tuple(space.shape) == shape and int(space.start.min()) == low, name
            assert int((space.start + space.nvec - 1).max()) == high, name
        else:
            assert tuple(space.shape) == shape, name
            np.testing.assert_allclose(space.low, low, err_msg=name)
            np.testing.assert_allclose(space.high, high, err_msg=name)
        np.testing.assert_allclose(np.asarray(space.init_value, np.float64), default, err_msg=name)


@pytest.mark.parametrize(("case", "seed"), RUNS)
def test_replays_upstream(case, seed):
    """Same factors, same trajectory and frames within one uint8 level of 0.1.1's for a seed."""
    name = f"{case}_seed{seed}"
    env = make()
    obs, info = env.reset(seed=seed, options=CASES[case])
    vs = env.unwrapped.variation_space
    for key in (
        "agent.radius",
        "agent.speed",
        "wall.axis",
        "wall.thickness",
        "door.number",
        "door.size",
        "door.position",
        "agent.color",
    ):
        group, leaf = key.split(".")
        np.testing.assert_array_equal(np.asarray(vs[group][leaf].value), REF[f"{name}/{key}"], err_msg=key)
    states, terms, frames = [obs], [], [env.render()]
    for t, action in enumerate(REF[f"{name}/actions"], 1):
        obs, reward, terminated, truncated, info = env.step(action)
        assert reward == 0.0 and not truncated
        states.append(obs)
        terms.append(terminated)
        if t in (15, 30):
            frames.append(env.render())
    np.testing.assert_array_equal(np.stack(states), REF[f"{name}/obs"])
    np.testing.assert_array_equal(terms, REF[f"{name}/terminated"])
    for ours, theirs in ((np.stack(frames), REF[f"{name}/frames"]), (info[keys.GOAL], REF[f"{name}/goal"])):
        diff = np.abs(ours.astype(int) - theirs.astype(int))
        assert diff.max() <= 1 and (diff > 0).mean() < 1e-3


def test_small_frames_are_upstreams_world_frames():
    """At 64 px the frames are what upstream's World makes of its 224-px frames (PIL bilinear)."""
    from PIL import Image

    env = TwoRoomV1Env()
    env.set_render_size((64, 64))
    env.reset(seed=0, options=CASES["default"])
    theirs = REF["default_seed0/frames"][0]  # upstream's first frame of this reset, 224 px
    expected = np.asarray(Image.fromarray(theirs).resize((64, 64), Image.BILINEAR)).astype(int)
    assert np.abs(env.render().astype(int) - expected).mean() < 0.05


def test_route_through_the_door_replays_upstream():
    env = make()
    env.reset(seed=0, options={"state": np.float32([60, 150]), "target_state": np.float32([170, 60])})
    out = [env.step(a) for a in REF["route/actions"]]
    np.testing.assert_array_equal(np.stack([o[0] for o in out]), REF["route/obs"])
    np.testing.assert_array_equal([o[2] for o in out], REF["route/terminated"])
    assert out[11][0][0] == 99.5  # stopped 0.5 px before the wall band grown by the radius
    assert out[-1][4]["distance_to_target"] < 16.0


def test_info_and_goal_image():
    env = make()
    _, info = env.reset(seed=1)
    assert {
        "env_name",
        keys.STATE,
        keys.PROPRIO,
        keys.GOAL_STATE,
        keys.GOAL_PROPRIO,
        keys.GOAL,
        "distance_to_target",
    } <= set(info)
    assert info[keys.GOAL].shape == (224, 224, 3)
    # the goal image is the frame with the agent at the target
    env.unwrapped._set_state(info[keys.GOAL_STATE])
    np.testing.assert_array_equal(env.render(), info[keys.GOAL])
    env.unwrapped.set_render_size((32, 32))
    _, info = env.reset(seed=1)
    assert env.render().shape == info[keys.GOAL].shape == (32, 32, 3)


def test_unseeded_reset_follows_the_env_seed():
    """Deliberate fix: upstream reseeds the factors from fresh entropy on reset() without a seed."""
    a, b = make(), make()
    a.reset(seed=5)
    b.reset(seed=5)
    np.testing.assert_array_equal(a.reset()[0], b.reset()[0])


def test_bad_state_option_is_refused():
    with pytest.raises(ConfigError, match="'state' with at least 2 numbers"):
        make().reset(seed=0, options={"state": [1.0]})


def test_expert_reaches_every_target():
    world = swm.World("swm/TwoRoom-v1", num_envs=4, image_shape=(16, 16), max_episode_steps=100, verbose=0)
    world.set_policy(TwoRoomV1Expert(noise=0.5, seed=0))
    assert world.evaluate(episodes=20, seed=0)["success_rate"] == 100.0
    assert swm.envs.expert_policy("swm/TwoRoom-v1").__class__ is TwoRoomV1Expert


@pytest.mark.parametrize(
    ("env_id", "controller"), [("swm/TwoRoom-v1", TwoRoomV1Expert), ("swm/TwoRoom-v2", TwoRoomExpert)]
)
def test_upstream_expert_name_drives_the_env_it_is_set_on(env_id, controller):
    world = swm.World(env_id, num_envs=2, image_shape=(16, 16), max_episode_steps=100, verbose=0)
    policy = ExpertPolicy(seed=0, door_reach_tol=12.0)
    world.set_policy(policy)
    assert type(policy._controller) is controller
    assert world.evaluate(episodes=6, seed=0)["success_rate"] == 100.0


def _full_frame(env, agent_xy) -> np.ndarray:
    """A frame drawn from scratch at 224 px and resized whole: no cached layer."""
    v = env.variation_space
    img = env._draw_static()
    env._blend_dot(img, env.target_position, v["target"]["radius"].value, v["target"]["color"].value)
    env._blend_dot(img, np.asarray(agent_xy, np.float32), v["agent"]["radius"].value, v["agent"]["color"].value)
    return env._sized(img)


# 64 and 32x56 / 128x112 take the redraw (scales 3.5, 7 x 4, 1.75 x 2); 96 resizes whole frames
@pytest.mark.parametrize("size", [(64, 64), (32, 56), (128, 112), (96, 96), (224, 224)])
def test_frames_redrawn_around_the_dot_equal_full_frames(size):
    """A frame redraws only the output pixels the agent's dot reaches; the result equals resizing
    the whole 224-px frame, bit for bit, for dots at the border, in the door, with the target
    shown, and after the goal moves."""
    env = TwoRoomV1Env(render_target=True)
    env.set_render_size(size)
    env.reset(seed=1, options={"variation": ["all"]})
    rng = np.random.default_rng(0)
    places = [(14.0, 14.0), (209.9, 14.0), (112.0, 112.0), (0.3, 223.7), *rng.uniform(10, 214, (12, 2))]
    for i, xy in enumerate(places):
        if i == 8:
            env._set_goal_state(np.array([40.0, 180.0], np.float32))  # a new goal: the layer under the dot changes
        env.agent_position = np.asarray(xy, np.float32)
        np.testing.assert_array_equal(env.render(), _full_frame(env, xy))
    v = env.variation_space
    goal = env._draw_static()  # the goal image: the agent drawn at the target, over the target dot
    env._blend_dot(goal, env.target_position, v["target"]["radius"].value, v["target"]["color"].value)
    env._blend_dot(goal, env.target_position, v["agent"]["radius"].value, v["agent"]["color"].value)
    np.testing.assert_array_equal(env._get_info()["goal"], env._sized(goal))
    assert env._get_info()["goal"] is not env._get_info()["goal"]  # callers may write into it

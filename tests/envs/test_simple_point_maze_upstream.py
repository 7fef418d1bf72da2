"""``swm/SimplePointMaze-v0`` keeps release 0.1.1's meaning (issue 13).

Reference numbers were recorded once from 0.1.1's env by ``data/record_simple_point_maze_v0.py``
(frames shrunk from its 500 x 500 matplotlib frames with ``cv2.INTER_AREA``); these tests replay them.
"""

from __future__ import annotations

from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest

from stable_worldmodel import keys
from stable_worldmodel.envs.simple_point_maze.v0 import LAYOUT, SimplePointMazeV0Env
from stable_worldmodel.envs.simple_point_maze.v0_expert import SimplePointMazeV0Expert

REF = np.load(Path(__file__).parent / "data" / "simple_point_maze_v0_upstream.npz")
MAX_MAD = 3.0  # mean absolute difference allowed between frames, in uint8 levels (3/255)
SEED_CASES = [("default", None, 0), ("default", None, 3), ("all", ["all"], 0), ("all", ["all"], 3)]

# factor -> (type, shape, low, high, default) of 0.1.1 (walls.positions/shape bounds checked separately)
FACTORS = {
    "agent.color": ("RGBBox", (3,), 0, 255, [255, 0, 0]),
    "agent.position": ("Box", (2,), 0.0, 5.0, [0.5, 0.5]),
    "agent.radius": ("Box", (), 0.05, 0.5, 0.1),
    "agent.speed": ("Box", (), 0.05, 2.0, 1.0),
    "background.color": ("RGBBox", (3,), 0, 255, [255, 255, 255]),
    "goal.color": ("RGBBox", (3,), 0, 255, [0, 255, 0]),
    "goal.position": ("Box", (2,), 0.0, 5.0, [4.5, 4.5]),
    "goal.radius": ("Box", (), 0.05, 0.5, 0.2),
    "walls.color": ("RGBBox", (3,), 0, 255, [0, 0, 0]),
    "walls.number": ("Discrete", (), 4, 6, 5),
    "walls.positions": ("Box", (6, 2), 0.0, 5.0, None),
    "walls.shape": ("Box", (6, 2), 0.5, 1.5, None),
}
WALLS_POSITIONS_0 = [[1.035264492034912, 3.455474853515625], [3.002354621887207, 3.4422965049743652]]
WALLS_SHAPE_0 = [[1.289385199546814, 0.8406872749328613], [1.2444018125534058, 1.0428158044815063]]


def mad(a, b) -> float:
    return float(np.abs(np.asarray(a, np.float64) - np.asarray(b, np.float64)).mean())


@pytest.fixture(scope="module")
def env():
    e = SimplePointMazeV0Env(render_size=64)
    yield e
    e.close()


def test_spaces_and_registration():
    e = gym.make("swm/SimplePointMaze-v0", disable_env_checker=True).unwrapped
    assert isinstance(e, SimplePointMazeV0Env)
    assert isinstance(e.observation_space, gym.spaces.Box) and e.observation_space.shape == (2,)
    assert e.observation_space.dtype == np.float32
    np.testing.assert_array_equal(e.observation_space.low, [0, 0])
    np.testing.assert_array_equal(e.observation_space.high, [5, 5])
    assert e.action_space.shape == (2,) and e.action_space.dtype == np.float32
    np.testing.assert_array_equal(e.action_space.low, np.float32([-0.2, -0.2]))
    np.testing.assert_array_equal(e.action_space.high, np.float32([0.2, 0.2]))


def test_factor_names_ranges_defaults(env):
    vs = env.variation_space
    assert sorted(vs.names()) == sorted(FACTORS)
    for name, (kind, shape, low, high, default) in FACTORS.items():
        group, leaf = name.split(".")
        space = vs[group][leaf]
        assert type(space).__name__ == kind, name
        assert tuple(space.shape) == shape, name
        if kind == "Discrete":
            assert (int(space.start), int(space.start + space.n - 1)) == (low, high), name
        else:
            np.testing.assert_allclose(space.low, low, rtol=1e-6, err_msg=name)
            np.testing.assert_allclose(space.high, high, rtol=1e-6, err_msg=name)
        if default is not None:
            np.testing.assert_allclose(np.asarray(space.init_value, np.float64), default, rtol=1e-6, err_msg=name)
    np.testing.assert_array_equal(vs["walls"]["positions"].init_value[:2], np.float32(WALLS_POSITIONS_0))
    np.testing.assert_array_equal(vs["walls"]["shape"].init_value[:2], np.float32(WALLS_SHAPE_0))


def _play(env, name):
    states, rewards, terms, frames = [np.asarray(env.state, np.float64)], [], [], {0: env.render()}
    steps = set(REF[name + "/frame_steps"].tolist())
    for t, a in enumerate(REF[name + "/actions"], 1):
        obs, r, term, trunc, info = env.step(a)
        assert not trunc and set(info) >= {keys.GOAL, keys.STATE, keys.PROPRIO, keys.GOAL_STATE, keys.GOAL_PROPRIO}
        states.append(np.asarray(obs, np.float64))
        rewards.append(r)
        terms.append(term)
        if t in steps:
            frames[t] = env.render()
    np.testing.assert_array_equal(np.array(states), REF[name + "/states"])
    np.testing.assert_array_equal(np.array(rewards), REF[name + "/rewards"])
    np.testing.assert_array_equal(np.array(terms), REF[name + "/terminated"])
    for k, t in enumerate(sorted(frames)):
        assert mad(frames[t], REF[name + "/frames64"][k]) <= MAX_MAD, (name, t)
    env.set_render_size((224, 224))
    assert mad(env.render(), REF[name + "/frame224"]) <= MAX_MAD, name
    env.set_render_size((64, 64))


@pytest.mark.parametrize("case,variation,seed", SEED_CASES)
def test_seeded_reset_and_rollout_match(env, case, variation, seed):
    name = f"{case}_seed{seed}"
    obs, info = env.reset(seed=seed, options=None if variation is None else {"variation": variation})
    assert obs.dtype == np.float32 and obs.shape == (2,)
    np.testing.assert_array_equal(obs, REF[name + "/obs0"])
    v = env.variation_space
    np.testing.assert_array_equal(v["walls"]["positions"].value, REF[name + "/walls_positions"])
    assert int(v["walls"]["number"].value) == int(REF[name + "/walls_number"])
    np.testing.assert_array_equal(v["agent"]["radius"].value, REF[name + "/agent_radius"])
    np.testing.assert_array_equal(v["goal"]["position"].value, REF[name + "/goal_position"])
    assert mad(info[keys.GOAL], REF[name + "/goal64"]) <= MAX_MAD
    np.testing.assert_array_equal(info[keys.GOAL_STATE], REF[name + "/goal_position"])
    _play(env, name)
    env.set_render_size((224, 224))
    env.reset(seed=seed, options=None if variation is None else {"variation": variation})
    assert mad(env._goal_img, REF[name + "/goal224"]) <= MAX_MAD
    env.set_render_size((64, 64))


@pytest.mark.parametrize("name", ["line", "reach"])
def test_fixed_state_rollout_matches(env, name):
    """A straight push that ends against a wall (the agent stays put) and one that reaches the goal (reward 1)."""
    env.reset(seed=0, options={"variation": [], "state": REF[name + "/start"], "goal_state": REF[name + "/goal"]})
    _play(env, name)


def test_success_rule_and_eval_state(env):
    env.reset(seed=0, options={"variation": []})
    radius = float(env.variation_space["goal"]["radius"].value)
    assert env.eval_state(np.array([4.5, 4.5]), np.array([4.5, 4.5 - 0.99 * radius]))[0]
    ok, dist = env.eval_state(np.array([4.5, 4.5]), np.array([4.5, 4.5 - 1.01 * radius]))
    assert not ok and dist == pytest.approx(1.01 * radius, rel=1e-5)


def test_expert_reaches_default_goals(env):
    expert = SimplePointMazeV0Expert()
    env.set_render_size((8, 8))
    solved = 0
    for seed in range(5):
        obs, info = env.reset(seed=seed)
        for _ in range(60):
            a = expert.get_action({k: np.asarray(info[k])[None, None] for k in (keys.STATE, keys.GOAL_STATE, LAYOUT)})
            obs, r, term, _, info = env.step(a[0])
            if term:
                solved += 1
                break
    env.set_render_size((64, 64))
    assert solved == 5


@pytest.mark.parametrize("size", [500, 64, 96])
def test_frames_blended_into_the_cached_layer_match_matplotlib(size):
    """Matplotlib draws the layer under the agent once per scene and the agent is blended in (64
    also redraws only the area-resize blocks under it; 96 resizes whole frames): within 0.005/255
    mean absolute difference of drawing every frame with matplotlib (measured: 0.0015), differing
    only on the disk's edge pixels and by at most 32 levels there (Agg's coverage is exact, ours is
    by distance), also with the agent under the axes frame and after the scene changes."""
    env = SimplePointMazeV0Env(render_size=size)
    rng = np.random.default_rng(0)
    states = [(0.0, 0.0), (5.0, 2.5), (2.5, 5.0), (4.98, 0.01), *rng.uniform(0, 5, (6, 2))]
    for seed, variation in ((0, None), (1, ["all"])):
        env.reset(seed=seed, options=None if variation is None else {"variation": variation})
        v = env.variation_space
        for xy in states:
            scene = {
                "background": v["background"]["color"].value,
                "walls": [tuple(w) for w in env._walls()],
                "wall_color": v["walls"]["color"].value,
                "goal": (v["goal"]["position"].value, v["goal"]["radius"].value, v["goal"]["color"].value),
                "agent": (np.asarray(xy, np.float64), v["agent"]["radius"].value, v["agent"]["color"].value),
            }
            fast = env._canvas.draw(scene, (size, size))
            full = env._canvas.draw_full(scene, (size, size))
            diff = np.abs(fast.astype(int) - full)
            assert diff.mean() <= 0.005 and diff.max() <= 32, (seed, xy, diff.mean(), diff.max())
            rows, cols = np.nonzero(diff.max(-1))
            if len(rows):  # only next to the agent's disk edge
                centre = np.array([(5.0 - xy[1]) / 5.0 * size, xy[0] / 5.0 * size])
                reach = (float(v["agent"]["radius"].value) / 5.0 + 0.02) * size + 2
                assert np.hypot(rows + 0.5 - centre[0], cols + 0.5 - centre[1]).max() <= reach, (seed, xy)
    env.close()

"""Env ids keep upstream's meaning (issue 13): facts observed on release 0.0.3 and upstream 0.1.1.

The reference numbers below were recorded by running the original packages side by side with
ours from the same states and actions; the tests replay them without the originals.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest

pytest.importorskip("pymunk")
pytest.importorskip("cv2")

import stable_worldmodel as swm  # noqa: E402  (registers the swm/... ids)
from stable_worldmodel import keys  # noqa: E402
from stable_worldmodel.envs.pusht import PushT, PushTDiscrete  # noqa: E402
from stable_worldmodel.envs.pusht.env import BLOCK_POSE, GOAL_POSE, N_CONTACTS, POS_AGENT, VEL_AGENT  # noqa: E402
from stable_worldmodel.envs.two_room.v0 import TwoRoomV0Env  # noqa: E402
from stable_worldmodel.envs.two_room.v0_overlap import overlap_fractions  # noqa: E402

# -- PushT (upstream 0.1.1) -----------------------------------------------------------------------
PUSHT_GOAL = np.array([256.0, 200.0, 256.0, 256.0, math.pi / 4, 0.0, 0.0])
PUSH_START = np.array([256.0, 210.0, 256.0, 256.0, 0.0, 0.0, 0.0])
# upstream 0.1.1 after 15 steps of (0, 0.4) from PUSH_START: state and n_contacts of each step
UP_PUSH_FINAL = np.array([256.0, 449.7377786255, 223.5482835917, 426.8226972387, 1.00084269, 0.0, 148.6848907471])
UP_PUSH_CONTACTS = [0, 0, 1, 1, 1, 1, 1, 1, 1, 1, 3, 2, 2, 2, 2]


def _pusht(cls=PushT, start=PUSH_START):
    env = cls(render_size=(32, 32))
    obs, info = env.reset(seed=0, options={keys.STATE: start, keys.GOAL_STATE: PUSHT_GOAL})
    return env, obs, info


def _check_pusht_info(obs, info, block_angle):
    s = obs[keys.STATE]
    for key, shape in ((POS_AGENT, (2,)), (VEL_AGENT, (2,)), (BLOCK_POSE, (3,)), (GOAL_POSE, (3,))):
        assert info[key].shape == shape and info[key].dtype == np.float64, key
    np.testing.assert_array_equal(info[POS_AGENT], s[0:2])
    np.testing.assert_array_equal(info[VEL_AGENT], s[5:7])
    np.testing.assert_allclose(info[BLOCK_POSE], [s[2], s[3], block_angle])  # angle not wrapped
    np.testing.assert_allclose(info[GOAL_POSE], [256.0, 256.0, math.pi / 4])  # where the goal silhouette is
    assert isinstance(info[N_CONTACTS], int)


@pytest.mark.parametrize("cls", [PushT, PushTDiscrete])
def test_pusht_info_has_upstream_keys(cls):
    start = PUSH_START.copy()
    start[4] = 7.0  # beyond 2 pi: state[4] wraps, block_pose keeps pymunk's angle
    env, obs, info = _pusht(cls, start)
    assert obs[keys.STATE][4] == pytest.approx(7.0 - 2 * math.pi)
    _check_pusht_info(obs, info, 7.0)
    assert info[N_CONTACTS] == 0
    action = np.zeros(2, np.float32) if cls is PushT else np.array([5, 5])
    obs, _, _, _, info = env.step(action)
    _check_pusht_info(obs, info, 7.0)


def test_pusht_push_matches_upstream_trajectory_and_contacts():
    env, _, _ = _pusht()
    contacts = []
    for _ in range(15):
        obs, *_, info = env.step(np.array([0.0, 0.4], np.float32))
        contacts.append(info[N_CONTACTS])
    # upstream forms the PD target in float32 (action * 100), we in float64: ~1e-4 px apart
    np.testing.assert_allclose(obs[keys.STATE], UP_PUSH_FINAL, rtol=0, atol=1e-3)
    assert contacts == UP_PUSH_CONTACTS


def test_pusht_render_goal_factor_of_upstream():
    env = PushT(render_size=(64, 64))
    assert "rendering.render_goal" in env.variation_space.names()
    green = np.array([144, 238, 144])

    def goal_pixels(render_goal):
        env.reset(seed=0, options={keys.VARIATION_VALUES: {"rendering.render_goal": render_goal}})
        return int(np.all(env.render() == green, axis=-1).sum())

    assert int(env.variation_space["rendering"]["render_goal"].value) == 1
    assert goal_pixels(1) > 20 and goal_pixels(0) == 0


# upstream 0.1.1's gym.make("swm/PushT-v1").reset(seed=s): (obs["state"], info["goal_state"]) rounded to 1e-4
UP_SEEDED_RESETS = {
    0: (
        [235.7827, 303.6074, 383.7718, 318.036, 4.9695, 0.0, 0.0],
        [449.7421, 228.0397, 151.3813, 309.2775, 0.2837, 0.0, 0.0],
    ),
    3: (
        [138.4352, 362.7003, 130.6711, 234.4672, 1.4122, 0.0, 0.0],
        [352.3057, 98.8365, 346.6426, 163.293, 5.061, 0.0, 0.0],
    ),
}


@pytest.mark.parametrize("seed", sorted(UP_SEEDED_RESETS))
def test_pusht_v1_seed_draws_upstream_start_and_goal(seed):
    obs, info = gym.make("swm/PushT-v1", disable_env_checker=True).reset(seed=seed)
    state, goal = UP_SEEDED_RESETS[seed]
    np.testing.assert_allclose(obs[keys.STATE], state, atol=1e-4)
    np.testing.assert_allclose(info[keys.GOAL_STATE], goal, atol=1e-4)


def test_pusht_v1_all_factors_drawn_as_upstream():
    env = gym.make("swm/PushT-v1", disable_env_checker=True)
    obs, _ = env.reset(seed=7, options={"variation": ["all"]})
    vs = env.unwrapped.variation_space
    assert vs["agent"]["color"].value.tolist() == [229, 204, 43] and int(vs["block"]["shape"].value) == 3
    np.testing.assert_allclose(
        obs[keys.STATE], [176.2336, 116.8658, 390.8437, 302.4224, 5.9023, 186.3105, 323.2808], atol=1e-4
    )


def test_pusht_v1_unseeded_reset_follows_the_env_seed():
    """Deliberate fix: upstream reseeds the factors from fresh entropy on reset() without a seed."""
    a, b = (gym.make("swm/PushT-v1", disable_env_checker=True) for _ in range(2))
    a.reset(seed=5)
    b.reset(seed=5)
    np.testing.assert_array_equal(a.reset()[0][keys.STATE], b.reset()[0][keys.STATE])


# -- TwoRoom-v0 (release 0.0.3) ---------------------------------------------------------------------
V0_FACTORS = {  # name: default of 0.0.3
    "agent.color": [255, 0, 0],
    "agent.radius": [15.0],
    "agent.position": [50.0, 50.0],
    "agent.max_energy": 100,
    "agent.speed": [10.0],
    "goal.color": [0, 255, 0],
    "goal.radius": [15.0],
    "goal.position": [450.0, 450.0],
    "wall.color": [115, 127, 145],
    "wall.thickness": 19,
    "wall.axis": 1,
    "wall.border_color": [180, 189, 204],
    "door.color": [255, 255, 255],
    "door.number": 1,
    "door.size": [75, 75, 75],
    "door.position": [247, 247, 247],
    "background.color": [255, 255, 255],
}
# 0.0.3 with the default layout: start, goal, actions -> final state, terminated per step
V0_RUNS = {
    "wall": ([150, 100], [400, 300], [1.0, 0.0], 20, [238.9187743963, 100.0, 400.0, 300.0, 80.0, 10.0], False),
    "door": ([150, 247], [400, 247], [1.0, 0.0], 20, [238.9187743963, 247.0, 400.0, 247.0, 80.0, 10.0], False),
    "slide": ([200, 100], [400, 300], [1.0, 0.3], 20, [238.9237462433, 160.0, 400.0, 300.0, 80.0, 10.0], False),
    "near": ([385, 300], [400, 300], [0.4, 0.0], 3, [397.0, 300.0, 400.0, 300.0, 97.0, 10.0], True),
}
UP_NEAR_FRACTIONS = [0.5434886215028857, 0.7053920771706806, 0.872784787456714]
UP_WALL_CONTACTS = [0] * 7 + [1] * 13
# 0.0.3's last "wall" frame at 64x64, grey level averaged over 8x8 blocks
UP_WALL_FRAME_BLOCKS = [
    [240.0, 247.0, 247.0, 217.8, 247.0, 247.0, 247.0, 240.0],
    [247.0, 255.0, 255.0, 204.2, 255.0, 255.0, 255.0, 247.0],
    [247.0, 255.0, 255.0, 222.0, 255.0, 255.0, 255.0, 247.0],
    [247.0, 255.0, 255.0, 222.0, 255.0, 255.0, 255.0, 247.0],
    [247.0, 255.0, 255.0, 255.0, 255.0, 255.0, 225.8, 247.0],
    [247.0, 255.0, 255.0, 229.8, 255.0, 255.0, 255.0, 247.0],
    [247.0, 255.0, 255.0, 222.0, 255.0, 255.0, 255.0, 247.0],
    [240.0, 247.0, 247.0, 218.2, 247.0, 247.0, 247.0, 240.0],
]


def _v0(start, goal, size=64, values=None):
    env = TwoRoomV0Env(render_size=size)
    options = {keys.VARIATION: [], keys.STATE: np.array(start, float), keys.GOAL_STATE: np.array(goal, float)}
    if values:
        options[keys.VARIATION_VALUES] = values
    obs, info = env.reset(seed=0, options=options)
    return env, obs, info


def test_two_room_v0_is_registered_with_0_0_3_spaces_and_factors():
    env = gym.make("swm/TwoRoom-v0", disable_env_checker=True).unwrapped
    assert isinstance(env, TwoRoomV0Env)
    state, proprio = env.observation_space[keys.STATE], env.observation_space[keys.PROPRIO]
    np.testing.assert_array_equal(state.low, [9, 9, 9, 9, 50, 0.5])
    np.testing.assert_array_equal(state.high, [494, 494, 494, 494, 200, 20])
    np.testing.assert_array_equal(proprio.low, [9, 9, 0, 10])
    np.testing.assert_array_equal(proprio.high, [494, 494, 200, 20])
    assert env.action_space == gym.spaces.Box(-1.0, 1.0, (2,), np.float32)
    assert sorted(env.variation_space.names()) == sorted(V0_FACTORS)
    for name, default in V0_FACTORS.items():
        group, leaf = name.split(".")
        init = np.asarray(env.variation_space[group][leaf].init_value, float)
        np.testing.assert_allclose(init, default, err_msg=name)
    speed = env.variation_space["agent"]["speed"]
    assert (float(speed.low[0]), float(speed.high[0])) == (10.0, 20.0)
    size = env.variation_space["door"]["size"]
    np.testing.assert_array_equal(size.start, [35] * 3)
    np.testing.assert_array_equal(size.nvec, [50] * 3)


@pytest.mark.parametrize("name", sorted(V0_RUNS))
def test_two_room_v0_matches_0_0_3_trajectories(name):
    start, goal, action, steps, final, success = V0_RUNS[name]
    env, obs, info = _v0(start, goal)
    assert set(info) >= {
        "pos_agent",
        "pos_goal",
        "n_contacts",
        "goal_pos",
        keys.GOAL,
        "energy",
        "max_energy",
        "fraction_of_goal",
        "fraction_of_agent",
        keys.GOAL_STATE,
        keys.GOAL_PROPRIO,
    }
    np.testing.assert_array_equal(obs[keys.PROPRIO], obs[keys.STATE][[0, 1, 4, 5]])
    terms, rewards = [], []
    for _ in range(steps):
        obs, reward, term, trunc, info = env.step(np.array(action, np.float32))
        terms.append(term)
        rewards.append(reward)
        assert not trunc
    np.testing.assert_allclose(obs[keys.STATE], final, rtol=0, atol=1e-9)
    assert terms == [success] * steps and rewards == [1.0 if success else -0.01] * steps
    np.testing.assert_array_equal(info["pos_agent"], obs[keys.STATE][:2])
    assert info["energy"] == 100 - steps and info["max_energy"] == 100


def test_two_room_v0_success_fractions_and_contacts_as_0_0_3():
    env, _, info = _v0([385, 300], [400, 300])
    assert info["fraction_of_goal"] == 0.0 and info["fraction_of_agent"] == 0.0
    for expected in UP_NEAR_FRACTIONS:
        *_, info = env.step(np.array([0.4, 0.0], np.float32))
        assert info["fraction_of_goal"] == pytest.approx(expected, abs=1e-9)
        assert info["fraction_of_agent"] == pytest.approx(expected, abs=1e-9)
    env, _, _ = _v0([150, 100], [400, 300])
    contacts = [env.step(np.array([1.0, 0.0], np.float32))[-1]["n_contacts"] for _ in range(20)]
    assert contacts == UP_WALL_CONTACTS
    assert overlap_fractions((0, 0), 15, (100, 0), 15) == (0.0, 0.0)
    assert overlap_fractions((3, 4), 15, (3, 4), 15) == pytest.approx((1.0, 1.0))
    fog, foa = overlap_fractions((0, 0), 15, (5, 0), 30)  # the small disk lies inside the big one
    assert foa == pytest.approx(1.0) and fog == pytest.approx(0.25, abs=2e-3)
    assert env.eval_state(np.array([400.0, 300.0]), np.array([397.0, 300.0])) == (True, 3.0)


def test_two_room_v0_energy_truncates():
    env, obs, _ = _v0([150, 100], [400, 300], values={"agent.max_energy": 50})
    assert obs[keys.STATE][4] == 50
    truncs = [env.step(np.zeros(2, np.float32))[3] for _ in range(50)]
    assert truncs == [False] * 49 + [True]


def test_two_room_v0_frames_look_like_0_0_3():
    env, _, info = _v0([150, 100], [400, 300])
    for _ in range(20):
        env.step(np.array([1.0, 0.0], np.float32))
    frame = env.render()
    assert frame.shape == (64, 64, 3) and frame.dtype == np.uint8
    blocks = frame.astype(float).mean(-1).reshape(8, 8, 8, 8).mean(axis=(1, 3))
    assert np.abs(blocks - np.array(UP_WALL_FRAME_BLOCKS)).max() < 3.0
    goal = info[keys.GOAL]  # the agent drawn at the goal: red at (400, 300) -> (50, 37.5) at 64 px
    np.testing.assert_array_equal(goal[37, 50], [255, 0, 0])
    env.set_render_size((32, 40))
    assert env.render().shape == (32, 40, 3)


def test_two_room_v0_doors_merge_like_0_0_3():
    values = {"door.number": 2, "door.position": np.array([100, 150, 0]), "door.size": np.array([75, 75, 40])}
    _, _, info = _v0([100, 100], [400, 300], values=values)
    layout = info["_layout"]
    assert layout[4] == 1  # one merged gap: t in [100, 225], canvas 9 + t
    np.testing.assert_array_equal(layout[5:7], [109, 234])
    values = {"wall.axis": 0, "door.number": 1, "door.position": np.array([300, 0, 0])}
    _, _, info = _v0([100, 100], [400, 400], values=values)
    np.testing.assert_array_equal(info["_layout"][[0, 4, 5, 6]], [0, 1, 309, 384])


def test_two_room_v0_reset_draws_start_goal_and_doors_per_seed():
    env = TwoRoomV0Env(render_size=16)
    draws = []
    for seed in range(6):
        obs, info = env.reset(seed=seed)
        again, _ = env.reset(seed=seed)
        np.testing.assert_array_equal(obs[keys.STATE], again[keys.STATE])
        assert not env.check_collide(env.variation_space["agent"]["position"].value, "agent")
        assert not env.check_collide(env.variation_space["goal"]["position"].value, "goal")
        assert env.check_one_door_fit(env.variation_space["door"]["size"].value)
        draws.append((*obs[keys.STATE][:4], *info["_layout"][4:]))
    assert len(set(draws)) == 6
    assert int(env.variation_space["wall"]["thickness"].value) == 19  # not in the default variations


def test_two_room_v0_expert_in_world():
    world = swm.World("swm/TwoRoom-v0", num_envs=4, image_shape=(16, 16), max_episode_steps=100, verbose=0)
    world.set_policy(swm.envs.expert_policy("swm/TwoRoom-v0"))
    assert world.evaluate(episodes=8, seed=0)["success_rate"] >= 75.0
    world.close()


# -- PushT-v1 / PushT-Discrete-v1 (upstream 0.1.1's behaviour; our design is PushT-v2) -------------
# Recorded from the original with tests/envs/data/record_pusht_v1.py: per case the start and goal
# states, actions, then upstream's states, rewards, terminated, n_contacts and frames.
_V1_DATA = Path(__file__).parent / "data"
V1 = np.load(_V1_DATA / "pusht_v1_upstream.npz")
V1_META = json.loads((_V1_DATA / "pusht_v1_upstream.json").read_text())
V1_CASES = sorted({k.rsplit("/", 1)[0] for k in V1.files})
MAX_MAD = 3.0  # mean absolute difference per pixel channel, out of 255


def _v1_values(values):
    if not values:
        return None
    return {
        k: np.asarray(v, np.uint8 if k.endswith("color") else np.float32 if k.endswith("scale") else None)
        for k, v in values.items()
    }


def _v1_run(case, size):
    env = gym.make(f"swm/{case.split('/')[0]}", render_size=(size, size)).unwrapped
    options = {keys.STATE: V1[case + "/start"], keys.GOAL_STATE: V1[case + "/goal"]}
    if V1_META[case + "/values"]:
        options[keys.VARIATION_VALUES] = _v1_values(V1_META[case + "/values"])
    obs, info = env.reset(seed=0, options=options)
    out = {
        "states": [obs[keys.STATE]],
        "rewards": [],
        "terminated": [],
        "n_contacts": [info[N_CONTACTS]],
        "frames": [env.render()],
    }
    goal = info[keys.GOAL]
    for action in V1[case + "/actions"]:
        obs, reward, terminated, truncated, info = env.step(action)
        assert truncated is False
        for key, value in (
            ("states", obs[keys.STATE]),
            ("rewards", reward),
            ("terminated", terminated),
            ("n_contacts", info[N_CONTACTS]),
        ):
            out[key].append(value)
        out["frames"].append(env.render())
    return {k: np.asarray(v) for k, v in out.items()}, goal


def _mad(a, b):
    return float(np.abs(np.asarray(a, np.float64) - np.asarray(b, np.float64)).mean())


@pytest.mark.parametrize("case", V1_CASES)
def test_pusht_v1_replays_upstream_states_rewards_success_and_contacts(case):
    run, goal = _v1_run(case, 64)
    np.testing.assert_allclose(run["states"], V1[case + "/states"], rtol=0, atol=1e-9)
    np.testing.assert_allclose(run["rewards"], V1[case + "/rewards"], rtol=0, atol=1e-9)
    np.testing.assert_array_equal(run["terminated"], V1[case + "/terminated"])
    np.testing.assert_array_equal(run["n_contacts"], V1[case + "/n_contacts"])
    for i, frame in enumerate(run["frames"]):
        assert frame.shape == (64, 64, 3) and frame.dtype == np.uint8
        assert _mad(frame, V1[case + "/frames@64"][i]) <= MAX_MAD, (case, i)
    assert _mad(goal, V1[case + "/goal@64"]) <= MAX_MAD


@pytest.mark.parametrize("case", ["PushT-v1/push", "PushT-v1/colors", "PushT-v1/shape_plus", "PushT-Discrete-v1/grid"])
def test_pusht_v1_frames_at_224_look_like_upstream(case):
    run, _ = _v1_run(case, 224)
    for mine, theirs in zip(run["frames"][[0, -1]], V1[case + "/frames@224"], strict=False):
        assert mine.shape == (224, 224, 3)
        assert _mad(mine, theirs) <= MAX_MAD


def test_pusht_v1_reward_and_success_rule_of_upstream():
    env = gym.make("swm/PushT-v1").unwrapped
    goal = np.array([256.0, 200.0, 256.0, 256.0, 0.1, 0.0, 0.0])
    near = goal + np.array([10.0, 0.0, 0.0, 10.0, 2 * math.pi - 0.2, 30.0, 0.0])  # angle wraps: 0.1 vs -0.1
    success, dist = env.eval_state(goal, near)
    assert success is True and dist == pytest.approx(np.linalg.norm(goal - near))
    assert env.eval_state(goal, goal + np.array([15.0, 0, 0, 15.0, 0, 0, 0]))[0] is False  # 4-number distance 21.2
    batch_ok, batch_dist = env.eval_state(np.stack([goal, goal]), np.stack([near, goal]))
    assert batch_ok.tolist() == [True, True] and batch_dist[1] == 0.0


def test_pusht_v1_factors_match_upstream():
    env = gym.make("swm/PushT-v1").unwrapped
    space = env.variation_space
    assert sorted(space.names()) == sorted(V1_META["factors"])
    for name, ref in V1_META["factors"].items():
        leaf = space[name.split(".")[0]][name.split(".")[1]]
        assert type(leaf).__name__ == ref["type"], name
        np.testing.assert_allclose(
            np.asarray(leaf.init_value, np.float64), np.asarray(ref["default"], np.float64), err_msg=name
        )
        if "low" in ref:
            np.testing.assert_allclose(leaf.low, ref["low"], err_msg=name)
            np.testing.assert_allclose(leaf.high, ref["high"], err_msg=name)
            assert str(leaf.dtype) == ref["dtype"] and list(leaf.shape) == ref["shape"], name
        if "n" in ref:
            assert (int(leaf.n), int(leaf.start)) == (ref["n"], ref["start"]), name


def test_pusht_v1_spaces_and_info_keys_of_upstream():
    env = gym.make("swm/PushT-v1").unwrapped
    obs, info = env.reset(seed=3)
    assert sorted(info) == sorted(V1_META["info_keys"]) and info["env_name"] == V1_META["env_name"] == "PushT"
    for key, (low, high) in V1_META["obs_space"].items():  # upstream's layout, bounds widened to what is reachable
        assert np.all(env.observation_space[key].low <= low) and np.all(env.observation_space[key].high >= high)
    assert env.observation_space[keys.STATE].high[4] == pytest.approx(2 * math.pi)
    assert env.action_space.shape == (2,) and env.action_space.dtype == np.float32
    np.testing.assert_array_equal(obs[keys.PROPRIO], obs[keys.STATE][[0, 1, 5, 6]])
    np.testing.assert_array_equal(info[keys.GOAL_PROPRIO], info[keys.GOAL_STATE][[0, 1, 5, 6]])
    np.testing.assert_allclose(info[GOAL_POSE], [256.0, 256.0, math.pi / 4])  # goal.position / goal.angle
    # with no goal_state option the goal is a second draw of the start factors, not the silhouette
    g = info[keys.GOAL_STATE]
    assert 50 <= g[0] <= 450 and 100 <= g[2] <= 400 and not np.allclose(g[:5], obs[keys.STATE][:5])


def test_pusht_discrete_v1_uses_upstreams_polar_grid():
    from stable_worldmodel.envs.pusht.v1 import dequantize, quantize

    env = gym.make("swm/PushT-Discrete-v1").unwrapped
    assert env.action_space.nvec.tolist() == V1_META["discrete_nvec"] == [16, 16]
    for key, move in V1_META["dequantized"].items():
        index = np.array([int(x) for x in key.split(",")])
        np.testing.assert_array_equal(dequantize(index), np.asarray(move, np.float32))
        np.testing.assert_array_equal(quantize(dequantize(index)), index)
    with pytest.raises(swm.errors.ConfigError, match="16x16"):
        type(env)(quantizer=object())


def test_pusht_v2_keeps_our_design_and_v1_has_an_expert():
    from stable_worldmodel.envs.pusht.v1 import PushTDiscreteV1, PushTV1

    assert type(gym.make("swm/PushT-v1").unwrapped) is PushTV1
    assert type(gym.make("swm/PushT-Discrete-v1").unwrapped) is PushTDiscreteV1
    assert type(gym.make("swm/PushT-v2").unwrapped) is PushT
    assert type(gym.make("swm/PushT-Discrete-v2").unwrapped) is PushTDiscrete
    v2 = gym.make("swm/PushT-v2").unwrapped
    assert v2.variation_space["agent"]["scale"].init_value == 1.0  # our multiplier
    for env_id, shape_dtype in (("swm/PushT-v1", np.float32), ("swm/PushT-Discrete-v1", np.int64)):
        expert = swm.envs.expert_policy(env_id)
        env = gym.make(env_id).unwrapped
        obs, info = env.reset(seed=0)
        action = expert.get_action(
            {keys.STATE: obs[keys.STATE][None, None], keys.GOAL_STATE: info[keys.GOAL_STATE][None, None]}
        )
        assert action.shape == (1, 2) and action.dtype == shape_dtype
        env.step(action[0])

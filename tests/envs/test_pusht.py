"""Tests of ``swm/PushT-v1`` / ``swm/PushT-Discrete-v1``: rules, factors, rendering, physics, expert."""

from __future__ import annotations

import subprocess
import sys

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

pytest.importorskip("pymunk")
pytest.importorskip("cv2")

from env_checks import assert_factor_changes_episode, assert_render_size, count_draws  # noqa: E402

import stable_worldmodel  # noqa: E402,F401  (registers swm/... ids)
from stable_worldmodel import keys  # noqa: E402
from stable_worldmodel.envs import expert_policy  # noqa: E402
from stable_worldmodel.envs.pusht import PushT, PushTDiscrete, PushTDiscreteExpert, PushTExpert  # noqa: E402
from stable_worldmodel.envs.pusht.env import ANGLE_TOLERANCE, discrete_bins  # noqa: E402
from stable_worldmodel.envs.pusht.physics import pd_gains  # noqa: E402
from stable_worldmodel.envs.pusht.planner import contact_plan  # noqa: E402
from stable_worldmodel.envs.pusht.shapes import SHAPES, distance_to_shape, shape_spec  # noqa: E402
from stable_worldmodel.errors import ConfigError, UnknownNameError  # noqa: E402


def make_env(cls=PushT, **kwargs):
    return cls(render_size=(64, 64), **kwargs)


def rollout(env, seed, options=None, n_steps=4):
    obs, info = env.reset(seed=seed, options=options)
    rng = np.random.default_rng(0)
    frames, states = [env.render()], [obs[keys.STATE]]
    for _ in range(n_steps):
        obs, *_ = env.step(rng.uniform(-1, 1, 2).astype(np.float32))
        frames.append(env.render())
        states.append(obs[keys.STATE])
    return np.stack(frames), np.stack(states), info[keys.GOAL], info[keys.GOAL_STATE]


def run_expert(env, expert, seed, max_steps=300, options=None):
    obs, info = env.reset(seed=seed, options=options)
    for t in range(max_steps):
        infos = {keys.STATE: obs[keys.STATE][None, None], keys.GOAL_STATE: info[keys.GOAL_STATE][None, None]}
        obs, _, terminated, _, info = env.step(expert.get_action(infos)[0])
        if terminated:
            return t + 1
    return None


# -- API ---------------------------------------------------------------------------------------
@pytest.mark.parametrize("cls", [PushT, PushTDiscrete])
def test_check_env(cls):
    check_env(make_env(cls))


@pytest.mark.parametrize("env_id", ["swm/PushT-v1", "swm/PushT-Discrete-v1"])
def test_registered_ids_make(env_id):
    env = gym.make(env_id, disable_env_checker=True)
    obs, info = env.reset(seed=0)
    assert obs[keys.STATE].shape == (7,) and obs[keys.PROPRIO].shape == (4,)
    assert info[keys.GOAL].shape == (224, 224, 3)  # the documented default render size
    assert isinstance(expert_policy(env_id), (PushTExpert, PushTDiscreteExpert))


def test_import_is_light():
    code = "import sys, stable_worldmodel.envs.pusht; assert not {'pymunk', 'cv2'} & set(sys.modules)"
    subprocess.run([sys.executable, "-c", code], check=True)


def test_observation_layout():
    env = make_env()
    obs, info = env.reset(seed=0)
    s = obs[keys.STATE]
    assert s.dtype == np.float64
    np.testing.assert_array_equal(s[:2], env.agent.position)
    np.testing.assert_array_equal(s[2:4], env.block.position)
    np.testing.assert_array_equal(obs[keys.PROPRIO], s[[0, 1, 5, 6]])
    np.testing.assert_allclose(info[keys.GOAL_STATE][2:5], [256, 256, np.pi / 4])
    np.testing.assert_array_equal(info[keys.GOAL_PROPRIO], info[keys.GOAL_STATE][[0, 1, 5, 6]])


def test_determinism_and_seed_dependence():
    a, b = make_env(), make_env()
    for ref, out in zip(
        rollout(a, 7, {keys.VARIATION: ["all"]}), rollout(b, 7, {keys.VARIATION: ["all"]}), strict=False
    ):
        np.testing.assert_array_equal(ref, out)
    for ref, out in zip(rollout(a, 7), rollout(b, 7), strict=False):
        np.testing.assert_array_equal(ref, out)
    assert not np.array_equal(rollout(a, 7)[1], rollout(a, 8)[1])


def test_start_positions_are_drawn_per_seed_and_clear():
    env = make_env()
    starts = []
    for seed in range(20):
        obs, _ = env.reset(seed=seed)
        s = obs[keys.STATE]
        local = (s[:2] - s[2:4]) @ np.array([[np.cos(s[4]), -np.sin(s[4])], [np.sin(s[4]), np.cos(s[4])]])
        assert distance_to_shape(env._specs["block"], local)[0] > 15  # the agent does not touch the block
        starts.append(s[:5])
    assert len({tuple(x) for x in np.round(starts, 6)}) == 20


# -- factors of variation ----------------------------------------------------------------------
FACTORS = PushT().variation_space.names()


def test_factor_count():
    assert len(FACTORS) == 17  # 16 + upstream's rendering.render_goal


@pytest.mark.parametrize("name", FACTORS)
def test_every_factor_changes_the_episode(name):
    env = make_env()
    # a circle agent looks the same at any angle: test agent.angle on a square agent
    base = {"agent.shape": SHAPES.index("square")} if name == "agent.angle" else {}

    def rollout_with_base(env, seed, options):
        values = {**base, **((options or {}).get(keys.VARIATION_VALUES) or {})}
        return rollout(env, seed, {keys.VARIATION_VALUES: values} if values else None)

    assert_factor_changes_episode(env, name, rollout_with_base)


def test_variation_values_and_unknown_factor():
    env = make_env()
    env.reset(seed=0, options={keys.VARIATION_VALUES: {"block.start_position": [200.0, 210.0], "block.angle": 0.5}})
    np.testing.assert_allclose([*env.block.position, env.block.angle], [200, 210, 0.5])
    with pytest.raises(UnknownNameError, match="block.color"):
        env.reset(seed=0, options={keys.VARIATION: ["block.colour"]})


# -- success rule and reward -------------------------------------------------------------------
def test_success_rule():
    env = make_env()
    _, info = env.reset(seed=0)
    goal = info[keys.GOAL_STATE]

    def moved(i, delta):
        s = goal.copy()
        s[i] += delta
        return s

    assert env.eval_state(goal, goal) == (True, 0.0)
    assert env.eval_state(goal, moved(0, 25.0))[0] is False  # agent off by 25
    assert env.eval_state(goal, moved(2, 25.0)) == (False, 25.0)  # block off by 25
    assert env.eval_state(goal, moved(2, 19.0))[0] is True
    both = moved(0, 15.0)
    both[3] += 15.0
    assert env.eval_state(goal, both)[0] is False  # 15 and 15 together are 21 > 20
    assert env.eval_state(goal, moved(4, np.pi / 8))[0] is False  # pi/8 > pi/9
    assert env.eval_state(goal, moved(4, -np.pi / 10))[0] is True
    assert env.eval_state(goal, moved(4, 2 * np.pi - 0.1))[0] is True  # wrapped
    success, dist = env.eval_state(np.stack([goal, goal]), np.stack([goal, moved(2, 30.0)]))
    np.testing.assert_array_equal(success, [True, False])
    np.testing.assert_allclose(dist, [0.0, 30.0])


def test_symmetric_blocks_compare_angles_modulo_their_symmetry():
    env = make_env()
    _, info = env.reset(seed=0, options={keys.VARIATION_VALUES: {"block.shape": SHAPES.index("square")}})
    goal = info[keys.GOAL_STATE]
    turned = goal.copy()
    turned[4] += np.pi / 2
    assert env.eval_state(goal, turned)[0] is True
    env.reset(seed=0)  # back to the tee
    assert env.eval_state(goal, turned)[0] is False


def test_terminated_reward_at_goal_and_reset_from_states():
    env = make_env()
    _, info = env.reset(seed=0)
    goal = info[keys.GOAL_STATE]
    obs, info = env.reset(seed=1, options={keys.STATE: goal, keys.GOAL_STATE: goal})
    np.testing.assert_array_equal(obs[keys.STATE], goal)
    _, reward, terminated, truncated, _ = env.step(np.zeros(2, np.float32))
    assert terminated and not truncated and reward == pytest.approx(1.0)
    start = goal.copy()
    start[2] += 100.0
    env.reset(seed=1, options=env.reset_options_from_dataset({keys.STATE: start}, {keys.STATE: goal}))
    _, reward, terminated, _, _ = env.step(np.zeros(2, np.float32))
    assert not terminated and 0.0 <= reward < 1.0
    with pytest.raises(ConfigError, match="length 5 or 7"):
        env.reset(seed=0, options={keys.STATE: np.zeros(3)})


# -- physics -----------------------------------------------------------------------------------
def test_pd_agent_and_quasi_static_block():
    env = make_env()
    state = np.array([100.0, 100.0, 300.0, 300.0, 0.0, 0.0, 0.0])
    env.reset(seed=0, options={keys.STATE: state})
    obs, *_ = env.step(np.array([1.0, 0.0], np.float32))
    # one step of the PD agent from rest covers g_u of the 100-unit target offset (~30 units)
    g_u, g_v = pd_gains()
    assert obs[keys.STATE][0] - 100.0 == pytest.approx(100.0 * g_u) and 29.0 < 100.0 * g_u < 31.0
    x1, v1 = obs[keys.STATE][0], obs[keys.STATE][5]
    obs, *_ = env.step(np.zeros(2, np.float32))  # target = position: only the velocity carries it on
    assert obs[keys.STATE][0] - x1 == pytest.approx(g_v * v1) and v1 > 0
    np.testing.assert_array_equal(obs[keys.STATE][2:5], state[2:5])  # untouched block does not move
    # push the T's top side downwards, then stop: the block stops at once (no sliding)
    env.reset(seed=0, options={keys.STATE: [300.0, 270.0, 300.0, 300.0, 0.0, 0.0, 0.0]})
    for _ in range(3):
        obs, *_ = env.step(np.array([0.0, 0.5], np.float32))
    assert obs[keys.STATE][3] > 305.0
    env.reset(seed=0, options={keys.STATE: [*obs[keys.STATE][:5], 0.0, 0.0]})
    env.agent.position = (100.0, 100.0)
    before = np.array(env.block.position)
    env.step(np.zeros(2, np.float32))
    np.testing.assert_allclose(env.block.position, before)


def test_invalid_actions_raise():
    env = make_env()
    env.reset(seed=0)
    with pytest.raises(ConfigError, match="shape"):
        env.step(np.zeros(3))
    with pytest.raises(ConfigError, match="finite"):
        env.step(np.array([np.nan, 0.0]))
    env = make_env(PushTDiscrete)
    env.reset(seed=0)
    with pytest.raises(ConfigError, match="integers"):
        env.step(np.array([11, 0]))


def test_discrete_variant():
    env, cont = make_env(PushTDiscrete), make_env()
    assert env.action_space == gym.spaces.MultiDiscrete([11, 11])
    bins = discrete_bins(11)
    assert bins[5] == 0.0 and bins[0] == -1.0 and bins[10] == 1.0 and bins[6] == pytest.approx(0.04)
    env.reset(seed=3)
    cont.reset(seed=3)
    for idx in ([10, 5], [5, 0], [7, 2]):
        a, *_ = env.step(np.array(idx))
        b, *_ = cont.step(bins[idx].astype(np.float32))
        np.testing.assert_allclose(a[keys.STATE], b[keys.STATE], atol=1e-4)
    np.testing.assert_array_equal(env.to_index(bins[[3, 9]]), [3, 9])
    np.testing.assert_array_equal(env.fix_action_sample([12.3, -1.0]), [10, 0])
    with pytest.raises(ConfigError, match="odd"):
        PushTDiscrete(n_bins=10)


def test_fix_action_sample():
    np.testing.assert_array_equal(make_env().fix_action_sample([[2.0, -0.5]]), [[1.0, -0.5]])


# -- shapes ------------------------------------------------------------------------------------
@pytest.mark.parametrize("name", SHAPES)
def test_add_shape_dispatch(name):
    env = make_env()
    env.reset(seed=0)
    body = getattr(env, f"add_{name}")((100.0, 100.0), angle=0.3)
    assert body in env.space.bodies and len(body.shapes) >= 1
    np.testing.assert_allclose([*body.position, body.angle], [100.0, 100.0, 0.3])
    spec = shape_spec(name, 15.0 if name == "circle" else 30.0)
    if spec.radius is not None:
        assert [s.radius for s in body.shapes] == [spec.radius]
    else:
        verts = np.array([tuple(v) for s in body.shapes for v in s.get_vertices()])
        np.testing.assert_allclose([*verts.min(0), *verts.max(0)], spec.bounds())
    same = env.add_shape(name, (300.0, 300.0), 0.3)
    assert len(same.shapes) == len(body.shapes)


def test_add_shape_unknown_name_suggests():
    env = make_env()
    env.reset(seed=0)
    with pytest.raises(UnknownNameError, match="Did you mean 'tee'"):
        env.add_shape("tea", (100.0, 100.0))


def test_contact_normals_point_outwards():
    for name in SHAPES:
        spec = shape_spec(name, 30.0)
        plan = contact_plan(spec, 15.0)
        assert len(plan.points) > 8
        assert (distance_to_shape(spec, plan.points + 2.0 * plan.normals) > 1.0).all()


# -- rendering ---------------------------------------------------------------------------------
def test_render_size():
    assert_render_size(make_env(), (64, 64))
    env = PushT()
    env.reset(seed=0)
    assert env.render().shape == (224, 224, 3)
    env.set_render_size((64, 64))
    assert env.render().shape == (64, 64, 3)
    with pytest.raises(ConfigError):
        env.set_render_size((0, 64))


def test_goal_image_is_drawn_once_per_reset():
    env = make_env()
    draws = count_draws(env)
    _, info = env.reset(seed=0)
    for _ in range(3):
        _, *_, step_info = env.step(np.zeros(2, np.float32))
    assert len(draws) == 1
    np.testing.assert_array_equal(step_info[keys.GOAL], info[keys.GOAL])
    frame = env.render()
    assert frame.dtype == np.uint8 and len(draws) == 2
    # the goal image shows the goal configuration: a different picture from the start frame
    assert not np.array_equal(frame, info[keys.GOAL])


# -- expert ------------------------------------------------------------------------------------
def test_expert_reaches_goal():
    env, expert = make_env(), PushTExpert()
    for seed in (0, 1):
        assert run_expert(env, expert, seed) is not None


def test_expert_handles_other_shapes_via_variation_keys():
    env, expert = make_env(), PushTExpert()
    obs, info = env.reset(seed=2, options={keys.VARIATION_VALUES: {"block.shape": SHAPES.index("L")}})
    for _ in range(300):
        infos = {
            keys.STATE: obs[keys.STATE][None, None],
            keys.GOAL_STATE: info[keys.GOAL_STATE][None, None],
            "variation.block.shape": np.array([[SHAPES.index("L")]]),
        }
        obs, _, terminated, _, info = env.step(expert.get_action(infos)[0])
        if terminated:
            break
    assert terminated


def test_expert_is_batched():
    env = make_env()
    states, goals = [], []
    for seed in range(3):
        obs, info = env.reset(seed=seed)
        states.append(np.stack([obs[keys.STATE]] * 2))
        goals.append(np.stack([info[keys.GOAL_STATE]] * 2))
    infos = {keys.STATE: np.stack(states), keys.GOAL_STATE: np.stack(goals)}  # (B=3, T=2, 7)
    action = PushTExpert().get_action(infos)
    assert action.shape == (3, 2) and action.dtype == np.float32 and np.abs(action).max() <= 1.0
    idx = PushTDiscreteExpert().get_action(infos)
    assert idx.shape == (3, 2) and idx.dtype == np.int64 and idx.min() >= 0 and idx.max() <= 10


@pytest.mark.slow
def test_expert_success_rate_100_seeds():
    env, expert = make_env(), PushTExpert()
    successes = sum(run_expert(env, expert, seed) is not None for seed in range(100))
    assert successes >= 60


def test_angle_tolerance_constant():
    assert ANGLE_TOLERANCE == pytest.approx(np.pi / 9)


def test_works_in_world_with_the_registered_expert():
    world_mod = pytest.importorskip("stable_worldmodel.world")
    world = world_mod.World(
        "swm/PushT-v1", num_envs=2, image_shape=(64, 64), max_episode_steps=300, verbose=0, vectorization_mode="sync"
    )
    world.set_policy(expert_policy("swm/PushT-v1"))
    world.reset(seed=0)
    assert world.infos[keys.STATE].shape[::2] == (2, 7) and world.infos[keys.GOAL].shape[-3:] == (64, 64, 3)
    result = world.evaluate(episodes=2, seed=0)
    assert result["success_rate"] >= 50.0


def test_resolution_alias_of_the_original_release():
    import gymnasium as gym

    env = gym.make("swm/PushT-v1", resolution=48, disable_env_checker=True)
    env.reset(seed=0)
    assert env.render().shape == (48, 48, 3)


def test_v1_frames_from_the_cached_static_layer_equal_fresh_ones():
    """PushT-v1 draws its background and goal silhouette once per episode: a frame drawn from the
    cached layer equals one drawn from scratch (the cached layer is never drawn on)."""
    from stable_worldmodel.envs.pusht import v1_render

    env = gym.make("swm/PushT-v1", render_mode="rgb_array").unwrapped
    env.reset(seed=3)
    v1_render._STATIC.clear()
    first = env.render()
    for _ in range(3):
        env.step(env.action_space.sample())
    cached = env.render()  # a cache hit
    v1_render._STATIC.clear()
    fresh = env.render()
    assert np.array_equal(cached, fresh) and not np.array_equal(first, cached)


@pytest.mark.parametrize("size", [(64, 64), (128, 128), (32, 64), (16, 16)])
def test_v1_frames_redrawn_under_the_bodies_equal_full_frames(size):
    """At sizes dividing 512 by a power of 2, a PushT-v1 frame redraws only the canvas blocks under
    the bodies: bit for bit the frame drawn at 512 px and resized whole, for bodies overlapping,
    apart, under the walls and partly off the canvas."""
    import cv2

    from stable_worldmodel.envs.pusht.v1_render import draw_v1_scene

    env = gym.make("swm/PushT-v1", render_mode="rgb_array").unwrapped
    env.reset(seed=5, options={"variation": ["all"]})
    v = env._values
    colors = {k: v[k]["color"] for k in ("background", "goal", "block", "agent")}
    rng = np.random.default_rng(1)
    poses = [((256, 256, 0), (256, 256, 0.3)), ((3, 4, 0), (508, 300, 1.0)), ((520, -8, 0), (-20, 505, 2.5))]
    poses += [((*rng.uniform(-10, 522, 2), 0), (*rng.uniform(-10, 522, 2), rng.uniform(0, 6.3))) for _ in range(20)]
    for agent_pose, block_pose in poses:
        agent = (*env._outlines["agent"], np.array(agent_pose, np.float64))
        block = (*env._outlines["block"], np.array(block_pose, np.float64))
        full = draw_v1_scene((512, 512), colors, env._goal_pose, block, agent)
        want = cv2.resize(full, size[::-1], interpolation=cv2.INTER_LINEAR)
        np.testing.assert_array_equal(draw_v1_scene(size, colors, env._goal_pose, block, agent), want)

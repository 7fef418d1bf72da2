"""DeepMind Control envs: upstream 0.1.1's spaces, the factors, resets, rendering and the experts."""

from __future__ import annotations

import pickle
import subprocess
import sys
import textwrap
import types

import numpy as np
import pytest

from stable_worldmodel._optional import is_available

if not (
    is_available("mujoco") and is_available("dm_control")
):  # find_spec: mujoco must not be imported before its GL setup
    pytest.skip("extra 'mujoco' not installed", allow_module_level=True)

import gymnasium as gym  # noqa: E402
from env_checks import assert_factor_changes_episode  # noqa: E402

import stable_worldmodel as swm  # noqa: E402
from stable_worldmodel import keys  # noqa: E402
from stable_worldmodel.envs import dmcontrol  # noqa: E402
from stable_worldmodel.errors import ConfigError, DependencyNotInstalled, SpaceError, UnknownNameError  # noqa: E402

# -- upstream 0.1.1's public facts (observed) ------------------------------------------------------
F32, F64 = np.float32, np.float64
DENSITY = ("box", (1,), F32, 500.0, 1500.0, 1000.0)
SWITCH = ("discrete", 2, 1)
AGENT = ("box", (3,), F64, 0.0, 1.0, [0.7, 0.5, 0.3])
TARGET = ("box", (3,), F64, 0.0, 1.0, [0.6, 0.3, 0.3])
FLOOR = {"floor.color": ("box", (2, 3), F64, 0.0, 1.0, [[0.1, 0.2, 0.3], [0.2, 0.3, 0.4]])}
FRICTION = {"floor.friction": ("box", (1,), F32, 0.0, 1.0, 1.0)}
GRAVITY = {
    "gravity.x": ("box", (1,), F64, -5.0, 5.0, 0.0),
    "gravity.y": ("box", (1,), F64, -5.0, 5.0, 0.0),
    "gravity.z": ("box", (1,), F64, -20.0, 0.0, -9.81),
}
LIGHT = {"light.intensity": ("box", (1,), F64, 0.0, 1.0, 0.7)}
TARGETS = {"target.color": TARGET, "target.shape": SWITCH}
RENDER = {"rendering.render_target": ("discrete", 2, 0)}
UPSTREAM = {  # name: (obs dim, action dim, factors in upstream's order, extra info keys)
    "Humanoid": (
        67,
        21,
        {
            "agent.color": AGENT,
            "agent.left_knee_locked": SWITCH,
            "agent.right_lower_arm_density": DENSITY,
            "agent.torso_density": DENSITY,
            **FLOOR,
            **FRICTION,
            **GRAVITY,
            **LIGHT,
        },
        ("speed", "torso_upright", "head_height"),
    ),
    "Cheetah": (
        17,
        6,
        {
            "agent.back_foot_density": DENSITY,
            "agent.back_foot_locked": SWITCH,
            "agent.color": AGENT,
            "agent.torso_density": DENSITY,
            **FLOOR,
            **FRICTION,
            **GRAVITY,
            **LIGHT,
        },
        ("speed", "torso_height", "bfoot_height", "ffoot_height", "angmomentum"),
    ),
    "Hopper": (
        15,
        4,
        {
            "agent.color": AGENT,
            "agent.foot_density": DENSITY,
            "agent.foot_locked": SWITCH,
            "agent.torso_density": DENSITY,
            **FLOOR,
            **FRICTION,
            **GRAVITY,
            **LIGHT,
        },
        ("speed", "height", "angmomentum"),
    ),
    "Reacher": (
        6,
        2,
        {
            "agent.arm_density": DENSITY,
            "agent.color": AGENT,
            "agent.finger_density": DENSITY,
            "agent.finger_locked": SWITCH,
            **FLOOR,
            **LIGHT,
            **RENDER,
            **TARGETS,
        },
        ("target_pos", "finger_pos"),
    ),
    "Walker": (
        24,
        6,
        {
            "agent.color": AGENT,
            "agent.left_foot_density": DENSITY,
            "agent.right_knee_locked": SWITCH,
            "agent.torso_density": DENSITY,
            **FLOOR,
            **FRICTION,
            "floor.rotation_y": ("box", (1,), F64, -10.0, 10.0, 0.0),
            **GRAVITY,
            **LIGHT,
        },
        (
            "speed",
            "torso_height",
            "torso_upright",
            "left_foot_height",
            "right_foot_height",
            "left_thigh_height",
            "right_thigh_height",
        ),
    ),
    "Acrobot": (
        6,
        1,
        {
            "agent.color": AGENT,
            "agent.lower_arm_density": DENSITY,
            "agent.upper_arm_density": DENSITY,
            "agent.upper_arm_locked": SWITCH,
            **FLOOR,
            **GRAVITY,
            **LIGHT,
            **TARGETS,
        },
        (),
    ),
    "Pendulum": (
        3,
        1,
        {
            "agent.color": AGENT,
            "agent.mass_density": DENSITY,
            "agent.mass_shape": SWITCH,
            "agent.pole_density": DENSITY,
            **FLOOR,
            **GRAVITY,
            **LIGHT,
        },
        (),
    ),
    "Cartpole": (
        5,
        1,
        {
            "agent.cart_mass": ("box", (1,), F32, 0.5, 1.5, 1.0),
            "agent.cart_shape": SWITCH,
            "agent.color": AGENT,
            "agent.pole_density": DENSITY,
            **FLOOR,
            **GRAVITY,
            **LIGHT,
        },
        (),
    ),
    "BallInCup": (
        8,
        2,
        {
            "agent.color": AGENT,
            "agent.density": DENSITY,
            "ball.color": AGENT,
            "ball.density": DENSITY,
            "ball.size": ("box", (1,), F32, 0.01, 0.05, 0.025),
            **FLOOR,
            **GRAVITY,
            **LIGHT,
            **RENDER,
            **TARGETS,
        },
        (),
    ),
    "Finger": (
        12,
        2,
        {
            "agent.color": AGENT,
            "agent.fingertip_density": DENSITY,
            "agent.proximal_density": DENSITY,
            **FLOOR,
            **LIGHT,
            **RENDER,
            "spinner.color": AGENT,
            "spinner.density": DENSITY,
            "spinner.friction": ("box", (1,), F32, 0.0, 1.0, 0.1),
            **TARGETS,
        },
        ("hinge_velocity", "target_position", "tip_position"),
    ),
    "Manipulator": (
        44,
        5,
        {
            "agent.color": AGENT,
            "agent.hand_density": DENSITY,
            "agent.upper_arm_density": DENSITY,
            "agent.upper_arm_length": DENSITY,
            **FLOOR,
            **LIGHT,
            **RENDER,
            **TARGETS,
        },
        (),
    ),
    "Quadruped": (
        78,
        12,
        {
            "agent.color": ("box", (3,), F64, 0.0, 1.0, [0.6, 0.3, 0.3]),
            "agent.foot_back_left_density": DENSITY,
            "agent.knee_back_left_locked": SWITCH,
            "agent.torso_density": DENSITY,
            **FLOOR,
            **FRICTION,
            **GRAVITY,
            **LIGHT,
        },
        ("torso_velocity",),
    ),
}
UPSTREAM_INFO = ("env_name", "success", "qpos", "qvel", "score")
_ENVS: dict = {}


def make(name: str, **kwargs):
    """One env per domain for the whole module (kwargs: a fresh one), drawing 16 x 16 frames."""
    if kwargs or name not in _ENVS:
        env = getattr(dmcontrol, f"{name}DMControlWrapper")(**kwargs)
        env.set_render_size((16, 16))
        if kwargs:
            return env
        _ENVS[name] = env
    return _ENVS[name]


@pytest.fixture(scope="module", autouse=True)
def _close_envs():
    yield
    for env in _ENVS.values():
        env.close()
    _ENVS.clear()


@pytest.mark.parametrize("name", list(UPSTREAM))
def test_spaces_info_and_step_match_upstream(name):
    n_obs, n_act, factors, extra = UPSTREAM[name]
    env = make(name)
    assert env.observation_space == gym.spaces.Box(-np.inf, np.inf, (n_obs,), np.float32)
    assert env.action_space == gym.spaces.Box(-1.0, 1.0, (n_act,), np.float64)
    assert env.variation_space.names() == list(factors)
    for factor, (kind, *spec) in factors.items():
        space = env.variation_space[factor]
        if kind == "discrete":
            assert isinstance(space, gym.spaces.Discrete) and space.n == spec[0] and space.init_value == spec[1], factor
        else:
            shape, dtype, low, high, init = spec
            assert space.shape == shape and space.dtype == dtype, factor
            assert np.all(space.low == np.asarray(low, dtype)) and np.all(space.high == np.asarray(high, dtype)), factor
            np.testing.assert_allclose(
                space.init_value, np.broadcast_to(np.asarray(init, dtype), shape), err_msg=factor
            )
    obs, info = env.reset(seed=0)
    assert obs.shape == (n_obs,) and obs.dtype == np.float32
    obs, reward, terminated, truncated, info = env.step(np.zeros(n_act))
    assert isinstance(reward, float) and not terminated and not truncated
    assert set(info) >= {
        *UPSTREAM_INFO,
        *extra,
        keys.STATE,
        keys.PROPRIO,
        keys.GOAL,
        keys.GOAL_STATE,
        keys.GOAL_PROPRIO,
    }
    m = env.model
    assert info[keys.STATE].shape == (m.nq + m.nv + m.na,) and info[keys.GOAL].shape == (16, 16, 3)
    assert info["env_name"] == name and info["score"] == pytest.approx(reward / 1000)
    assert env.eval_state(info[keys.GOAL_STATE], info[keys.GOAL_STATE])[0]


def test_reset_matches_dm_control_and_is_reproducible():
    from dm_control import suite

    env = make("Cartpole")
    obs, _ = env.reset(seed=7)
    ts = suite.load("cartpole", "swingup_sparse", task_kwargs={"random": 7}).reset()
    np.testing.assert_allclose(obs, np.concatenate([np.ravel(v) for v in ts.observation.values()]), rtol=1e-6)

    def episode(e, seed, options=None, follow=False):
        obs, info = e.reset(seed=seed, options=options)
        if follow:
            obs, info = e.reset()
        frames, states = [e.render()], [info[keys.STATE]]
        for t in range(3):
            obs, _, _, _, info = e.step(np.full(e.action_space.shape, 0.5 - 0.3 * t))
            frames.append(e.render())
            states.append(info[keys.STATE])
        return np.stack(frames), np.stack(states), e.variation_space["agent"]["color"].value

    everything = {keys.VARIATION: ["all"]}
    a, b = episode(env, 3, everything), episode(make("Cartpole", render_quality="medium"), 3, everything)
    for x, y in zip(a, b, strict=False):
        np.testing.assert_array_equal(x, y)
    assert not np.array_equal(a[1], episode(env, 4, everything)[1])
    np.testing.assert_array_equal(episode(env, 5, follow=True)[1], episode(env, 5, follow=True)[1])
    seeded = make("Cartpole", seed=11)
    np.testing.assert_array_equal(
        seeded.reset()[0], env.reset(seed=11)[0]
    )  # the constructor's seed seeds the first reset


def test_episodes_go_on_unless_a_time_limit_is_given():
    env = make("Pendulum")
    env.reset(seed=0)
    for _ in range(520):  # past dm_control's 1000 physics steps: no hidden restart
        _, _, terminated, truncated, info = env.step(np.zeros(1))
        assert not terminated and not truncated
    assert env._physics.data.time == pytest.approx(520 * 2 * 0.02)
    short = make("Pendulum", environment_kwargs={"time_limit": 0.2})  # 10 physics steps
    short.reset(seed=0)
    flags = [short.step(np.zeros(1))[3] for _ in range(5)]
    assert flags == [False, False, False, False, True]


def _frames(env, seed, options, extra=None):
    options = {**(options or {})}
    values = {**(extra or {}), **options.get(keys.VARIATION_VALUES, {})}
    env.reset(seed=seed, options={keys.VARIATION_VALUES: values})
    frames = [env.render()]
    for _ in range(2):
        env.step(np.zeros(env.action_space.shape))
        frames.append(env.render())
    return (np.stack(frames),)


def _states(env, seed, options):
    _, info = env.reset(seed=seed, options=options)
    if isinstance(env, dmcontrol.FingerDMControlWrapper):  # spin the spinner: its friction then matters
        env.set_state(info["qpos"], np.array([0.0, 0.0, 5.0]))
        info[keys.STATE] = env.step(np.zeros(2))[4][keys.STATE]
    states = [info[keys.STATE]]
    for t in range(15):
        _, _, _, _, info = env.step(np.full(env.action_space.shape, 0.8 if t % 6 < 3 else -0.8))
        states.append(info[keys.STATE])
    return (np.stack(states),)


FRAME_FACTORS = [
    ("Cartpole", "agent.color"),
    ("Cartpole", "floor.color"),
    ("Cartpole", "light.intensity"),
    ("Cartpole", "agent.cart_shape"),
    ("Reacher", "target.color"),
    ("Reacher", "target.shape"),
    ("Reacher", "rendering.render_target"),
    ("Finger", "spinner.color"),
    ("BallInCup", "ball.color"),
]
STATE_FACTORS = [
    ("Cartpole", "gravity.z"),
    ("Cartpole", "gravity.x"),
    ("Cartpole", "agent.cart_mass"),
    ("Cartpole", "agent.pole_density"),
    ("Pendulum", "agent.mass_density"),
    ("Cheetah", "floor.friction"),
    ("Cheetah", "agent.torso_density"),
    ("Walker", "floor.rotation_y"),
    ("BallInCup", "ball.size"),
    ("Finger", "spinner.friction"),
]


@pytest.fixture(scope="module")
def big_reacher():
    """Reacher's easy (5 cm) target at 32 x 32: the hard one is about a pixel at 16 x 16."""
    env = make("Reacher", task="easy")
    env.set_render_size((32, 32))
    yield env
    env.close()


@pytest.mark.parametrize(("name", "factor"), FRAME_FACTORS)
def test_visual_factor_changes_frames(name, factor, big_reacher):
    env = big_reacher if name == "Reacher" else make(name)
    extra = {"rendering.render_target": 1} if factor.startswith("target.") else None
    assert_factor_changes_episode(env, factor, lambda e, s, o: _frames(e, s, o, extra), tries=6)


@pytest.mark.parametrize(("name", "factor"), STATE_FACTORS)
def test_physical_factor_changes_dynamics(name, factor):
    assert_factor_changes_episode(make(name), factor, _states, tries=6)


def test_only_structural_factors_recompile():
    env = make("Cartpole")
    env.reset(seed=0)  # the default model, whatever earlier tests left
    calls = []
    recompile = env._editor.recompile_into
    env._editor.recompile_into = lambda *a: calls.append(1) or recompile(*a)
    try:
        env.reset(seed=0)
        env.reset(seed=0, options={keys.VARIATION_VALUES: {"agent.color": [1.0, 0.0, 0.0], "gravity.z": [-5.0]}})
        assert calls == []
        env.reset(seed=0, options={keys.VARIATION_VALUES: {"agent.pole_density": [800.0]}})
        env.reset(seed=1, options={keys.VARIATION_VALUES: {"agent.pole_density": [800.0]}})
        assert calls == [1]
        env.reset(seed=0)
        assert calls == [1, 1]
    finally:
        env._editor.recompile_into = recompile
    assert env.model.body("pole_1").mass[0] == pytest.approx(0.1)  # back to dm_control's model


@pytest.mark.parametrize("name", ["Reacher", "Quadruped"])
def test_reset_from_dataset_rows_restores_state_and_goal(name):
    env = make(name)
    _, info = env.reset(seed=2, options={keys.VARIATION: ["agent.color"]})
    rows = []
    for _ in range(4):
        rows.append(
            {keys.STATE: info[keys.STATE], "variation.agent.color": env.variation_space["agent"]["color"].value}
        )
        _, _, _, _, info = env.step(np.full(env.action_space.shape, 0.3))
    other = make(name, render_quality="medium")
    other.set_render_size((16, 16))
    options = other.reset_options_from_dataset(rows[1], rows[3])
    _, restored = other.reset(seed=9, options=options)
    np.testing.assert_array_equal(restored[keys.STATE], rows[1][keys.STATE])
    np.testing.assert_array_equal(restored[keys.GOAL_STATE], rows[3][keys.STATE])
    np.testing.assert_array_equal(other.variation_space["agent"]["color"].value, rows[1]["variation.agent.color"])
    assert other.eval_state(restored[keys.GOAL_STATE], rows[3][keys.STATE])[0]
    env.reset(seed=9, options=options)
    for _ in range(3):
        a = env.step(np.full(env.action_space.shape, -0.2))[4][keys.STATE]
        b = other.step(np.full(env.action_space.shape, -0.2))[4][keys.STATE]
        np.testing.assert_array_equal(a, b)
    if name == "Reacher":  # the target moved under the goal state's fingertip
        np.testing.assert_allclose(restored["target_pos"], other.goal_features(rows[3][keys.STATE][:2]), atol=1e-9)


def test_goal_and_eval_state():
    env = make("Reacher")
    _, info = env.reset(seed=1)
    np.testing.assert_allclose(env.goal_features(info[keys.GOAL_STATE][:2]), info["target_pos"], atol=1e-6)
    assert not env.eval_state(info[keys.GOAL_STATE], info[keys.STATE])[0]
    ball = make("BallInCup")
    _, info = ball.reset(seed=0)
    assert ball.eval_state() is False  # upstream's form: the ball in the cup now
    _, info = ball.reset(seed=0, options={keys.STATE: info[keys.GOAL_STATE]})
    assert ball.eval_state() is True and info["success"] == 1.0


def test_render_sizes_and_cameras():
    env = make("Quadruped")
    env.reset(seed=0)
    assert env.render().shape == (16, 16, 3)
    assert env.render(width=24, height=12).shape == (12, 24, 3)
    assert not np.array_equal(env.render(camera_id=0), env.render())  # the default is camera 2, as upstream


def test_mjrenderer_frames_equal_physics_render():
    """physics.render runs first in a fresh process (dm_control caches its GL context per thread)."""
    code = textwrap.dedent("""
        import numpy as np
        from stable_worldmodel.envs import dmcontrol
        cases = [("Cartpole", {}), ("Reacher", {"rendering.render_target": 1}), ("Quadruped", {})]
        envs = []
        for name, values in cases:
            env = getattr(dmcontrol, name + "DMControlWrapper")(render_quality="high")
            env.set_render_size((48, 64))
            env._render_goal = lambda: np.zeros((48, 64, 3), np.uint8)  # no MjRenderer before physics.render
            env.reset(seed=1, options={"variation_values": values})
            env.step(np.full(env.action_space.shape, 0.4))
            envs.append((env, env._physics.render(48, 64, camera_id=env.camera_id)))
        for env, expected in envs:
            frame = env.render()
            assert frame.shape == expected.shape and np.array_equal(frame, expected), (
                type(env).__name__,
                np.abs(frame.astype(int) - expected).max(),
            )
        print("ok")
    """)
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert out.stdout.strip().endswith("ok"), out.stderr[-2000:]


def _episode_return(env, policy, steps, seed=0):
    _, info = env.reset(seed=seed)
    total = 0.0
    for _ in range(steps):
        batch = {k: np.asarray(v)[None, None] for k, v in info.items() if k in (keys.STATE, keys.GOAL_STATE)}
        action = policy(batch)[0] if callable(policy) else policy.get_action(batch)[0]
        _, reward, _, _, info = env.step(action)
        total += reward
    return total, info["success"]


@pytest.mark.parametrize(("name", "steps"), [("Pendulum", 150), ("Cartpole", 300), ("Reacher", 60)])
def test_scripted_expert_beats_random(name, steps):
    env = make(name)
    expert = swm.envs.expert_policy(f"swm/{name}DMControl-v0")
    rng = np.random.default_rng(0)
    random = lambda _: rng.uniform(-1, 1, (1, *env.action_space.shape))  # noqa: E731
    ret, success = _episode_return(env, expert, steps)
    assert ret > _episode_return(env, random, steps)[0] + 50 and success == 1.0


def test_bad_input_raises_typed_errors(tmp_path):
    with pytest.raises(UnknownNameError, match="Did you mean 'walk'"):
        dmcontrol.WalkerDMControlWrapper(task="wlak")
    with pytest.raises(ConfigError, match="render_quality"):
        dmcontrol.CartpoleDMControlWrapper(render_quality="ultra")
    with pytest.raises(ConfigError, match="Did you mean 'time_limit'"):
        dmcontrol.CartpoleDMControlWrapper(environment_kwargs={"time_limt": 3})
    env = make("Cartpole")
    with pytest.raises(ConfigError, match="state"):
        env.reset(seed=0, options={keys.STATE: [0.0, 1.0, 2.0]})
    with pytest.raises(UnknownNameError, match="agent.color"):
        env.reset(seed=0, options={keys.VARIATION: ["agent.colour"]})
    env.reset(seed=0)
    with pytest.raises(SpaceError):
        env.step(np.zeros(3))
    with pytest.raises(UnknownNameError, match="CartpoleDMControl"):
        dmcontrol.DMControlExpert(env_id="swm/CartpolDMControl-v0")
    with pytest.raises(FileNotFoundError, match="ckpt_path"):
        dmcontrol.ExpertPolicy(str(tmp_path / "none.zip"), str(tmp_path / "none.pkl"))
    (tmp_path / "a.zip").write_bytes(b"")
    (tmp_path / "a.pkl").write_bytes(b"")
    if "stable_baselines3" not in sys.modules:
        try:
            import stable_baselines3  # noqa: F401
        except ImportError:
            with pytest.raises(DependencyNotInstalled, match="stable_baselines3"):
                dmcontrol.ExpertPolicy(str(tmp_path / "a.zip"), str(tmp_path / "a.pkl"))


def test_expert_policy_runs_a_sac_checkpoint(tmp_path, monkeypatch):
    """Upstream's SB3 expert on a stub of stable_baselines3: normalization, noise and clipping."""
    seen = {}

    class SAC:
        @classmethod
        def load(cls, path, device="cpu"):
            seen["load"] = (path, device)
            return cls()

        def set_random_seed(self, seed):
            seen["seed"] = seed

        def predict(self, obs, deterministic=False):
            seen["obs"] = obs
            return np.full((obs.shape[0], 1), 2.0), None

    monkeypatch.setitem(sys.modules, "stable_baselines3", types.SimpleNamespace(SAC=SAC))
    stats = types.SimpleNamespace(obs_rms=types.SimpleNamespace(mean=np.ones(5), var=np.full(5, 4.0)))
    (tmp_path / "sac.zip").write_bytes(b"zip")
    (tmp_path / "vn.pkl").write_bytes(pickle.dumps(stats))
    policy = dmcontrol.ExpertPolicy(str(tmp_path / "sac.zip"), str(tmp_path / "vn.pkl"), seed=3)
    obs = np.arange(10, dtype=np.float32).reshape(2, 1, 5)
    action = policy.get_action({"observation": obs})
    assert seen["load"] == (str(tmp_path / "sac.zip"), "cpu") and seen["seed"] == 3
    np.testing.assert_allclose(seen["obs"], np.clip((obs[:, -1] - 1.0) / np.sqrt(4.0 + 1e-8), -10, 10))
    assert action.dtype == np.float32 and action.shape == (2, 1) and np.all(action == 1.0)


def test_importing_the_package_is_light():
    code = (
        "import sys, stable_worldmodel.envs.dmcontrol as d; print('mujoco' in sys.modules, 'dm_control' in sys.modules)"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert out.stdout.split() == ["False", "False"], out.stderr

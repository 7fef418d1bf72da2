"""OGBench Cube / Scene (swm/OGBCube-v0, swm/OGBScene-v0): factors, seeds, goals, dataset resets,
OGBench's success rule, the expert, errors. Tiny frames (16 x 16) keep the MuJoCo part short."""

from __future__ import annotations

import pickle
import subprocess
import sys

import numpy as np
import pytest

from stable_worldmodel.envs.mujoco_render import setup_gl  # noqa: E402

setup_gl()  # before mujoco is imported (headless EGL)
pytest.importorskip("mujoco")
pytest.importorskip("ogbench")

from env_checks import assert_factor_changes_episode  # noqa: E402

from stable_worldmodel import keys  # noqa: E402
from stable_worldmodel.envs.base import SupportsDatasetReset, SupportsEvalState, SupportsRenderSize  # noqa: E402
from stable_worldmodel.envs.ogbench.cube_env import CubeEnv  # noqa: E402
from stable_worldmodel.envs.ogbench.expert import OGBenchExpert  # noqa: E402
from stable_worldmodel.envs.ogbench.scene_env import SceneEnv  # noqa: E402
from stable_worldmodel.errors import ConfigError, SpaceError, UnknownNameError  # noqa: E402

SIZE = (16, 16)
CUBE_FACTORS = [
    "agent.color",
    "agent.ee_start_position",
    "camera.angle_delta",
    "cube.color",
    "cube.goal_position",
    "cube.goal_yaw",
    "cube.size",
    "cube.start_position",
    "cube.start_yaw",
    "floor.color",
    "light.intensity",
]


def _small(cls):
    env = cls()
    env.set_render_size(SIZE)
    yield env
    env.close()


@pytest.fixture(scope="module")
def cube():
    yield from _small(CubeEnv)


@pytest.fixture(scope="module")
def scene():
    yield from _small(SceneEnv)


def rollout(env, seed, options, steps=1):
    """(first frame, goal image, states) of a reset with ``seed``/``options`` and ``steps`` zero actions."""
    _, info = env.reset(seed=seed, options=options)
    frame, states = env.render(), [info[keys.STATE]]
    for _ in range(steps):
        _, _, _, _, info = env.step(np.zeros(5, np.float32))
        states.append(info[keys.STATE])
    return frame, info[keys.GOAL], np.stack(states)


def test_module_paths_and_light_import():
    from stable_worldmodel.envs.ogbench_cube import CubeEnv as Cube003
    from stable_worldmodel.envs.ogbench_scene import SceneEnv as Scene003

    assert Cube003 is CubeEnv and Scene003 is SceneEnv
    code = "import sys, stable_worldmodel.envs.ogbench; print('mujoco' in sys.modules, 'ogbench' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert out.stdout.split() == ["False", "False"]


def test_spaces_and_infos_as_upstream(cube):
    for protocol in (SupportsRenderSize, SupportsEvalState, SupportsDatasetReset):
        assert isinstance(cube, protocol)
    assert cube.observation_space.shape == (28,) and cube.observation_space.dtype == np.float64
    assert cube.action_space.shape == (5,) and cube.action_space.dtype == np.float32 and cube.env_name == "Cube"
    v = cube.variation_space
    assert v.names() == CUBE_FACTORS
    np.testing.assert_allclose(v["agent"]["ee_start_position"].low, [0.25, -0.35, 0.2])
    np.testing.assert_allclose(v["light"]["intensity"].init_value, [0.7])
    assert pickle.loads(pickle.dumps(v)).names() == CUBE_FACTORS  # World's workers send the spaces pickled
    obs, info = cube.reset(seed=0)
    assert obs.shape == (28,) and info["qpos"].shape == (21,) and info["env_name"] == "Cube"
    assert info["success"] is False
    assert {"proprio.joint_pos", "proprio.gripper_contact", "privileged.block_0_quat", "prev_qvel"} <= set(info)
    assert info[keys.STATE].shape == (41,) and info[keys.GOAL_STATE].shape == (41,) and info["target"].shape == (28,)
    assert info[keys.PROPRIO].shape == (19,) and info[keys.GOAL_PROPRIO].shape == (19,)
    np.testing.assert_allclose(info[keys.PROPRIO], obs[:19])
    assert info[keys.GOAL].shape == (*SIZE, 3) and info[keys.GOAL].dtype == np.uint8
    np.testing.assert_allclose(info["proprio.effector_pos"], v["agent"]["ee_start_position"].value, atol=1e-4)


def test_scene_spaces(scene):
    assert scene.observation_space.shape == (40,) and scene.env_name == "Scene"
    assert "lock_color" in scene.variation_space.names()
    np.testing.assert_allclose(scene.variation_space["cube"]["goal_position"].high, [[0.45, 0.18]])
    obs, info = scene.reset(seed=0)
    assert obs.shape == (40,) and info[keys.STATE].shape == (51,) and set(info["button_states"]) <= {0, 1}


@pytest.mark.parametrize("make", [CubeEnv, SceneEnv])
def test_seeds_make_resets_reproducible(make, cube, scene):
    env = cube if make is CubeEnv else scene
    a = rollout(env, 5, {keys.VARIATION: ["all"]}, steps=2)
    b = rollout(env, 5, {keys.VARIATION: ["all"]}, steps=2)
    for x, y in zip(a, b, strict=True):
        np.testing.assert_array_equal(x, y)
    c = rollout(env, 6, None)
    assert not np.array_equal(a[2][0], c[2][0])
    env.reset(seed=9)
    first = env.reset()[1][keys.STATE]
    env.reset(seed=9)
    np.testing.assert_array_equal(env.reset()[1][keys.STATE], first)  # reset() continues the seeded stream


def test_cube_factors_place_the_cubes(cube):
    values = {"cube.start_position": [[0.5, 0.2]], "cube.goal_position": [[0.32, -0.25]], "cube.size": [0.03]}
    _, info = cube.reset(seed=0, options={keys.VARIATION_VALUES: values})
    np.testing.assert_allclose(info["privileged.block_0_pos"], [0.5, 0.2, 0.03], atol=1e-6)
    np.testing.assert_allclose(info["privileged.target_block_0_pos"], [0.32, -0.25, 0.03], atol=2e-3)


@pytest.mark.parametrize("name", CUBE_FACTORS)
def test_each_cube_factor_changes_the_episode(cube, name):
    assert_factor_changes_episode(cube, name, rollout, tries=4)


@pytest.mark.parametrize("name", ["lock_color", "agent.color", "camera.angle_delta"])
def test_scene_factors_change_the_episode(scene, name):
    assert_factor_changes_episode(scene, name, rollout, seed=3, tries=4)


def test_factors_do_not_leak_into_later_resets(cube, scene):
    for env in (cube, scene):
        before = rollout(env, 3, None)
        rollout(env, 3, {keys.VARIATION: ["all"]})
        for a, b in zip(before, rollout(env, 3, None), strict=True):
            np.testing.assert_array_equal(a, b)


def test_goal_image_is_the_goal_state_rendered(cube, scene):
    for env in (cube, scene):
        _, info = env.reset(seed=2, options={keys.VARIATION: ["all"]})
        goal = info[keys.GOAL_STATE]
        values = {k: np.asarray(v) for k, v in _flat(env.variation_space.value).items()}
        _, again = env.reset(seed=4, options={keys.STATE: goal, keys.GOAL_STATE: goal, keys.VARIATION_VALUES: values})
        np.testing.assert_array_equal(again[keys.STATE], goal)
        np.testing.assert_array_equal(env.render(), info[keys.GOAL])
        np.testing.assert_array_equal(again[keys.GOAL], info[keys.GOAL])


def _flat(d, prefix=""):
    out = {}
    for k, v in d.items():
        out.update(_flat(v, f"{prefix}{k}.") if isinstance(v, dict) else {f"{prefix}{k}": v})
    return out


def test_reset_from_dataset_rows(cube, scene):
    for env in (cube, scene):
        _, info = env.reset(seed=1, options={keys.VARIATION: ["cube.color", "floor.color"]})
        factors = {f"{keys.VARIATION}.{k}": v for k, v in _flat(env.variation_space.value).items()}
        frame, goal_row = env.render(), {keys.STATE: info[keys.GOAL_STATE]}
        for _ in range(3):
            _, _, _, _, later = env.step(np.full(5, 0.5, np.float32))
        rows = (({keys.STATE: info[keys.STATE], **factors}, frame), ({keys.STATE: later[keys.STATE], **factors}, None))
        for row, expected in rows:
            env.reset(seed=7)
            _, again = env.reset(seed=8, options=env.reset_options_from_dataset(row, goal_row))
            np.testing.assert_array_equal(again[keys.STATE], row[keys.STATE])
            np.testing.assert_array_equal(again[keys.GOAL_STATE], goal_row[keys.STATE])
            np.testing.assert_array_equal(again[keys.GOAL], info[keys.GOAL])
            if expected is not None:
                np.testing.assert_array_equal(env.render(), expected)
        upstream_row = {k: later[k] for k in ("qpos", "qvel", "button_states") if k in later}  # no "state" column
        _, again = env.reset(seed=8, options=env.reset_options_from_dataset(upstream_row, goal_row))
        np.testing.assert_array_equal(again[keys.STATE], later[keys.STATE])


def test_success_follows_ogbench_rule(cube, scene):
    _, info = cube.reset(seed=0)
    goal, start = info[keys.GOAL_STATE], info[keys.STATE]
    assert cube.eval_state(goal, goal) == (True, 0.0)
    assert cube.eval_state(goal, start)[0] is False
    adr = cube._cube_qpos[0]
    for shift, ok in ((0.035, True), (0.045, False)):
        moved = goal.copy()
        moved[adr] += shift
        assert cube.eval_state(goal, moved)[0] is ok
    _, _, terminated, _, info = cube.step(np.zeros(5, np.float32))
    assert not terminated and info["success"] is False
    cube.reset(seed=0, options={keys.STATE: goal})
    _, reward, terminated, truncated, info = cube.step(np.zeros(5, np.float32))
    assert terminated and info["success"] is True and reward == 1.0 and not truncated

    _, info = scene.reset(seed=0)
    goal = info[keys.GOAL_STATE]
    flipped = goal.copy()
    flipped[-1] = 1 - flipped[-1]
    assert scene.eval_state(goal, goal)[0] and not scene.eval_state(goal, flipped)[0]
    drawer = goal.copy()
    drawer[scene._slide_qpos[0]] += 0.05
    assert not scene.eval_state(goal, drawer)[0]


def test_multiview_pixels_and_render_size():
    env = CubeEnv(multiview=True, ob_type="pixels")
    env.set_render_size((12, 20))
    obs, _ = env.reset(seed=0)
    assert obs.shape == env.observation_space.shape == (12, 20, 3)
    views = env.render_multiview()
    assert list(views) == ["front", "front_pixels", "side_pixels", "side"]
    assert all(v.shape == (12, 20, 3) and v.dtype == np.uint8 for v in views.values())
    np.testing.assert_array_equal(views["front_pixels"], env.render())
    env.close()
    assert env.render().shape == (12, 20, 3)  # a closed env renders again on demand
    env.close()


def test_floor_colour_reaches_a_live_renderer(cube):
    values = {keys.VARIATION_VALUES: {"floor.color": [[0.9, 0.1, 0.1], [0.1, 0.9, 0.1]]}}
    cube.reset(seed=0)
    cube.render()  # the renderer exists before the floor changes
    cube.reset(seed=0, options=values)
    fresh = CubeEnv()
    fresh.set_render_size(SIZE)
    fresh.reset(seed=0, options=values)
    np.testing.assert_array_equal(cube.render(), fresh.render())
    fresh.close()


def test_set_new_target_keeps_the_state(cube):
    _, info = cube.reset(seed=0)
    obs, new = cube.set_new_target()
    np.testing.assert_array_equal(new[keys.STATE], info[keys.STATE])
    assert not np.array_equal(new[keys.GOAL_STATE], info[keys.GOAL_STATE])


def _expert_episode(env, expert, seed, steps):
    _, info = env.reset(seed=seed)
    for t in range(steps):
        batch = {k: np.asarray(v)[None, None] for k, v in info.items() if k.startswith(("proprio.", "privileged."))}
        batch[keys.STEP_IDX] = np.array([[t]])
        _, _, terminated, _, info = env.step(expert.get_action(batch)[0])
        if terminated:
            return True
    return False


def test_expert_solves_single_cube_episodes(cube):
    expert = OGBenchExpert(seed=0)
    assert all(_expert_episode(cube, expert, seed, 200) for seed in range(3))


def test_expert_solves_a_scene_episode(scene):
    assert _expert_episode(scene, OGBenchExpert("swm/OGBScene-v0", seed=0), 1, 750)


def test_typed_errors(cube):
    with pytest.raises(ConfigError, match="env_type in .*'single'.*got 'singel'.*Did you mean 'single'"):
        CubeEnv(env_type="singel")
    with pytest.raises(ConfigError, match="render_quality"):
        CubeEnv(render_quality="ultra")
    with pytest.raises(ConfigError, match="ob_type"):
        CubeEnv(ob_type="rgb")
    with pytest.raises(ConfigError, match="env_type 'scene'"):
        SceneEnv(env_type="cube")
    with pytest.raises(ConfigError, match="list of factor names"):
        cube.reset(seed=0, options={keys.VARIATION: "cube.color"})
    with pytest.raises(UnknownNameError, match="cube.colour.*Did you mean .*'cube.color'"):
        cube.reset(seed=0, options={keys.VARIATION: ["cube.colour"]})
    with pytest.raises(UnknownNameError, match="light.intensty"):
        cube.reset(seed=0, options={keys.VARIATION_VALUES: {"light.intensty": [0.5]}})
    with pytest.raises(ConfigError, match="41 finite numbers"):
        cube.reset(seed=0, options={keys.STATE: np.zeros(5)})
    with pytest.raises(ConfigError, match="options as a dict"):
        cube.reset(seed=0, options=["state"])
    with pytest.raises(SpaceError):
        cube.reset(seed=0, options={keys.VARIATION_VALUES: {"cube.size": [0.5]}})
    with pytest.raises(ConfigError, match="noise"):
        OGBenchExpert(noise=-1.0)


def test_an_expert_cube_dataset_trains_lewm(tmp_path, monkeypatch):
    """What `swm collect swm/OGBCube-v0 --policy expert` then `swm train lewm` do, tiny: the loss falls."""
    import torch

    from stable_worldmodel import World
    from stable_worldmodel.data import HDF5Dataset
    from stable_worldmodel.envs import expert_policy
    from stable_worldmodel.train import train

    monkeypatch.setenv("STABLEWM_HOME", str(tmp_path))
    with World(
        "swm/OGBCube-v0", 2, SIZE, max_episode_steps=12, verbose=0, vectorization_mode="sync", render_quality="low"
    ) as world:
        world.set_policy(expert_policy("swm/OGBCube-v0", noise=0.1, seed=0))
        world.record_dataset("cube", episodes=4, seed=0, cache_dir=tmp_path)
    data = HDF5Dataset("cube", cache_dir=tmp_path)
    assert data.num_episodes == 4 and {keys.PIXELS, keys.ACTION, keys.PROPRIO}.issubset(data.column_names)
    threads = torch.get_num_threads()
    torch.set_num_threads(1)
    try:
        result = train(
            "lewm",
            "cube",
            "tiny",
            steps=40,
            frameskip=1,
            device="cpu",
            seed=0,
            progress=False,
            cache_dir=str(tmp_path),
            log_every=5,
            image_size=16,
            embed_dim=16,
            cnn_width=8,
            depth=1,
            heads=2,
            dim_head=8,
            mlp_dim=32,
            projector_hidden=32,
            sigreg_num_proj=64,
            batch_size=8,
            warmup_steps=5,
        )
    finally:
        torch.set_num_threads(threads)
    losses = [r["train/loss"] for r in result.history if "train/loss" in r]
    assert result.steps == 40 and np.isfinite(losses).all()
    assert np.mean(losses[-2:]) < 0.8 * np.mean(losses[:2]), losses


def _arm_mesh(model, name="ur5e/upperarm_3"):
    i = model.mesh(name).id
    v0, f0 = model.mesh_vertadr[i], model.mesh_faceadr[i]
    return model.mesh_vert[v0 : v0 + model.mesh_vertnum[i]], model.mesh_face[f0 : f0 + model.mesh_facenum[i]]


def test_ogbench_decimated_meshes_are_cached_on_disk_and_reused(cube, tmp_path, monkeypatch):
    from stable_worldmodel.envs.ogbench import manip, meshes

    cube.reset(seed=0)
    model = manip._MODELS[cube._model_key()]
    verts, faces = _arm_mesh(model)
    small_v, small_f = meshes.decimate(verts, faces, 0.1)
    assert len(small_f) <= 0.12 * len(faces) and small_v.shape[1] == 3 and small_f.max() < len(small_v)
    assert len(list((tmp_path / "stablewm_home" / "meshes").glob("*.npz"))) == 1  # $STABLEWM_HOME (conftest)
    monkeypatch.setattr(meshes, "_simplify", lambda *a: pytest.fail("decimated again instead of reading the cache"))
    again_v, again_f = meshes.decimate(verts, faces, 0.1)
    np.testing.assert_array_equal(again_v, small_v)
    np.testing.assert_array_equal(again_f, small_f)
    with pytest.raises(pytest.fail.Exception):  # another ratio is another cache entry
        meshes.decimate(verts, faces, 0.2)


def test_ogbench_decimated_arm_draws_the_same_64px_frame(cube):
    from stable_worldmodel.envs.mujoco_render import MjRenderer

    cube.reset(seed=3)
    cube.step(np.array([0.5, -0.5, -0.5, 0.3, 1.0], np.float32))
    light = cube._mesh_model()
    assert light is not None and light.mesh_facenum.sum() < 0.3 * cube._model.mesh_facenum.sum()
    frames = []
    for mesh_model in (None, light):
        r = MjRenderer(cube._model, 64, 64, "medium", mesh_model=mesh_model)
        frames.append(r.render(cube._data, "front_pixels").astype(np.int64))
        r.close()
    assert np.abs(frames[0] - frames[1]).mean() < 2.0  # measured ~1/255; a misplaced mesh gives > 5


def test_ogbench_decimation_reaches_its_target_on_every_arm_mesh(cube):
    from stable_worldmodel.envs.ogbench import meshes

    cube.reset(seed=0)
    exact, light = cube._model, cube._mesh_model()
    for i in range(exact.nmesh):  # quadric collapse alone stalled at 54 % of the gripper mount's faces
        n = int(exact.mesh_facenum[i])
        assert light.mesh_facenum[i] <= (0.12 * n if n >= meshes.MIN_FACES else n), exact.mesh(i).name


def test_ogbench_floor_is_drawn_coarser_and_left_out_of_the_shadow_map_below_high(cube):
    from stable_worldmodel.envs.ogbench import meshes

    cube.reset(seed=0)
    floor = cube._floor_geoms()
    assert len(floor) == 1 and cube._model.geom_size[floor[0], 2] == pytest.approx(0.01)  # OGBench's 1 cm grid
    assert cube._mesh_model().geom_size[floor[0], 2] == pytest.approx(meshes.PLANE_GRID["medium"])
    cube.render()
    assert cube._mjr._shadowless == frozenset(floor)
    high = CubeEnv(render_quality="high")
    high.set_render_size(SIZE)
    high.reset(seed=0)
    high.render()
    assert high._mjr._shadowless == frozenset() and meshes.PLANE_GRID["high"] is None  # upstream's picture
    high.close()
    for bad in (0, "3cm"):
        with pytest.raises(ConfigError, match="plane_grid > 0"):
            meshes.render_mesh_model(cube._model, "<mujoco/>", {}, 0.1, plane_grid=bad)


def test_ogbench_high_quality_keeps_exact_meshes_and_decimation_errors_are_typed(cube):
    from stable_worldmodel.envs.mujoco_render import MjRenderer
    from stable_worldmodel.envs.ogbench import meshes
    from stable_worldmodel.envs.ogbench.manip import mujoco

    high = CubeEnv(render_quality="high")
    assert high._mesh_model() is None and meshes.MESH_DETAIL["high"] is None
    high.close()
    for bad in (0, -0.5, 1.5, "x", None, True):
        with pytest.raises(ConfigError, match="ratio in \\(0, 1\\]"):
            meshes.check_ratio(bad)
    with pytest.raises(ConfigError, match="vertices \\(V, 3\\) and faces \\(F, 3\\)"):
        meshes.decimate(np.zeros((4, 2)), np.zeros((2, 3), np.int32), 0.5)
    cube.reset(seed=0)
    other = mujoco.MjModel.from_xml_string("<mujoco><worldbody><geom size='1'/></worldbody></mujoco>")
    with pytest.raises(ConfigError, match="mesh_model with the same ngeom"):
        MjRenderer(cube._model, 16, 16, "medium", mesh_model=other)
    r = MjRenderer(cube._model, 16, 16, "low")
    with pytest.raises(ConfigError, match="camera of the model, got 'front_pixel'. Did you mean .*'front_pixels'"):
        r.render(cube._data, "front_pixel")
    r.close()

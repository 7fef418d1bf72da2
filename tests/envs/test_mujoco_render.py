"""Headless MuJoCo rendering: backend choice, render quality, and closing renderers safely."""

from __future__ import annotations

import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np
import pytest

from stable_worldmodel._optional import is_available
from stable_worldmodel.envs import mujoco_render
from stable_worldmodel.errors import ConfigError, DependencyNotInstalled

# never import mujoco here before setup_gl(): it picks its GL backend on import
pytestmark = pytest.mark.skipif(not is_available("mujoco"), reason="extra 'mujoco' not installed")

XML = """<mujoco><visual><global offwidth="16" offheight="16"/></visual><worldbody>
<light pos="0 0 2" castshadow="true"/><geom type="plane" size="1 1 .1" rgba=".3 .6 .3 1"/>
<geom type="box" size=".1 .1 .1" pos="0 0 .1" rgba="1 0 0 1"/>
<camera name="c" pos="0 -1 .6" xyaxes="1 0 0 0 .5 1"/></worldbody></mujoco>"""


@pytest.fixture(scope="module")
def scene():
    mujoco_render.setup_gl()
    import mujoco

    model = mujoco.MjModel.from_xml_string(XML)
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    return model, data


def test_setup_gl_picks_egl_headless_and_refuses_a_mismatched_platform():
    code = (
        "import os; os.environ.pop('DISPLAY', None); os.environ.pop('WAYLAND_DISPLAY', None);"
        "os.environ.pop('MUJOCO_GL', None); os.environ.pop('PYOPENGL_PLATFORM', None);"
        "from stable_worldmodel.envs.mujoco_render import setup_gl; print(setup_gl(), os.environ['PYOPENGL_PLATFORM'])"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert out.stdout.split() == ["egl", "egl"]


_HEADLESS = (
    "import os; [os.environ.pop(k, None) for k in ('DISPLAY', 'WAYLAND_DISPLAY', 'MUJOCO_GL', 'PYOPENGL_PLATFORM')];"
)


def test_importing_the_package_sets_no_environment_variable():
    code = _HEADLESS + (
        "before = dict(os.environ); import stable_worldmodel, sys; "
        "print(dict(os.environ) == before, 'mujoco' in sys.modules)"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert out.stdout.split() == ["True", "False"], out.stderr[-2000:]


@pytest.mark.parametrize(
    "first", ["import stable_worldmodel; import mujoco", "import mujoco; import stable_worldmodel"]
)
def test_mujoco_imported_before_our_envs_still_renders_headless(first):
    """``mujoco`` imported before MUJOCO_GL was chosen picks GLFW (no display): setup_gl points its
    renderer at EGL, whatever the import order."""
    code = (
        _HEADLESS
        + first
        + (
            "; from stable_worldmodel.envs.mujoco_render import MjRenderer, setup_gl;"
            f"print(setup_gl()); m = mujoco.MjModel.from_xml_string({XML!r}); d = mujoco.MjData(m); "
            "mujoco.mj_forward(m, d); r = MjRenderer(m, 16, 16); "
            "print(os.environ['MUJOCO_GL'], os.environ['PYOPENGL_PLATFORM'], r.render(d, 'c').std() > 0); r.close()"
        )
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert out.stdout.split() == ["egl", "egl", "egl", "True"], out.stderr[-2000:]


def test_mujoco_imported_first_with_egl_unloadable_gets_a_typed_error():
    code = _HEADLESS + (
        "import mujoco; os.environ['PYOPENGL_PLATFORM'] = 'glx'\n"
        "from stable_worldmodel.envs.mujoco_render import setup_gl\n"
        "try:\n    setup_gl()\nexcept Exception as e:\n    print(type(e).__name__, e)"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert out.stdout.startswith("ConfigError mujoco was imported before MUJOCO_GL was set"), out.stderr[-2000:]
    assert "MUJOCO_GL=egl" in out.stdout


def test_setup_gl_errors(monkeypatch):
    monkeypatch.setenv("MUJOCO_GL", "egl")
    monkeypatch.setenv("PYOPENGL_PLATFORM", "osmesa")
    with pytest.raises(ConfigError, match="PYOPENGL_PLATFORM unset or 'egl', got 'osmesa'"):
        mujoco_render.setup_gl()
    from stable_worldmodel import _optional

    monkeypatch.setattr(_optional, "is_available", lambda m: m != "dm_control")
    with pytest.raises(DependencyNotInstalled, match=r'dm_control.*pip install "stable-worldmodel\[mujoco\]"'):
        mujoco_render.setup_gl()


def test_render_quality_and_its_errors(scene):
    model, data = scene
    frames = {}
    for quality in mujoco_render.RENDER_QUALITIES:
        r = mujoco_render.MjRenderer(model, 16, 16, quality)
        frames[quality] = r.render(data, "c").astype(np.int64)
        r.close()
        assert frames[quality].shape == (16, 16, 3)
    assert model.vis.quality.shadowsize == 4096  # the model's settings are restored
    assert np.abs(frames["medium"] - frames["high"]).mean() < 2.0  # the same picture
    assert np.abs(frames["low"] - frames["high"]).mean() > 2.0  # no shadows
    with pytest.raises(
        ConfigError, match="render_quality in \\['low', 'medium', 'high'\\], got 'hihg'. Did you mean 'high'"
    ):
        mujoco_render.MjRenderer(model, 16, 16, "hihg")


def test_shadowless_geoms_stay_out_of_the_shadow_map_only(scene):
    model, data = scene  # geom 0: the floor, geom 1: the box; the light straight above
    frames = {}
    for name, geoms in (("all", ()), ("floor", [0]), ("box", np.array([1]))):
        r = mujoco_render.MjRenderer(model, 16, 16, "medium", shadowless=geoms)
        frames[name] = r.render(data, "c").astype(np.int64)
        r.close()
    np.testing.assert_array_equal(frames["floor"], frames["all"])  # the floor could only shadow itself
    assert np.abs(frames["box"] - frames["all"]).mean() > 0.3  # the box's shadow is gone (measured 0.74)
    for bad in ([2], [-1], ["0"], [True], [0.0]):
        with pytest.raises(ConfigError, match="shadowless geom ids in \\[0, 2\\)"):
            mujoco_render.MjRenderer(model, 16, 16, shadowless=bad)


def test_closing_one_renderer_leaves_the_other_intact(scene):
    model, data = scene
    a, b = mujoco_render.MjRenderer(model, 16, 16), mujoco_render.MjRenderer(model, 16, 16)
    ref = a.render(data, "c")
    b.render(data, "c")  # b's context is now the current one
    b.close()
    np.testing.assert_array_equal(a.render(data, "c"), ref)
    b.close()  # closing twice is harmless
    with pytest.raises(RuntimeError, match="after close"):
        b.render(data, "c")
    a.close()


@pytest.mark.parametrize("env_id", ["swm/OGBCube-v0", "swm/CheetahDMControl-v0"])
def test_worker_processes_render_after_torch_was_imported(env_id):
    """0.0.3's dmc/ogb docs import torch first, then run a World with worker processes: the
    workers start clean (forkserver once torch is loaded) and render headless."""
    code = _HEADLESS + (
        "import torch, stable_worldmodel as swm\n"
        "if __name__ == '__main__':\n"
        f"    w = swm.World({env_id!r}, num_envs=2, image_shape=(16, 16), max_episode_steps=3, verbose=0,\n"
        "                  vectorization_mode='async', render_quality='low')\n"
        "    w.set_policy(swm.policy.RandomPolicy(seed=0)); w.reset(seed=0); w.step()\n"
        "    print(w.envs.mode, w.infos['pixels'].shape, int(w.infos['pixels'].std() > 0)); w.close()\n"
    )
    script = Path(tempfile.mkdtemp()) / "user_script.py"
    script.write_text(code)
    out = subprocess.run([sys.executable, str(script)], capture_output=True, text=True, timeout=240)
    assert out.stdout.split() == ["async", "(2,", "1,", "16,", "16,", "3)", "1"], out.stderr[-2000:]

"""Headless MuJoCo rendering shared by the MuJoCo env families (OGBench, DeepMind Control).

Our MuJoCo env modules call :func:`setup_gl` before they import ``mujoco``: MuJoCo picks its GL
backend from ``MUJOCO_GL`` when it is first imported. On Linux without a display we choose EGL
(``MUJOCO_GL=egl``, ``PYOPENGL_PLATFORM=egl``); a value the user set is kept. ``import
stable_worldmodel`` sets nothing: the choice is made when a MuJoCo env is first made, and if the
user imported ``mujoco`` before that (it then picked GLFW, which cannot render headless), its
renderer is pointed at EGL instead.

Traps this module handles (measured here, EGL on a CPU):

- ``mujoco.Renderer.close`` frees its GL objects in whichever context is *current*: closing one
  renderer while another's context is current corrupts the survivor's frames.
  :meth:`MjRenderer.close` makes its own context current first, and so does its ``__del__``.
- dm_control's ``physics.render`` caches "the current context" per thread and skips the
  rebind, so interleaving it with ``mujoco.Renderer`` in one thread gives wrong frames. Our envs
  render every family through :class:`MjRenderer` (the frames equal ``physics.render``'s), so
  nothing is interleaved.
- Shadows dominate CPU rendering: MuJoCo's default 4096-px shadow map makes a 64x64 frame cost
  ~70 ms. ``render_quality`` picks the trade-off (see :data:`RENDER_QUALITIES`).
"""

from __future__ import annotations

import atexit
import os
import sys
import weakref
from collections.abc import Iterable
from typing import Any

import numpy as np

from ..errors import ConfigError, did_you_mean

#: ``"high"``: MuJoCo's own settings (4096-px shadow map, 4x multisampling), as upstream renders;
#: ``"medium"`` (the default): the shadow map scaled to the frame (8x its larger side, 256 to
#: 4096 px), which draws the same picture (mean absolute difference ~1/255 at 64x64) ~2x faster;
#: ``"low"``: no shadows, no multisampling, ~8x faster than ``"high"``, a visibly flatter picture.
#: Env families may also draw lighter meshes below ``"high"`` (``MjRenderer(mesh_model=...)``;
#: the OGBench arm: :mod:`stable_worldmodel.envs.ogbench.meshes`).
RENDER_QUALITIES = ("low", "medium", "high")


def default_gl_backend() -> str | None:
    """``MUJOCO_GL`` after choosing EGL where MuJoCo could not render otherwise (no mujoco import).

    On Linux without ``DISPLAY`` / ``WAYLAND_DISPLAY``, an unset ``MUJOCO_GL`` becomes ``"egl"``
    while ``mujoco`` is not imported yet.
    """
    backend = os.environ.get("MUJOCO_GL")
    if backend is None and _headless_linux() and "mujoco" not in sys.modules:
        backend = os.environ["MUJOCO_GL"] = "egl"
    return backend


def _adopt_egl() -> bool:
    """Point an already imported ``mujoco`` (which picked GLFW, headless) at EGL: the GL context
    its ``Renderer`` makes, and ``mujoco.GLContext``. False where EGL cannot load (PyOpenGL set up
    for another platform, no libEGL)."""
    import importlib

    import mujoco

    try:
        egl = importlib.import_module("mujoco.egl")
    except (ImportError, OSError, AttributeError):
        return False
    sys.modules[mujoco.Renderer.__module__].gl_context.GLContext = egl.GLContext
    mujoco.GLContext = egl.GLContext
    os.environ["MUJOCO_GL"] = "egl"  # what dm_control, imported later, reads
    return True


def _headless_linux() -> bool:
    return sys.platform.startswith("linux") and not (os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"))


def setup_gl(extra: str = "mujoco", what: str = "the MuJoCo environments") -> str | None:
    """Choose the GL backend before ``mujoco`` is imported; returns ``MUJOCO_GL``.

    On Linux without ``DISPLAY`` / ``WAYLAND_DISPLAY``, an unset ``MUJOCO_GL`` becomes ``"egl"``
    (:func:`default_gl_backend`). For ``egl`` / ``osmesa``, an unset ``PYOPENGL_PLATFORM`` is set
    to match (dm_control and PyOpenGL read it); a different value raises, since frames would come
    from the wrong library. When ``mujoco`` was imported headless before ``MUJOCO_GL`` was set, it
    has picked GLFW, which cannot render without a display: its renderer is pointed at EGL
    (ConfigError saying how to fix it where EGL cannot load).
    Raises :class:`~stable_worldmodel.errors.DependencyNotInstalled` (with the pip command) when
    the modules of ``extra`` (default ``mujoco``: mujoco, dm_control, ogbench) are not installed;
    ``what`` names the envs that need them.
    """
    from .._optional import EXTRA_MODULES, is_available
    from ..errors import DependencyNotInstalled

    missing = [m for m in EXTRA_MODULES[extra] if not is_available(m)]
    if missing:
        raise DependencyNotInstalled(
            f"{what} require {', '.join(missing)}, which is not installed. "
            f'Install it with: pip install "stable-worldmodel[{extra}]"'
        )
    backend = default_gl_backend()
    if backend is None and _headless_linux():
        if not _adopt_egl():
            raise ConfigError(
                "mujoco was imported before MUJOCO_GL was set, so it picked GLFW, which cannot render without a "
                "display, and EGL could not be loaded instead; set MUJOCO_GL=egl in the environment"
            )
        backend = "egl"
    if backend in ("egl", "osmesa"):
        platform = os.environ.setdefault("PYOPENGL_PLATFORM", backend)
        if platform != backend:
            raise ConfigError(
                f"MUJOCO_GL={backend!r} requires PYOPENGL_PLATFORM unset or {backend!r}, got {platform!r}; "
                f"unset PYOPENGL_PLATFORM or set both to the same backend"
            )
    return backend


def check_render_quality(owner: str, quality: Any) -> str:
    """``quality`` if it is one of :data:`RENDER_QUALITIES`; ConfigError naming ``owner`` otherwise."""
    if quality not in RENDER_QUALITIES:
        raise ConfigError(
            f"{owner} requires render_quality in {list(RENDER_QUALITIES)}, got "
            f"{quality!r}.{did_you_mean(str(quality), RENDER_QUALITIES)}"
        )
    return quality


_LIVE: weakref.WeakSet = weakref.WeakSet()
_GL_STARTED: list[bool] = []


def gl_started() -> bool:
    """Whether this process has made a GL context to render MuJoCo (then env workers are not forked)."""
    return bool(_GL_STARTED)


_AT_EXIT: list[bool] = []


def _close_live_renderers() -> None:
    """Free every open renderer before EGL's own exit handler terminates the display
    (registered on the first renderer, after mujoco's import, so it runs first); otherwise
    their ``__del__`` fails noisily at exit."""
    for renderer in list(_LIVE):
        try:
            renderer.close()
        except Exception:
            pass


def _matching_mesh_model(model, mesh_model):
    """``mesh_model`` after checking it matches ``model`` and copying ``model``'s textures and
    statistics (shadow and fog extents) into it."""
    counts = ("ngeom", "nmesh", "ntex", "ntexdata", "nmat", "nskin", "nflex", "nlight", "ncam")
    wrong = [c for c in counts if getattr(model, c) != getattr(mesh_model, c)]
    if wrong:
        raise ConfigError(
            f"MjRenderer requires mesh_model with the same {', '.join(wrong)} as model, got "
            + ", ".join(f"{c} {getattr(mesh_model, c)} (model: {getattr(model, c)})" for c in wrong)
            + "; compile mesh_model from the same description"
        )
    np.copyto(mesh_model.tex_data, model.tex_data)
    for name in ("extent", "center", "meansize", "meanmass", "meaninertia"):
        setattr(mesh_model.stat, name, getattr(model.stat, name))
    return mesh_model


class MjRenderer:
    """An offscreen renderer of one ``mujoco.MjModel`` at ``(height, width)`` and a quality.

    ``render(data, camera)`` returns a fresh ``(H, W, 3)`` uint8 frame. The quality settings live
    in the model's ``vis.quality`` (read when the GL context is made), so they are applied here,
    before the context exists; the model's own values are restored right after.

    ``mesh_model`` (optional): a model compiled from the same description whose meshes have fewer
    faces (a level of detail, e.g. :mod:`stable_worldmodel.envs.ogbench.meshes`), with its mesh
    vertices in ``model``'s mesh frames. Its meshes are the ones uploaded to the GL context; the
    scene (poses, colours, lights, cameras) still comes from ``model`` and ``data``, and ``model``'s
    textures are copied into it first (factors may have changed them). ConfigError when its
    geoms, meshes or textures do not match ``model``'s. Its planes' grid spacing (``geom_size[:, 2]``,
    which only sets how finely MuJoCo tessellates a plane for drawing) may differ from ``model``'s:
    a coarser grid is a level of detail of the floor.

    ``shadowless`` (optional; nothing to do at ``"low"``, which draws no shadows): ids of ``model``
    geoms left out of the shadow map. They are drawn, lit and shadowed as usual but cast
    no shadow: meant for a floor that nothing lies below (it could only shadow itself), which
    otherwise costs a full draw into the shadow map every frame.
    """

    def __init__(
        self, model, height: int, width: int, quality: str = "medium", mesh_model=None, shadowless: Iterable[int] = ()
    ):
        import mujoco

        self.quality = check_render_quality("MjRenderer", quality)
        self.height, self.width = int(height), int(width)
        self._model = model
        shadowless = self._check_geoms(shadowless)
        gl_model = model if mesh_model is None else _matching_mesh_model(model, mesh_model)
        vis = gl_model.vis
        saved = (vis.global_.offwidth, vis.global_.offheight, vis.quality.shadowsize, vis.quality.offsamples)
        vis.global_.offwidth = max(vis.global_.offwidth, self.width)
        vis.global_.offheight = max(vis.global_.offheight, self.height)
        if quality == "medium":
            vis.quality.shadowsize = int(min(saved[2], max(256, 8 * max(self.height, self.width))))
        elif quality == "low":
            vis.quality.offsamples = 0
        try:
            self._renderer = mujoco.Renderer(gl_model, self.height, self.width)
        finally:
            vis.global_.offwidth, vis.global_.offheight, vis.quality.shadowsize, vis.quality.offsamples = saved
        self._shadows = quality != "low"
        self._shadowless = shadowless if self._shadows else frozenset()
        self._option = mujoco.MjvOption()
        self._camera = mujoco.MjvCamera()
        self._camera_ids: dict[str, int] = {}
        _LIVE.add(self)
        _GL_STARTED[:] = [True]
        if not _AT_EXIT:
            atexit.register(_close_live_renderers)
            _AT_EXIT.append(True)

    def upload_texture(self, model, texture: int) -> bool:
        """Send ``model``'s texture ``texture`` (changed in place, e.g. a colour factor) to this renderer's
        GL context; False when it has no context to send it to (closed: a new one reads the model)."""
        import mujoco

        inner = self._renderer  # mujoco.Renderer: its GL and MuJoCo contexts
        gl, con = getattr(inner, "_gl_context", None), getattr(inner, "_mjr_context", None)
        if con is None:
            return False
        if gl is not None:
            gl.make_current()
        mujoco.mjr_uploadTexture(model, con, texture)
        return True

    def render(self, data, camera: int | str = -1, scene_option=None) -> np.ndarray:
        """The frame of ``data`` seen from ``camera`` (id, name, or -1 for the free camera)."""
        import mujoco

        r = self._renderer
        if r is None:
            raise RuntimeError("MjRenderer.render called after close()")
        cam = self._camera
        cam_id = self._camera_id(camera)
        if cam_id == -1:
            cam.type = mujoco.mjtCamera.mjCAMERA_FREE
            mujoco.mjv_defaultFreeCamera(self._model, cam)
        else:
            cam.type, cam.fixedcamid = mujoco.mjtCamera.mjCAMERA_FIXED, cam_id
        option = self._option if scene_option is None else scene_option
        # the scene from the physics model (not the renderer's, which may be mesh_model)
        mujoco.mjv_updateScene(self._model, data, option, None, cam, mujoco.mjtCatBit.mjCAT_ALL.value, r.scene)
        if not self._shadows:
            r.scene.flags[mujoco.mjtRndFlag.mjRND_SHADOW] = False
        elif self._shadowless:
            self._drop_from_shadow_map(r.scene)
        return r.render()

    def _check_geoms(self, geoms: Iterable[int]) -> frozenset[int]:
        ids = list(geoms)
        ngeom = self._model.ngeom
        wrong = [g for g in ids if isinstance(g, bool) or not isinstance(g, (int, np.integer)) or not 0 <= g < ngeom]
        if wrong:
            raise ConfigError(f"MjRenderer requires shadowless geom ids in [0, {ngeom}), got {wrong}")
        return frozenset(int(g) for g in ids)

    def _drop_from_shadow_map(self, scene) -> None:
        """mjr_render draws every scene geom into the shadow map except decorative ones, and reads
        the category nowhere else: marking a geom decorative keeps it out of the map only."""
        import mujoco

        geom, decor, left = mujoco.mjtObj.mjOBJ_GEOM.value, mujoco.mjtCatBit.mjCAT_DECOR.value, len(self._shadowless)
        for i in range(scene.ngeom):
            g = scene.geoms[i]
            if g.objtype == geom and g.objid in self._shadowless:
                g.category = decor
                left -= 1
                if not left:
                    break

    def _camera_id(self, camera: int | str) -> int:
        if isinstance(camera, str):
            if camera not in self._camera_ids:
                import mujoco

                cam_id = mujoco.mj_name2id(self._model, mujoco.mjtObj.mjOBJ_CAMERA.value, camera)
                if cam_id == -1:
                    names = [self._model.camera(i).name for i in range(self._model.ncam)]
                    raise ConfigError(
                        f"MjRenderer requires a camera of the model, got {camera!r}.{did_you_mean(camera, names)}"
                    )
                self._camera_ids[camera] = cam_id
            return self._camera_ids[camera]
        cam_id = int(camera)
        if not -1 <= cam_id < self._model.ncam:
            raise ConfigError(f"MjRenderer requires a camera id in [-1, {self._model.ncam}), got {camera!r}")
        return cam_id

    @property
    def scene(self):
        """The ``mujoco.MjvScene`` of the last ``render`` (for callbacks that add geoms)."""
        return self._renderer.scene

    def close(self) -> None:
        """Free the GL resources in this renderer's own context (never in another's)."""
        r, self._renderer = getattr(self, "_renderer", None), None
        if r is None:
            return
        context = getattr(r, "_gl_context", None)
        if context is not None:
            context.make_current()
        r.close()

    def __del__(self) -> None:
        try:
            self.close()
        except Exception:  # interpreter shutdown: the GL library may already be gone
            pass


class OwnsRenderer:
    """Mixin of an env that draws through one lazily made :class:`MjRenderer` kept in ``self._mjr``
    (made at the first render, dropped when the frame size changes or the env closes)."""

    _mjr: MjRenderer | None = None

    def _upload_texture(self, texture: int) -> None:
        """Send a changed texture of ``self._model`` to the live GL context (a new context reads the model anyway)."""
        if self._mjr is not None and not self._mjr.upload_texture(self._model, texture):
            self._close_renderer()

    def _close_renderer(self) -> None:
        r, self._mjr = self._mjr, None
        if r is not None:
            r.close()

"""Building and recompiling the MuJoCo model of a DeepMind Control env.

The first model of a (domain, task) is compiled once per process, with the structural factors
at their defaults, and copied for every env (``copy.deepcopy`` of an ``MjModel`` is a memcpy).

When a structural factor (density, mass, size, shape) changes, :class:`ModelEditor` edits a
``mujoco.MjSpec`` of the same XML with its textures removed (compiling dm_control's 800 x 4800
skybox is what makes a full compile take ~50 ms; without textures it takes ~1 ms) and copies
the new model's arrays into the live model in place, except texture and name arrays. The live
``MjModel`` object, its ``MjData`` and the renderers bound to it stay valid.

The floor color is the "grid" checker texture: :func:`grid_texture` compiles that one texture
with the new colors (MuJoCo's own texture builder, so the bytes match a full compile) and the
env writes it into ``tex_data``; renderers upload textures when made, so the env drops them.

:func:`solve_ik` finds the goal configurations of the tasks with a target (Reacher, Finger).
"""

from __future__ import annotations

import copy
import threading
import warnings
from collections.abc import Callable, Mapping
from typing import Any, NamedTuple

import numpy as np

_CACHE: dict[Any, Any] = {}
_LOCK = threading.Lock()
#: arrays never copied from a recompiled model: textures (handled apart) and names (the texture-free
#: spec has fewer names)
_SKIP_PREFIXES = ("tex_", "name_", "names", "mat_texid", "paths")
_STAT_FIELDS = ("meaninertia", "meanmass", "meansize", "extent", "center")
GRID = "grid"
_GRID_XML = (
    '<mujoco><asset><texture name="grid" type="2d" builtin="checker" rgb1="{} {} {}" rgb2="{} {} {}" '
    'width="{}" height="{}" mark="edge" markrgb=".2 .3 .4"/></asset></mujoco>'
)


def parse_spec(xml: str, assets: Mapping[str, bytes]):
    import mujoco

    return mujoco.MjSpec.from_string(xml, include=dict(assets))


def cached_model(key: Any, build: Callable[[], Any]):
    """A private copy of the model ``build()`` makes, compiled once per process for ``key``."""
    with _LOCK:
        if key not in _CACHE:
            _CACHE[key] = build()
        model = _CACHE[key]
    return copy.deepcopy(model)


class GeomOriginal(NamedTuple):
    """A geom as parsed: ``mass`` is NaN where the density decides it."""

    type: Any
    size: np.ndarray
    mass: float
    pos: np.ndarray


def geom_originals(spec) -> dict[str, GeomOriginal]:
    """Each named geom as parsed, before any factor edits it."""
    return {
        g.name: GeomOriginal(g.type, np.array(g.size, float), float(g.mass), np.array(g.pos, float))
        for g in spec.geoms
        if g.name
    }


def strip_textures(spec) -> None:
    """Remove every texture (and material reference to one) from ``spec``: physics is unchanged."""
    for tex in list(spec.textures):
        spec.delete(tex)
    for mat in spec.materials:
        mat.textures = [""] * len(mat.textures)


def _array_fields(model) -> list[str]:
    return [
        k
        for k in dir(model)
        if not k.startswith("_") and not k.startswith(_SKIP_PREFIXES) and isinstance(getattr(model, k), np.ndarray)
    ]


def copy_model_into(live, new) -> None:
    """Copy ``new``'s compiled arrays (same sizes) into ``live`` in place; textures and names excepted."""
    for k in _array_fields(live):
        dst, src = getattr(live, k), getattr(new, k)
        assert dst.shape == src.shape, f"recompiled model differs in {k}: {dst.shape} vs {src.shape}"  # our bug
        dst[...] = src
    for k in _STAT_FIELDS:
        setattr(live.stat, k, getattr(new.stat, k))


class ModelEditor:
    """Recompiles the structural factors of one env into its live model (spec parsed lazily)."""

    def __init__(self, xml: str, assets: Mapping[str, bytes]):
        self._xml, self._assets = xml, assets
        self._spec = None
        self.original: dict[str, GeomOriginal] = {}

    def spec(self):
        if self._spec is None:
            self._spec = parse_spec(self._xml, self._assets)
            self.original = geom_originals(self._spec)
            strip_textures(self._spec)
        return self._spec

    def recompile_into(self, live, edits: list[tuple[Any, np.ndarray]]) -> None:
        """Apply ``(effect, value)`` edits to the spec, compile and copy into ``live``."""
        spec = self.spec()
        for effect, value in edits:
            effect.edit(spec, value, self.original)
        copy_model_into(live, compile_spec(spec))


def build_default(xml: str, assets: Mapping[str, bytes], edits: list[tuple[Any, np.ndarray]]):
    """The full model (textures included) with the structural factors at their defaults."""
    spec = parse_spec(xml, assets)
    original = geom_originals(spec)
    for effect, value in edits:
        effect.edit(spec, value, original)
    return compile_spec(spec)


def compile_spec(spec):
    """``spec.compile()`` without MuJoCo's deprecation notice for dm_control's own ``settotalmass`` (cheetah)."""
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message="compiler attribute 'settotalmass' is deprecated")
        return spec.compile()


def grid_texture(model, rgb: np.ndarray) -> tuple[slice, np.ndarray] | None:
    """(slice of ``tex_data``, bytes) of the "grid" texture with checker colors ``rgb`` (2, 3); None without one."""
    import mujoco

    i = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_TEXTURE, GRID)
    if i < 0:
        return None
    h, w, c = int(model.tex_height[i]), int(model.tex_width[i]), int(model.tex_nchannel[i])
    colors = [repr(float(x)) for x in np.asarray(rgb, float).reshape(6)]
    tiny = mujoco.MjModel.from_xml_string(_GRID_XML.format(*colors, w, h))
    start = int(model.tex_adr[i])
    return slice(start, start + h * w * c), np.array(tiny.tex_data)


def solve_ik(
    model,
    kinematics: Callable[[np.ndarray], Any],
    qpos: np.ndarray,
    index: list[int],
    point: Callable[[Any], np.ndarray],
    target: np.ndarray,
    iters: int = 30,
) -> np.ndarray:
    """``qpos`` with the hinge angles at ``index`` moved so that ``point(kinematics(q))`` reaches ``target``.

    Damped Gauss-Newton on a finite-difference Jacobian from several starts (``qpos``, then a
    grid); angles are wrapped to [-pi, pi] and solutions outside a joint's range are dropped.
    The closest feasible solution wins (the start wins ties).
    """
    target = np.asarray(target, float)
    joints = [int(np.flatnonzero(model.jnt_qposadr == i)[0]) for i in index]
    low = np.where(model.jnt_limited[joints], model.jnt_range[joints, 0], -np.inf)
    high = np.where(model.jnt_limited[joints], model.jnt_range[joints, 1], np.inf)
    grid = np.linspace(-np.pi, np.pi, 5)[:-1]
    starts = [np.asarray(qpos, float)[index]] + [np.full(len(index), a) + np.arange(len(index)) for a in grid]
    best, best_err = np.asarray(qpos, float).copy(), np.inf
    for start in starts:
        q = np.asarray(qpos, float).copy()
        q[index] = start
        for _ in range(iters):
            here = point(kinematics(q)).copy()
            err = target - here
            jac = np.empty((err.shape[0], len(index)))
            for k, i in enumerate(index):
                dq = q.copy()
                dq[i] += 1e-6
                jac[:, k] = (point(kinematics(dq)) - here) / 1e-6
            q[index] += np.linalg.solve(jac.T @ jac + 1e-6 * np.eye(len(index)), jac.T @ err)
        q[index] = (q[index] + np.pi) % (2 * np.pi) - np.pi
        if np.any(q[index] < low) or np.any(q[index] > high):
            continue
        err = float(np.linalg.norm(target - point(kinematics(q))))
        if err < best_err - 1e-9:
            best, best_err = q, err
    return best

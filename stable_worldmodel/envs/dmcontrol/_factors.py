"""Factors of variation of the DeepMind Control envs: their spaces and what each one changes.

A :class:`Factor` is a dotted name, a space builder and an effect. Effects come in two kinds:

- **runtime** effects write the compiled ``mujoco.MjModel`` directly (colors, light, gravity,
  friction, target visibility and site shapes): a few array writes per reset;
- **structural** effects edit the ``mujoco.MjSpec`` (densities, masses, sizes, geom shapes,
  floor tilt): the env recompiles only when one of their values changed (see ``_model.py``);
- the floor color (:class:`FloorRGB`) rewrites the "grid" texture (the env handles it).

Spaces keep upstream 0.1.1's shapes, dtypes, bounds and defaults (observed): colors are
float64 ``Box(0, 1, (3,))``, densities float32 ``Box(500, 1500, (1,))``, switches ``Discrete(2)``.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from ... import spaces

FLOOR_RGB = ((0.1, 0.2, 0.3), (0.2, 0.3, 0.4))  # dm_control's "grid" checker colors
AGENT_RGB = (0.7, 0.5, 0.3)  # dm_control's "self" material
TARGET_RGB = (0.6, 0.3, 0.3)  # dm_control's "target" material
FRICTION_TAIL = (0.005, 0.0001)  # MuJoCo's torsional / rolling friction defaults


# -- spaces -------------------------------------------------------------------------------------
def _box(low, high, init, shape=(1,), dtype=np.float64) -> spaces.Box:
    return spaces.Box(low, high, shape=shape, dtype=dtype, init_value=np.asarray(init, dtype).reshape(shape))


def rgb(init=AGENT_RGB) -> spaces.Box:
    return _box(0.0, 1.0, init, (3,))


def density(init: float = 1000.0) -> spaces.Box:
    return _box(500.0, 1500.0, init, dtype=np.float32)


def switch(init: int = 1) -> spaces.Discrete:
    return spaces.Discrete(2, init_value=init)


def floor_rgb() -> spaces.Box:
    return _box(0.0, 1.0, FLOOR_RGB, (2, 3))


def friction(init: float = 1.0) -> spaces.Box:
    return _box(0.0, 1.0, init, dtype=np.float32)


def scalar(low: float, high: float, init: float, dtype=np.float64) -> spaces.Box:
    return _box(low, high, init, dtype=dtype)


# -- effects ------------------------------------------------------------------------------------
def _id(model, kind: str, name: str) -> int:
    import mujoco

    obj = getattr(mujoco.mjtObj, f"mjOBJ_{kind.upper()}")
    i = mujoco.mj_name2id(model, obj, name)
    assert i >= 0, f"no {kind} {name!r} in the model"  # our table names a missing element: our bug
    return i


class Effect:
    """What a factor changes. Runtime effects implement :meth:`apply`, structural ones :meth:`edit`.

    Runtime effects apply before the task starts the episode (dm_control's cheetah settles under
    gravity there), except those marked ``after_task`` (they build on sizes the task sets).
    """

    structural = False
    after_task = False

    def apply(self, model, value: np.ndarray, defaults: Mapping[str, np.ndarray]) -> None:
        """Write ``value`` into the compiled model (``defaults``: the model's compiled arrays)."""

    def edit(self, spec, value: np.ndarray, original: Mapping[str, Any]) -> None:
        """Write ``value`` into the spec (``original``: each geom as parsed, a ``_model.GeomOriginal``)."""


class NoEffect(Effect):
    """A factor kept for upstream compatibility that changes nothing (as upstream)."""


@dataclass(frozen=True)
class MaterialRGB(Effect):
    material: str

    def apply(self, model, value, defaults):
        model.mat_rgba[_id(model, "material", self.material), :3] = value


@dataclass(frozen=True)
class MaterialAlpha(Effect):
    """0 hides every element drawn with ``material``, 1 shows it (``rendering.render_target``)."""

    material: str

    def apply(self, model, value, defaults):
        model.mat_rgba[_id(model, "material", self.material), 3] = float(np.asarray(value).item())


@dataclass(frozen=True)
class GeomRGB(Effect):
    """The color of ``geoms``; with ``unless``, that value leaves the compiled color (their material's)."""

    geoms: tuple[str, ...]
    unless: tuple[float, ...] | None = None

    def apply(self, model, value, defaults):
        keep = self.unless is not None and np.allclose(value, self.unless)
        for g in self.geoms:
            i = _id(model, "geom", g)
            model.geom_rgba[i, :3] = defaults["geom_rgba"][i, :3] if keep else value


@dataclass(frozen=True)
class SiteRGB(Effect):
    site: str

    def apply(self, model, value, defaults):
        model.site_rgba[_id(model, "site", self.site), :3] = value


@dataclass(frozen=True)
class SiteShown(Effect):
    """``rendering.render_target`` of a target site: its alpha (as upstream) and, when 1,
    group 0 so that it is drawn."""

    site: str

    def apply(self, model, value, defaults):
        i = _id(model, "site", self.site)
        shown = bool(np.asarray(value).item())
        model.site_group[i] = 0 if shown else defaults["site_group"][i]
        model.site_rgba[i, 3] = float(shown)


@dataclass(frozen=True)
class SiteShape(Effect):
    """Upstream's target shape of a site: 1 a sphere (its size unchanged), 0 a box of half-size ``size[0]``.

    Applied after the task, which may set the radius (``size[0]``) per episode.
    """

    site: str
    after_task = True

    def apply(self, model, value, defaults):
        import mujoco

        i = _id(model, "site", self.site)
        radius = float(model.site_size[i, 0])
        if int(np.asarray(value).item()) == 1:
            model.site_type[i] = mujoco.mjtGeom.mjGEOM_SPHERE
            model.site_size[i] = (radius, *defaults["site_size"][i, 1:])
        else:
            model.site_type[i], model.site_size[i] = mujoco.mjtGeom.mjGEOM_BOX, np.full(3, radius)


class LightIntensity(Effect):
    """The diffuse intensity of every light (dm_control's lights default to 0.6 or 0.7)."""

    def apply(self, model, value, defaults):
        model.light_diffuse[:] = float(np.asarray(value).item())


@dataclass(frozen=True)
class Gravity(Effect):
    axis: int

    def apply(self, model, value, defaults):
        model.opt.gravity[self.axis] = float(np.asarray(value).item())


@dataclass(frozen=True)
class Friction(Effect):
    """Sliding friction of ``geom``; torsional and rolling friction become MuJoCo's defaults (as upstream)."""

    geom: str

    def apply(self, model, value, defaults):
        model.geom_friction[_id(model, "geom", self.geom)] = (float(np.asarray(value).item()), *FRICTION_TAIL)


@dataclass(frozen=True)
class FloorTilt(Effect):
    """Rotation of ``geom`` about the world's y axis, in degrees: the floor still passes through the origin.

    Structural: the compiler derives more than ``geom_quat`` from it (``geom_sameframe``, the
    world body's bounding volumes); writing ``geom_quat`` alone would not tilt the contacts.
    """

    geom: str
    structural = True

    def edit(self, spec, value, original):
        import mujoco

        angle = np.deg2rad(float(np.asarray(value).item()))
        x, y, z = original[self.geom].pos
        g = spec.geom(self.geom)
        g.alt.type = mujoco.mjtOrientation.mjORIENTATION_QUAT
        g.quat = (np.cos(angle / 2), 0.0, np.sin(angle / 2), 0.0)
        g.pos = (x * np.cos(angle) + z * np.sin(angle), y, -x * np.sin(angle) + z * np.cos(angle))


@dataclass(frozen=True)
class JointFrictionLoss(Effect):
    joint: str

    def apply(self, model, value, defaults):
        model.dof_frictionloss[model.jnt_dofadr[_id(model, "joint", self.joint)]] = float(np.asarray(value).item())


class FloorRGB(Effect):
    """The two checker colors of the "grid" texture (handled by the env: it re-uploads textures)."""


@dataclass(frozen=True)
class GeomDensity(Effect):
    """Density of ``geoms``; a geom whose mass the model fixes gets that mass scaled by density / 1000."""

    geoms: tuple[str, ...]
    structural = True

    def edit(self, spec, value, original):
        d = float(np.asarray(value).item())
        for name in self.geoms:
            g, mass = spec.geom(name), original[name].mass
            if np.isnan(mass):
                g.density = d
            else:
                g.mass = mass * d / 1000.0


@dataclass(frozen=True)
class GeomMass(Effect):
    geom: str
    structural = True

    def edit(self, spec, value, original):
        spec.geom(self.geom).mass = float(np.asarray(value).item())


@dataclass(frozen=True)
class GeomRadius(Effect):
    geom: str
    structural = True

    def edit(self, spec, value, original):
        spec.geom(self.geom).size[0] = float(np.asarray(value).item())


@dataclass(frozen=True)
class GeomShape(Effect):
    """1: the geom's own shape; 0: a box for a sphere (half-size = radius), an ellipsoid for a box.

    ``radius`` (when given) replaces the sphere's parsed radius in both shapes.
    """

    geom: str
    radius: float | None = None
    structural = True

    def edit(self, spec, value, original):
        import mujoco

        kind, size = original[self.geom].type, np.array(original[self.geom].size, float)
        if self.radius is not None:
            size[0] = self.radius
        g, box = spec.geom(self.geom), mujoco.mjtGeom.mjGEOM_BOX
        if int(np.asarray(value).item()) == 1:
            g.type, g.size = kind, size
        elif kind == box:
            g.type, g.size = mujoco.mjtGeom.mjGEOM_ELLIPSOID, size
        else:
            g.type, g.size = box, np.full(3, size[0])


@dataclass(frozen=True)
class Factor:
    """One factor of variation: dotted ``name``, a space builder and its ``effect``."""

    name: str
    space: Callable[[], Any]
    effect: Effect


def build_space(factors: tuple[Factor, ...]) -> spaces.Dict:
    """The nested variation space of ``factors`` (insertion order as given: upstream's sorted order)."""
    tree: dict[str, Any] = {}
    for f in factors:
        node = tree
        *parents, leaf = f.name.split(".")
        for p in parents:
            node = node.setdefault(p, {})
        node[leaf] = f.space()

    def to_dict(node):
        return spaces.Dict({k: to_dict(v) if isinstance(v, dict) else v for k, v in node.items()})

    return to_dict(tree)


# -- shared factor groups -----------------------------------------------------------------------
def floor_factors(floor_geom: str | None = None, tilt: bool = False) -> tuple[Factor, ...]:
    """``floor.color`` (+ ``floor.friction`` of ``floor_geom``, + ``floor.rotation_y`` when ``tilt``)."""
    out = [Factor("floor.color", floor_rgb, FloorRGB())]
    if floor_geom is not None:
        out.append(Factor("floor.friction", friction, Friction(floor_geom)))
    if tilt:
        out.append(Factor("floor.rotation_y", lambda: scalar(-10.0, 10.0, 0.0), FloorTilt(floor_geom)))
    return tuple(out)


def gravity_factors() -> tuple[Factor, ...]:
    return (
        Factor("gravity.x", lambda: scalar(-5.0, 5.0, 0.0), Gravity(0)),
        Factor("gravity.y", lambda: scalar(-5.0, 5.0, 0.0), Gravity(1)),
        Factor("gravity.z", lambda: scalar(-20.0, 0.0, -9.81), Gravity(2)),
    )


def light_factor() -> Factor:
    return Factor("light.intensity", lambda: scalar(0.0, 1.0, 0.7), LightIntensity())


def agent_color(init=AGENT_RGB) -> Factor:
    return Factor("agent.color", lambda: rgb(init), MaterialRGB("self"))


def target_factors(color: Effect, shape: Effect, render: Effect | None = None) -> tuple[Factor, ...]:
    """``rendering.render_target`` (when ``render``), ``target.color`` and ``target.shape``."""
    out = [] if render is None else [Factor("rendering.render_target", lambda: switch(0), render)]
    return (*out, Factor("target.color", lambda: rgb(TARGET_RGB), color), Factor("target.shape", switch, shape))

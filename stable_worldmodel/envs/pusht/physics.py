"""PushT physics: a pymunk space with walls, a kinematic agent and one dynamic block.

The dynamics are those of the original PushT (Diffusion Policy, gym-pusht):

- a 512x512 table closed by four static segments (5..506, radius 2), no gravity;
- ``space.damping = 0``: every body loses all its velocity at each sub-step, so the block
  moves only while it is pushed (quasi-static pushing, no sliding);
- the agent is a *kinematic* body (walls and the block do not slow it down) driven towards a
  target position by a PD controller ``a = k_p (target - p) - k_v v`` with ``k_p = 100``,
  ``k_v = 20`` (critically damped), integrated at ``SIM_HZ = 100`` for ``SIM_HZ // CONTROL_HZ
  = 10`` sub-steps per env step;
- the block has mass 1; contacts are frictionless (the original set ``friction`` on the
  bodies, where pymunk ignores it, so its shapes kept pymunk's default friction 0).

:class:`PushTPhysics` is a mixin: the env inherits ``add_tee`` ... ``add_shape`` from it, and
the expert builds a private instance to look ahead.
"""

from __future__ import annotations

import math

import numpy as np

from .shapes import SHAPES, ShapeSpec, check_shape_name, shape_spec

WINDOW = 512.0
SIM_HZ = 100
CONTROL_HZ = 10
K_P, K_V = 100.0, 20.0
WALLS = (((5, 506), (5, 5)), ((5, 5), (506, 5)), ((506, 5), (506, 506)), ((5, 506), (506, 506)))
DEFAULT_UNITS = {"circle": 15.0}  # add_circle's default radius is the agent's; every other shape uses 30


def _pymunk():
    import pymunk

    return pymunk


class PushTPhysics:
    """The pymunk world of PushT; ``new_space()`` starts an empty table."""

    space = None

    def new_space(self) -> None:
        """Replace :attr:`space` by an empty walled table."""
        pymunk = _pymunk()
        space = pymunk.Space()
        space.gravity = (0.0, 0.0)
        space.damping = 0.0
        for a, b in WALLS:
            space.add(pymunk.Segment(space.static_body, a, b, 2))
        self.space = space

    # -- bodies (the method names of seed 000) ---------------------------------------------
    def add_shape(
        self, name: str, position, angle: float = 0.0, scale: float | None = None, *, kinematic: bool = False
    ):
        """Add a body of shape ``name`` (one of :data:`SHAPES`) at ``position`` / ``angle``.

        ``scale`` is the unit length of :mod:`.shapes` (30 by default; a circle's radius, 15 by
        default). A kinematic body is an agent; a dynamic one is a block of mass 1. Returns the
        pymunk body. Unknown names raise :class:`~stable_worldmodel.errors.UnknownNameError`.
        """
        check_shape_name(name)
        unit = DEFAULT_UNITS.get(name, 30.0) if scale is None else float(scale)
        return self.add_spec(shape_spec(name, unit), position, angle, kinematic=kinematic)

    def add_spec(self, spec: ShapeSpec, position, angle: float = 0.0, *, kinematic: bool = False):
        """Add a body built from ``spec`` (see :meth:`add_shape`)."""
        pymunk = _pymunk()
        if self.space is None:
            self.new_space()
        if kinematic:
            body = pymunk.Body(body_type=pymunk.Body.KINEMATIC)
        else:
            body = pymunk.Body(1.0, spec.moment)
        if spec.radius is not None:
            shapes = [pymunk.Circle(body, spec.radius)]
        else:
            shapes = [pymunk.Poly(body, [tuple(p) for p in poly]) for poly in spec.polygons()]
        if not kinematic:
            body.center_of_gravity = (float(spec.cog[0]), float(spec.cog[1]))
        set_pose(body, position, angle)
        self.space.add(body, *shapes)
        return body

    def add_tee(self, position, angle: float = 0.0, scale: float = 30.0, *, kinematic: bool = False):
        """The original T block: two 120x30 bars at the default ``scale`` 30."""
        return self.add_shape("tee", position, angle, scale, kinematic=kinematic)

    def add_small_tee(self, position, angle: float = 0.0, scale: float = 30.0, *, kinematic: bool = False):
        """A T with a 90x30 bar and a 60x30 stem."""
        return self.add_shape("small_tee", position, angle, scale, kinematic=kinematic)

    def add_L(self, position, angle: float = 0.0, scale: float = 30.0, *, kinematic: bool = False):  # noqa: N802
        """An L block."""
        return self.add_shape("L", position, angle, scale, kinematic=kinematic)

    def add_Z(self, position, angle: float = 0.0, scale: float = 30.0, *, kinematic: bool = False):  # noqa: N802
        """A Z block."""
        return self.add_shape("Z", position, angle, scale, kinematic=kinematic)

    def add_I(self, position, angle: float = 0.0, scale: float = 30.0, *, kinematic: bool = False):  # noqa: N802
        """A straight 30x120 bar."""
        return self.add_shape("I", position, angle, scale, kinematic=kinematic)

    def add_plus(self, position, angle: float = 0.0, scale: float = 30.0, *, kinematic: bool = False):
        """A plus-shaped block."""
        return self.add_shape("plus", position, angle, scale, kinematic=kinematic)

    def add_square(self, position, angle: float = 0.0, scale: float = 30.0, *, kinematic: bool = False):
        """A 60x60 square."""
        return self.add_shape("square", position, angle, scale, kinematic=kinematic)

    def add_box(self, position, angle: float = 0.0, scale: float = 30.0, *, kinematic: bool = False):
        """A 120x60 box."""
        return self.add_shape("box", position, angle, scale, kinematic=kinematic)

    def add_circle(self, position, radius: float = 15.0, angle: float = 0.0, *, kinematic: bool = True):
        """A disk; kinematic by default, as the original's agent."""
        return self.add_shape("circle", position, angle, radius, kinematic=kinematic)

    # -- stepping ------------------------------------------------------------------------
    @staticmethod
    def pd_step(agent, space, target, n_substeps: int = SIM_HZ // CONTROL_HZ) -> None:
        """Drive kinematic ``agent`` towards ``target`` = (x, y) for ``n_substeps`` physics steps."""
        dt = 1.0 / SIM_HZ
        tx, ty = float(target[0]), float(target[1])
        px, py = agent.position
        vx, vy = agent.velocity
        step = space.step
        for _ in range(n_substeps):
            vx += (K_P * (tx - px) - K_V * vx) * dt
            vy += (K_P * (ty - py) - K_V * vy) * dt
            agent.velocity = (vx, vy)
            step(dt)
            px += vx * dt  # what pymunk does to a kinematic body; saves reading it back
            py += vy * dt


def on_post_solve(space, callback) -> None:
    """Call ``callback(arbiter, space, data)`` after each solved contact between any two shapes.

    The shapes of PushT all have collision type 0 (pymunk's default), as in the original's
    ``space.on_collision(0, 0, post_solve=...)``; pymunk 6 spells it ``add_collision_handler``.
    """
    if hasattr(space, "on_collision"):  # pymunk >= 7
        space.on_collision(0, 0, post_solve=callback)
    else:
        space.add_collision_handler(0, 0).post_solve = callback


def pd_gains(n_substeps: int = SIM_HZ // CONTROL_HZ) -> tuple[float, float]:
    """``(g_u, g_v)``: one env step moves the agent by ``g_u * offset + g_v * v0`` (per axis).

    ``offset`` is the PD target minus the start position and ``v0`` the start velocity; the
    map is exact (linear recurrence of :meth:`PushTPhysics.pd_step`): g_u ~ 0.296, g_v ~ 0.030 s.
    """
    dt = 1.0 / SIM_HZ

    def run(offset: float, v: float) -> float:
        p = 0.0
        for _ in range(n_substeps):
            v += (K_P * (offset - p) - K_V * v) * dt
            p += v * dt
        return p

    return run(1.0, 0.0), run(0.0, 1.0)


def set_pose(body, position, angle: float) -> None:
    """Place ``body``'s origin at ``position`` with ``angle``.

    The angle goes first: pymunk turns a body about its centre of gravity, so setting it after
    the position would move the origin of a block whose centre of gravity is off its origin.
    """
    body.angle = float(angle)
    body.position = (float(position[0]), float(position[1]))


def body_state(agent, block) -> np.ndarray:
    """``(7,)`` float64 state: agent x, y, block x, y, block angle in [0, 2pi), agent vx, vy."""
    ax, ay = agent.position
    bx, by = block.position
    vx, vy = agent.velocity
    return np.array([ax, ay, bx, by, block.angle % (2 * math.pi), vx, vy], np.float64)


__all__ = [
    "CONTROL_HZ",
    "K_P",
    "K_V",
    "SHAPES",
    "SIM_HZ",
    "WINDOW",
    "PushTPhysics",
    "body_state",
    "on_post_solve",
    "pd_gains",
    "set_pose",
]

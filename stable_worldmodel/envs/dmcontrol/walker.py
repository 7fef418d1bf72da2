"""``swm/WalkerDMControl-v0``: dm_control's walker ``walk`` (see :mod:`.dmcontrol`, :mod:`._locomotion`).

Factors (upstream's): ``agent.color``, ``agent.left_foot_density``, ``agent.right_knee_locked``
(no effect, as upstream), ``agent.torso_density``, ``floor.color``, ``floor.friction`` (as
upstream, the default 1 replaces dm_control's walker floor friction 0.7 / 0.1 / 0.1 by
1 / 0.005 / 0.0001), ``floor.rotation_y`` (floor tilt in degrees, about the world's y axis;
upstream turns the 500 m floor about its centre at x = 248 m, which lifts or sinks it by ~4 m
per degree under the walker, whose physics then blows up), ``gravity.x/y/z``,
``light.intensity``. Extra info: ``speed``, ``torso_height``, ``torso_upright``,
``left/right_foot_height``, ``left/right_thigh_height``.
"""

from __future__ import annotations

from ..mujoco_render import setup_gl

setup_gl()  # before dm_control picks its GL backend

from dm_control.suite import walker  # noqa: E402

from . import _factors as F  # noqa: E402
from ._locomotion import LocomotionWrapper  # noqa: E402

SPEEDS = {"stand": 0.0, "walk": 1.0, "run": 8.0}


class WalkerDMControlWrapper(LocomotionWrapper):
    """The planar biped walker."""

    ENV_NAME = "Walker"
    PHYSICS = walker.Physics
    DEFAULT_TASK = "walk"
    TASKS = {name: lambda r, v=v: walker.PlanarWalker(move_speed=v, random=r) for name, v in SPEEDS.items()}
    CONTROL_TIMESTEP = 0.025
    HORIZONTAL_QPOS = (1,)  # walker's qpos: rootz, rootx, rooty, ...

    def __init__(self, task="walk", seed=None, environment_kwargs=None, render_mode=None, *, render_quality="medium"):
        super().__init__(task, seed, environment_kwargs, render_mode, render_quality)

    @classmethod
    def factors(cls, task):
        return (
            F.agent_color(),
            F.Factor("agent.left_foot_density", F.density, F.GeomDensity(("left_foot",))),
            F.Factor("agent.right_knee_locked", F.switch, F.NoEffect()),
            F.Factor("agent.torso_density", F.density, F.GeomDensity(("torso",))),
            *F.floor_factors("floor", tilt=True),
            *F.gravity_factors(),
            F.light_factor(),
        )

    def extra_info(self):
        p = self._physics
        xpos = p.named.data.xpos
        return {
            "speed": float(p.horizontal_velocity()),
            "torso_height": float(p.torso_height()),
            "torso_upright": float(p.torso_upright()),
            **{
                f"{part}_height": float(xpos[part, "z"])
                for part in ("left_foot", "right_foot", "left_thigh", "right_thigh")
            },
        }

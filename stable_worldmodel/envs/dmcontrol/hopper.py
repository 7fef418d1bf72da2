"""``swm/HopperDMControl-v0``: dm_control's hopper ``hop`` (see :mod:`.dmcontrol`, :mod:`._locomotion`).

Factors (upstream's): ``agent.color``, ``agent.foot_density``, ``agent.foot_locked`` (no effect,
as upstream), ``agent.torso_density`` (the torso capsule), ``floor.color``, ``floor.friction``,
``gravity.x/y/z``, ``light.intensity``. Extra info: ``speed``, ``height``, ``angmomentum``.
"""

from __future__ import annotations

from ..mujoco_render import setup_gl

setup_gl()  # before dm_control picks its GL backend

from dm_control.suite import hopper  # noqa: E402

from . import _factors as F  # noqa: E402
from ._locomotion import LocomotionWrapper  # noqa: E402


class HopperDMControlWrapper(LocomotionWrapper):
    """The planar one-legged hopper."""

    ENV_NAME = "Hopper"
    PHYSICS = hopper.Physics
    DEFAULT_TASK = "hop"
    TASKS = {
        "stand": lambda r: hopper.Hopper(hopping=False, random=r),
        "hop": lambda r: hopper.Hopper(hopping=True, random=r),
    }
    CONTROL_TIMESTEP = 0.02

    def __init__(self, task="hop", seed=None, environment_kwargs=None, render_mode=None, *, render_quality="medium"):
        super().__init__(task, seed, environment_kwargs, render_mode, render_quality)

    @classmethod
    def factors(cls, task):
        return (
            F.agent_color(),
            F.Factor("agent.foot_density", F.density, F.GeomDensity(("foot",))),
            F.Factor("agent.foot_locked", F.switch, F.NoEffect()),
            F.Factor("agent.torso_density", F.density, F.GeomDensity(("torso",))),
            *F.floor_factors("floor"),
            *F.gravity_factors(),
            F.light_factor(),
        )

    def extra_info(self):
        p = self._physics
        return {
            "speed": float(p.speed()),
            "height": float(p.height()),
            "angmomentum": float(p.named.data.subtree_angmom["torso"][1]),
        }

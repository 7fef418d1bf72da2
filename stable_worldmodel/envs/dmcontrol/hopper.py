"""``swm/HopperDMControl-v0``: dm_control's hopper ``hop`` (see :mod:`.dmcontrol`, :mod:`._locomotion`).

Factors (upstream's): ``agent.color``, ``agent.foot_density``, ``agent.foot_locked`` (no effect,
as upstream), ``agent.torso_density`` (the torso capsule), ``floor.color``, ``floor.friction``,
``gravity.x/y/z``, ``light.intensity``. Extra info: ``speed``, ``height``, ``angmomentum``.

Tasks (``task=``, as upstream 0.1.1): dm_control's ``stand`` and ``hop`` (standing times hopping
forward, full at 2 m/s), and ``hop-backward`` (upstream's custom goal): standing (torso above
0.6 m, as ``hop``) times a backward-speed term that is 1 at ``speed <= -1`` m/s and falls linearly
through 0.5 at -0.5 m/s to 0 at speed 0 and above. Same model, factors and infos for all three.
"""

from __future__ import annotations

from ..mujoco_render import setup_gl

setup_gl()  # before dm_control picks its GL backend

from dm_control.suite import hopper  # noqa: E402
from dm_control.utils import rewards  # noqa: E402

from . import _factors as F  # noqa: E402
from ._locomotion import LocomotionWrapper  # noqa: E402


class HopBackward(hopper.Hopper):
    """The hopper standing and hopping backwards: ``standing * backward``, where ``standing`` is
    dm_control's (height in [0.6, 2]) and ``backward`` is 1 at ``speed <= -_HOP_SPEED / 2`` and
    falls linearly, through 0.5 one margin (``_HOP_SPEED / 4``) further, to 0 at speed 0."""

    def __init__(self, random=None):
        super().__init__(hopping=False, random=random)

    def get_reward(self, physics):
        standing = rewards.tolerance(physics.height(), (hopper._STAND_HEIGHT, 2))
        fast = hopper._HOP_SPEED
        backward = rewards.tolerance(
            physics.speed(), bounds=(-float("inf"), -fast / 2), margin=fast / 4, value_at_margin=0.5, sigmoid="linear"
        )
        return standing * backward


class HopperDMControlWrapper(LocomotionWrapper):
    """The planar one-legged hopper."""

    ENV_NAME = "Hopper"
    PHYSICS = hopper.Physics
    DEFAULT_TASK = "hop"
    TASKS = {
        "stand": lambda r: hopper.Hopper(hopping=False, random=r),
        "hop": lambda r: hopper.Hopper(hopping=True, random=r),
        "hop-backward": lambda r: HopBackward(random=r),
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

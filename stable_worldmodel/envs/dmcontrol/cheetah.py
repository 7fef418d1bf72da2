"""``swm/CheetahDMControl-v0``: dm_control's cheetah ``run`` (see :mod:`.dmcontrol`, :mod:`._locomotion`).

Factors (upstream's): ``agent.back_foot_density``, ``agent.back_foot_locked`` (no effect, as
upstream), ``agent.color``, ``agent.torso_density`` (the torso capsule; dm_control's cheetah keeps
its total mass at 14 kg, so a density moves mass between the bodies, as upstream),
``floor.color``, ``floor.friction``, ``gravity.x/y/z``, ``light.intensity``. Extra info:
``speed``, ``torso_height``, ``bfoot_height``, ``ffoot_height``, ``angmomentum``.
"""

from __future__ import annotations

from ..mujoco_render import setup_gl

setup_gl()  # before dm_control picks its GL backend

from dm_control.suite import cheetah  # noqa: E402

from . import _factors as F  # noqa: E402
from ._locomotion import LocomotionWrapper  # noqa: E402


class CheetahDMControlWrapper(LocomotionWrapper):
    """The planar half-cheetah."""

    ENV_NAME = "Cheetah"
    PHYSICS = cheetah.Physics
    DEFAULT_TASK = "run"
    TASKS = {"run": lambda r: cheetah.Cheetah(random=r)}

    def __init__(self, task="run", seed=None, environment_kwargs=None, render_mode=None, *, render_quality="medium"):
        super().__init__(task, seed, environment_kwargs, render_mode, render_quality)

    @classmethod
    def factors(cls, task):
        return (
            F.Factor("agent.back_foot_density", F.density, F.GeomDensity(("bfoot",))),
            F.Factor("agent.back_foot_locked", F.switch, F.NoEffect()),
            F.agent_color(),
            F.Factor("agent.torso_density", F.density, F.GeomDensity(("torso",))),
            *F.floor_factors("ground"),
            *F.gravity_factors(),
            F.light_factor(),
        )

    def extra_info(self):
        p = self._physics
        xpos = p.named.data.xpos
        return {
            "speed": float(p.speed()),
            "torso_height": float(xpos["torso", "z"]),
            "bfoot_height": float(xpos["bfoot", "z"]),
            "ffoot_height": float(xpos["ffoot", "z"]),
            "angmomentum": float(p.named.data.subtree_angmom["torso"][1]),
        }

"""``swm/CheetahDMControl-v0``: dm_control's cheetah ``run`` (see :mod:`.dmcontrol`, :mod:`._locomotion`).

Tasks (``task=``, as upstream 0.1.1): ``run`` (dm_control's: reward rises linearly with the
forward speed up to 1 at 10 m/s) and ``run-backward`` (the mirror: reward 1 at a speed of -10 m/s
or less, falling linearly to 0 at speed 0; upstream's custom goal). Same model, factors and infos.

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
from dm_control.utils import rewards  # noqa: E402

from . import _factors as F  # noqa: E402
from ._locomotion import LocomotionWrapper  # noqa: E402


class RunBackward(cheetah.Cheetah):
    """dm_control's cheetah task rewarding backward running: ``tolerance(speed)`` that is 1 at
    ``speed <= -10`` m/s and falls linearly to 0 at ``speed >= 0``."""

    def get_reward(self, physics):
        top = cheetah._RUN_SPEED
        return rewards.tolerance(
            physics.speed(), bounds=(-float("inf"), -top), margin=top, value_at_margin=0, sigmoid="linear"
        )


class CheetahDMControlWrapper(LocomotionWrapper):
    """The planar half-cheetah."""

    ENV_NAME = "Cheetah"
    PHYSICS = cheetah.Physics
    DEFAULT_TASK = "run"
    TASKS = {
        "run": lambda r: cheetah.Cheetah(random=r),
        "run-backward": lambda r: RunBackward(random=r),
    }

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

"""``swm/HumanoidDMControl-v0``: dm_control's humanoid ``walk`` (see :mod:`.dmcontrol`, :mod:`._locomotion`).

Factors (upstream's): ``agent.color``, ``agent.left_knee_locked`` (no effect, as upstream),
``agent.right_lower_arm_density``, ``agent.torso_density`` (the torso capsule), ``floor.color``,
``floor.friction``, ``gravity.x/y/z``, ``light.intensity``. Extra info: ``speed`` (horizontal
centre-of-mass speed), ``torso_upright``, ``head_height``.
"""

from __future__ import annotations

from ..mujoco_render import setup_gl

setup_gl()  # before dm_control picks its GL backend

import numpy as np  # noqa: E402
from dm_control.suite import humanoid  # noqa: E402

from . import _factors as F  # noqa: E402
from ._locomotion import LocomotionWrapper  # noqa: E402

SPEEDS = {"stand": 0.0, "walk": 1.0, "run": 10.0}


class HumanoidDMControlWrapper(LocomotionWrapper):
    """The 21-actuator humanoid."""

    ENV_NAME = "Humanoid"
    PHYSICS = humanoid.Physics
    DEFAULT_TASK = "walk"
    TASKS = {
        name: lambda r, v=v: humanoid.Humanoid(move_speed=v, pure_state=False, random=r) for name, v in SPEEDS.items()
    }
    CONTROL_TIMESTEP = 0.025
    HORIZONTAL_QPOS = (0, 1)

    def __init__(self, task="walk", seed=None, environment_kwargs=None, render_mode=None, *, render_quality="medium"):
        super().__init__(task, seed, environment_kwargs, render_mode, render_quality)

    @classmethod
    def factors(cls, task):
        return (
            F.agent_color(),
            F.Factor("agent.left_knee_locked", F.switch, F.NoEffect()),
            F.Factor("agent.right_lower_arm_density", F.density, F.GeomDensity(("right_lower_arm",))),
            F.Factor("agent.torso_density", F.density, F.GeomDensity(("torso",))),
            *F.floor_factors("floor"),
            *F.gravity_factors(),
            F.light_factor(),
        )

    def extra_info(self):
        p = self._physics
        return {
            "speed": float(np.linalg.norm(p.center_of_mass_velocity()[:2])),
            "torso_upright": float(p.torso_upright()),
            "head_height": float(p.head_height()),
        }

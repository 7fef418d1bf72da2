"""``swm/PendulumDMControl-v0``: dm_control's pendulum ``swingup`` (see :mod:`.dmcontrol`).

Goal: the pole upright at rest (``qpos = [0]``); ``eval_state`` compares ``[cos, sin]`` of the
angle within 2 sin(15 deg) (the reward's 30 degrees).

Factors (upstream's): ``agent.color``, ``agent.mass_density`` (scales the bob's fixed 1 kg by
density / 1000; upstream: no effect), ``agent.mass_shape`` (1: sphere, 0: a box of the same
extent; upstream: no effect), ``agent.pole_density`` (the pole is massless in dm_control, so
scaling its mass changes nothing, as upstream), ``floor.color``, ``gravity.x/y/z``,
``light.intensity``.
"""

from __future__ import annotations

from ..mujoco_render import setup_gl

setup_gl()  # before dm_control picks its GL backend

import numpy as np  # noqa: E402
from dm_control.suite import pendulum  # noqa: E402

from . import _factors as F  # noqa: E402
from .dmcontrol import DMControlWrapper  # noqa: E402


class PendulumDMControlWrapper(DMControlWrapper):
    """Torque-limited pendulum swing-up."""

    ENV_NAME = "Pendulum"
    PHYSICS = pendulum.Physics
    DEFAULT_TASK = "swingup"
    TASKS = {"swingup": lambda r: pendulum.SwingUp(random=r)}
    GOAL_TOLERANCE = 2 * np.sin(np.deg2rad(15.0))

    def __init__(self, seed=None, environment_kwargs=None, render_mode=None, *, render_quality="medium"):
        super().__init__("swingup", seed, environment_kwargs, render_mode, render_quality)

    @classmethod
    def factors(cls, task):
        return (
            F.agent_color(),
            F.Factor("agent.mass_density", F.density, F.GeomDensity(("mass",))),
            F.Factor("agent.mass_shape", F.switch, F.GeomShape("mass")),
            F.Factor("agent.pole_density", F.density, F.GeomDensity(("pole",))),
            *F.floor_factors(),
            *F.gravity_factors(),
            F.light_factor(),
        )

    def goal_qpos(self):
        return np.zeros(self.model.nq)

    def goal_features(self, qpos):
        return np.array([np.cos(qpos[0]), np.sin(qpos[0])])

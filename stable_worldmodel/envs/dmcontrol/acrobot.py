"""``swm/AcrobotDMControl-v0``: dm_control's acrobot ``swingup_sparse`` (see :mod:`.dmcontrol`).

Goal: both links upright (``qpos = [0, 0]``), the tip in the target sphere; ``eval_state``
compares tip positions within the target's 0.2 radius.

Factors (upstream's): ``agent.color``, ``agent.lower_arm_density`` / ``agent.upper_arm_density``
(scale the links' fixed 1 kg masses by density / 1000; upstream: no effect),
``agent.upper_arm_locked`` (no effect, as upstream), ``floor.color``, ``gravity.x/y/z``,
``light.intensity``, ``target.color`` and ``target.shape`` (the target site's material and shape;
dm_control puts it in site group 3, which is not drawn, so neither shows, as upstream).
"""

from __future__ import annotations

from ..mujoco_render import setup_gl

setup_gl()  # before dm_control picks its GL backend

import numpy as np  # noqa: E402
from dm_control.suite import acrobot  # noqa: E402

from . import _factors as F  # noqa: E402
from .dmcontrol import DMControlWrapper  # noqa: E402


class AcrobotDMControlWrapper(DMControlWrapper):
    """Acrobot swing-up with a sparse reward (tip in the target)."""

    ENV_NAME = "Acrobot"
    PHYSICS = acrobot.Physics
    DEFAULT_TASK = "swingup_sparse"
    TASKS = {
        "swingup_sparse": lambda r: acrobot.Balance(sparse=True, random=r),
        "swingup": lambda r: acrobot.Balance(sparse=False, random=r),
    }
    GOAL_TOLERANCE = 0.2

    def __init__(
        self, seed=None, environment_kwargs=None, render_mode=None, *, task="swingup_sparse", render_quality="medium"
    ):
        super().__init__(task, seed, environment_kwargs, render_mode, render_quality)

    @classmethod
    def factors(cls, task):
        return (
            F.agent_color(),
            F.Factor("agent.lower_arm_density", F.density, F.GeomDensity(("lower_arm",))),
            F.Factor("agent.upper_arm_density", F.density, F.GeomDensity(("upper_arm",))),
            F.Factor("agent.upper_arm_locked", F.switch, F.NoEffect()),
            *F.floor_factors(),
            *F.gravity_factors(),
            F.light_factor(),
            *F.target_factors(F.MaterialRGB("target"), F.SiteShape("target")),
        )

    def goal_qpos(self):
        return np.zeros(self.model.nq)

    def goal_features(self, qpos):
        return self.kinematics(qpos).site("tip").xpos[[0, 2]].copy()

"""``swm/ManipulatorDMControl-v0``: dm_control's manipulator ``bring_ball`` (see :mod:`.dmcontrol`).

Goal: the ball at the target, the arm as it starts; a ``goal_state`` option moves the target to
that state's ball. ``eval_state`` compares ball positions (x, z) within 0.02.

Factors (upstream's): ``agent.color``, ``agent.hand_density`` (the hand's first capsule),
``agent.upper_arm_density``, ``agent.upper_arm_length`` (no effect, as upstream),
``floor.color`` (floor and walls), ``light.intensity``, ``rendering.render_target`` (0, the
default, hides the target as upstream), ``target.color``, ``target.shape`` (1: sphere, 0: box).
As upstream, the densities default to 1000 where dm_control's arm has 500, and the target
ball's radius is 0.015 (dm_control: 0.02).
"""

from __future__ import annotations

from ..mujoco_render import setup_gl

setup_gl()  # before dm_control picks its GL backend

import numpy as np  # noqa: E402
from dm_control.suite import manipulator  # noqa: E402

from . import _factors as F  # noqa: E402
from .dmcontrol import DMControlWrapper  # noqa: E402

ARM = ("arm_root", "arm_shoulder", "arm_elbow", "arm_wrist", "finger", "fingertip", "thumb", "thumbtip")
BALL = ("ball_x", "ball_z", "ball_y")


class ManipulatorDMControlWrapper(DMControlWrapper):
    """Planar arm bringing a ball to a target."""

    ENV_NAME = "Manipulator"
    PHYSICS = manipulator.Physics
    DEFAULT_TASK = "bring_ball"
    TASKS = {"bring_ball": lambda r: manipulator.Bring(use_peg=False, insert=False, fully_observable=True, random=r)}
    CONTROL_TIMESTEP = 0.01
    AGENT_JOINTS = ARM
    GOAL_TOLERANCE = 0.02

    def __init__(self, seed=None, environment_kwargs=None, render_mode=None, *, render_quality="medium"):
        super().__init__("bring_ball", seed, environment_kwargs, render_mode, render_quality)
        self._ball = [int(self.model.joint(j).qposadr[0]) for j in BALL]

    def model_source(self, task):
        xml, assets = manipulator.make_model(use_peg=False, insert=False)
        return xml.decode() if isinstance(xml, bytes) else xml, assets

    @classmethod
    def factors(cls, task):
        return (
            F.agent_color(),
            F.Factor("agent.hand_density", F.density, F.GeomDensity(("hand",))),
            F.Factor("agent.upper_arm_density", F.density, F.GeomDensity(("upper_arm",))),
            F.Factor("agent.upper_arm_length", F.density, F.NoEffect()),
            *F.floor_factors(),
            F.light_factor(),
            *F.target_factors(
                F.MaterialRGB("target"), F.GeomShape("target_ball", radius=0.015), render=F.MaterialAlpha("target")
            ),
        )

    def goal_qpos(self):
        qpos = self._physics.data.qpos.copy()
        body = self.model.body("target_ball")
        qw, qy = body.quat[0], body.quat[2]
        qpos[self._ball] = body.pos[0], body.pos[2], 2.0 * np.arctan2(qy, qw)
        return qpos

    def place_goal(self, qpos):
        body = self.model.body("target_ball")
        x, z, angle = (float(qpos[i]) for i in self._ball)
        body.pos[[0, 2]] = x, z
        body.quat[:] = np.cos(angle / 2), 0.0, np.sin(angle / 2), 0.0

    def goal_features(self, qpos):
        return np.asarray(qpos, float)[self._ball[:2]]

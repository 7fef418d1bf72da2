"""``swm/FingerDMControl-v0``: dm_control's finger ``turn_hard`` (see :mod:`.dmcontrol`).

Goal: the spinner turned so that its tip is on the target, the finger as it starts; a
``goal_state`` option moves the target to that state's spinner tip. ``eval_state`` compares
tip positions within the target radius (the reward's bound). ``spin`` has no target: its goal
is the reference pose.

Factors (upstream's): ``agent.color``, ``agent.fingertip_density``, ``agent.proximal_density``,
``floor.color``, ``light.intensity``, ``rendering.render_target`` (0, the default, hides the
target material, and with it the spinner's tip, as upstream), ``spinner.color``,
``spinner.density``, ``spinner.friction`` (the hinge's friction loss), ``target.color``,
``target.shape`` (1: sphere, 0: box). Extra info: ``hinge_velocity``,
``target_position``, ``tip_position`` (x, z relative to the hinge).
"""

from __future__ import annotations

from ..mujoco_render import setup_gl

setup_gl()  # before dm_control picks its GL backend

from dm_control.suite import finger  # noqa: E402

from . import _factors as F  # noqa: E402
from .dmcontrol import DMControlWrapper  # noqa: E402

TARGET_RADIUS = {"turn_easy": 0.07, "turn_hard": 0.03}


class FingerDMControlWrapper(DMControlWrapper):
    """Planar finger turning a spinner to a target."""

    ENV_NAME = "Finger"
    PHYSICS = finger.Physics
    DEFAULT_TASK = "turn_hard"
    TASKS = {
        "spin": lambda r: finger.Spin(random=r),
        **{
            name: lambda r, radius=radius: finger.Turn(target_radius=radius, random=r)
            for name, radius in TARGET_RADIUS.items()
        },
    }
    CONTROL_TIMESTEP = 0.02
    AGENT_JOINTS = ("proximal", "distal")

    def __init__(
        self, task="turn_hard", seed=None, environment_kwargs=None, render_mode=None, *, render_quality="medium"
    ):
        super().__init__(task, seed, environment_kwargs, render_mode, render_quality)
        self.GOAL_TOLERANCE = TARGET_RADIUS.get(self.task_name, 0.1)

    @classmethod
    def factors(cls, task):
        return (
            F.agent_color(),
            F.Factor("agent.fingertip_density", F.density, F.GeomDensity(("fingertip",))),
            F.Factor("agent.proximal_density", F.density, F.GeomDensity(("proximal",))),
            *F.floor_factors(),
            F.light_factor(),
            F.Factor("rendering.render_target", lambda: F.switch(0), F.MaterialAlpha("target")),
            F.Factor("spinner.color", F.rgb, F.GeomRGB(("cap1", "cap2"))),
            F.Factor("spinner.density", F.density, F.GeomDensity(("cap1", "cap2"))),
            F.Factor("spinner.friction", lambda: F.friction(0.1), F.JointFrictionLoss("hinge")),
            F.Factor("target.color", lambda: F.rgb(F.TARGET_RGB), F.MaterialRGB("target")),
            F.Factor("target.shape", F.switch, F.SiteShape("target")),
        )

    def goal_qpos(self):
        qpos = self._physics.data.qpos.copy()
        if self.task_name not in TARGET_RADIUS:
            return self.model.qpos0.copy()
        target = self._physics.named.data.site_xpos["target", [0, 2]].copy()
        return self.solve_ik(qpos, [2], self._tip, target)

    def place_goal(self, qpos):
        if self.task_name in TARGET_RADIUS:
            self.model.site("target").pos[[0, 2]] = self._tip(self.kinematics(qpos))

    def goal_features(self, qpos):
        return self._tip(self.kinematics(qpos)).copy()

    def extra_info(self):
        p = self._physics
        return {
            "hinge_velocity": float(p.hinge_velocity()),
            "target_position": p.target_position().copy(),
            "tip_position": p.tip_position().copy(),
        }

    @staticmethod
    def _tip(data):
        return data.site("tip").xpos[[0, 2]]

"""``swm/ReacherDMControl-v0``: dm_control's reacher ``hard`` (see :mod:`.dmcontrol`).

Goal: the fingertip on the target (the arm configuration found by inverse kinematics); a
``goal_state`` option moves the target under that state's fingertip. ``eval_state`` compares
fingertip positions within the target's plus the fingertip's radius (the reward's bound).

Factors (upstream's): ``agent.arm_density``, ``agent.color``, ``agent.finger_density``,
``agent.finger_locked`` (no effect, as upstream), ``floor.color``, ``light.intensity``,
``rendering.render_target`` (0, the default, hides the target as upstream does),
``target.color``, ``target.shape`` (1: sphere, 0: box of the same extent). Extra info:
``target_pos``, ``finger_pos`` (x, y).
"""

from __future__ import annotations

from ..mujoco_render import setup_gl

setup_gl()  # before dm_control picks its GL backend

from dm_control.suite import reacher  # noqa: E402

from . import _factors as F  # noqa: E402
from .dmcontrol import DMControlWrapper  # noqa: E402

TARGET_SIZE = {"easy": 0.05, "hard": 0.015}


class ReacherDMControlWrapper(DMControlWrapper):
    """Two-link planar reacher; the target is hidden unless ``rendering.render_target`` is 1."""

    ENV_NAME = "Reacher"
    PHYSICS = reacher.Physics
    DEFAULT_TASK = "hard"
    TASKS = {
        name: lambda r, size=size: reacher.Reacher(target_size=size, random=r) for name, size in TARGET_SIZE.items()
    }

    def __init__(self, task="hard", seed=None, environment_kwargs=None, render_mode=None, *, render_quality="medium"):
        super().__init__(task, seed, environment_kwargs, render_mode, render_quality)
        self.GOAL_TOLERANCE = TARGET_SIZE[self.task_name] + float(self.model.geom("finger").size[0])

    @classmethod
    def factors(cls, task):
        return (
            F.Factor("agent.arm_density", F.density, F.GeomDensity(("arm",))),
            F.agent_color(),
            F.Factor("agent.finger_density", F.density, F.GeomDensity(("finger",))),
            F.Factor("agent.finger_locked", F.switch, F.NoEffect()),
            *F.floor_factors(),
            F.light_factor(),
            *F.target_factors(
                F.MaterialRGB("target"),
                F.GeomShape("target", radius=TARGET_SIZE.get(task)),
                render=F.MaterialAlpha("target"),
            ),
        )

    def goal_qpos(self):
        target = self._physics.named.data.geom_xpos["target", :2].copy()
        return self.solve_ik(self._physics.data.qpos.copy(), [0, 1], self._finger, target)

    def place_goal(self, qpos):
        self.model.geom("target").pos[:2] = self._finger(self.kinematics(qpos))

    def goal_features(self, qpos):
        return self._finger(self.kinematics(qpos)).copy()

    def extra_info(self):
        xpos = self._physics.named.data.geom_xpos
        return {"target_pos": xpos["target", :2].copy(), "finger_pos": xpos["finger", :2].copy()}

    @staticmethod
    def _finger(data):
        return data.geom("finger").xpos[:2]

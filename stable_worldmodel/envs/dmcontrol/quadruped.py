"""``swm/QuadrupedDMControl-v0``: dm_control's quadruped ``walk`` (see :mod:`.dmcontrol`, :mod:`._locomotion`).

Frames come from camera 2 (``y``, tracking the body), as upstream.

Factors (upstream's): ``agent.color`` (default [0.6, 0.3, 0.3], as upstream),
``agent.foot_back_left_density`` (as upstream, the default 1000 replaces dm_control's 500),
``agent.knee_back_left_locked`` (no effect, as upstream), ``agent.torso_density``,
``floor.color``, ``floor.friction``, ``gravity.x/y/z``, ``light.intensity``. Extra info:
``torso_velocity``.
"""

from __future__ import annotations

from ..mujoco_render import setup_gl

setup_gl()  # before dm_control picks its GL backend

from dm_control.suite import common, quadruped  # noqa: E402

from . import _factors as F  # noqa: E402
from ._locomotion import LocomotionWrapper  # noqa: E402

SPEEDS = {"walk": 0.5, "run": 5.0}
TIME_LIMIT = 20.0  # dm_control sizes the floor as time limit x speed


class QuadrupedDMControlWrapper(LocomotionWrapper):
    """The 12-actuator quadruped (actuator ranges of -1..1.1 and -0.8..0.8 are scaled from [-1, 1])."""

    ENV_NAME = "Quadruped"
    PHYSICS = quadruped.Physics
    DEFAULT_TASK = "walk"
    TASKS = {name: lambda r, v=v: quadruped.Move(desired_speed=v, random=r) for name, v in SPEEDS.items()}
    CONTROL_TIMESTEP = 0.02
    CAMERA_ID = 2
    HORIZONTAL_QPOS = (0, 1)

    def __init__(self, task="walk", seed=None, environment_kwargs=None, render_mode=None, *, render_quality="medium"):
        super().__init__(task, seed, environment_kwargs, render_mode, render_quality)

    def model_source(self, task):
        xml = quadruped.make_model(floor_size=TIME_LIMIT * SPEEDS[task])
        return xml.decode() if isinstance(xml, bytes) else xml, common.ASSETS

    @classmethod
    def factors(cls, task):
        return (
            F.agent_color((0.6, 0.3, 0.3)),
            F.Factor("agent.foot_back_left_density", F.density, F.GeomDensity(("foot_back_left",))),
            F.Factor("agent.knee_back_left_locked", F.switch, F.NoEffect()),
            F.Factor("agent.torso_density", F.density, F.GeomDensity(("torso",))),
            *F.floor_factors("floor"),
            *F.gravity_factors(),
            F.light_factor(),
        )

    def extra_info(self):
        return {"torso_velocity": self._physics.torso_velocity().copy()}

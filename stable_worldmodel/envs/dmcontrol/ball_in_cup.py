"""``swm/BallInCupDMControl-v0``: dm_control's ball_in_cup ``catch`` (see :mod:`.dmcontrol`).

Goal: the cup at the origin with the ball resting in it (``qpos = [0, 0, 0, 0.35]``);
``eval_state`` compares the ball's position relative to the cup within 0.025 (the target box's
half-size less the ball radius). ``eval_state()`` with no arguments is upstream's: whether the
ball is in the cup now.

Factors (upstream's): ``agent.color``, ``agent.density`` (the cup), ``ball.color`` (upstream: no
effect; here the default [0.7, 0.5, 0.3] keeps dm_control's ball color [0.7, 0.4, 0.2], as
upstream draws it, and any other value colors the ball), ``ball.density``, ``ball.size``
(radius), ``floor.color``, ``gravity.x/y/z``, ``light.intensity``, ``rendering.render_target``,
``target.color``, ``target.shape`` (the target site's alpha, color, and shape: 1 sphere, as
upstream makes dm_control's box, 0 box). Upstream leaves the target in site group 4, never
drawn; here ``rendering.render_target`` 1 also moves it to group 0, so it shows.
"""

from __future__ import annotations

from ..mujoco_render import setup_gl

setup_gl()  # before dm_control picks its GL backend

import numpy as np  # noqa: E402
from dm_control.suite import ball_in_cup  # noqa: E402

from . import _factors as F  # noqa: E402
from .dmcontrol import DMControlWrapper  # noqa: E402

CUP_PARTS = tuple(f"cup_part_{i}" for i in range(5))


class BallInCupDMControlWrapper(DMControlWrapper):
    """A cup on two sliders catching a ball on a string."""

    ENV_NAME = "BallInCup"
    PHYSICS = ball_in_cup.Physics
    DEFAULT_TASK = "catch"
    TASKS = {"catch": lambda r: ball_in_cup.BallInCup(random=r)}
    CONTROL_TIMESTEP = 0.02
    AGENT_JOINTS = ("cup_x", "cup_z")
    GOAL_TOLERANCE = 0.025

    def __init__(self, seed=None, environment_kwargs=None, render_mode=None, *, render_quality="medium"):
        super().__init__("catch", seed, environment_kwargs, render_mode, render_quality)

    @classmethod
    def factors(cls, task):
        return (
            F.agent_color(),
            F.Factor("agent.density", F.density, F.GeomDensity(CUP_PARTS)),
            F.Factor("ball.color", F.rgb, F.GeomRGB(("ball",), unless=F.AGENT_RGB)),
            F.Factor("ball.density", F.density, F.GeomDensity(("ball",))),
            F.Factor("ball.size", lambda: F.scalar(0.01, 0.05, 0.025, np.float32), F.GeomRadius("ball")),
            *F.floor_factors(),
            *F.gravity_factors(),
            F.light_factor(),
            *F.target_factors(F.SiteRGB("target"), F.SiteShape("target"), render=F.SiteShown("target")),
        )

    def goal_qpos(self):
        return np.array([0.0, 0.0, 0.0, 0.35])

    def goal_features(self, qpos):
        """The ball's (x, z) relative to the cup (the bodies start 0.4 apart in z)."""
        return np.array([qpos[2] - qpos[0], qpos[3] - qpos[1] - 0.4])

    def eval_state(self, goal_state=None, cur_state=None):
        """``(success, distance)`` of ``cur_state`` against ``goal_state``; with no arguments,
        upstream's check: whether the ball is in the cup now (a bool)."""
        if goal_state is None and cur_state is None:
            return bool(self._physics.in_target())
        return super().eval_state(goal_state, cur_state)

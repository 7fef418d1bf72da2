"""``swm/CartpoleDMControl-v0``: dm_control's cartpole ``swingup_sparse`` (see :mod:`.dmcontrol`).

Goal: the pole upright over the cart at the centre, at rest (``qpos = [0, 0]``); ``eval_state``
compares ``[x, cos(angle), sin(angle)]`` within 0.1 (the sparse reward's 5.7 degrees).

Factors (upstream's): ``agent.cart_mass`` (the cart's mass), ``agent.cart_shape`` (1: box, 0: an
ellipsoid of the same extent; upstream: no effect), ``agent.color``, ``agent.pole_density``
(scales the pole's fixed 0.1 kg mass by density / 1000; upstream: no effect), ``floor.color``,
``gravity.x/y/z``, ``light.intensity``.
"""

from __future__ import annotations

from ..mujoco_render import setup_gl

setup_gl()  # before dm_control picks its GL backend

import numpy as np  # noqa: E402
from dm_control.suite import cartpole  # noqa: E402

from . import _factors as F  # noqa: E402
from .dmcontrol import DMControlWrapper  # noqa: E402


class CartpoleDMControlWrapper(DMControlWrapper):
    """Cart-pole swing-up with a sparse reward (upright and centred)."""

    ENV_NAME = "Cartpole"
    PHYSICS = cartpole.Physics
    DEFAULT_TASK = "swingup_sparse"
    TASKS = {
        "swingup_sparse": lambda r: cartpole.Balance(swing_up=True, sparse=True, random=r),
        "swingup": lambda r: cartpole.Balance(swing_up=True, sparse=False, random=r),
        "balance": lambda r: cartpole.Balance(swing_up=False, sparse=False, random=r),
        "balance_sparse": lambda r: cartpole.Balance(swing_up=False, sparse=True, random=r),
    }
    GOAL_TOLERANCE = 0.1

    def __init__(
        self, seed=None, environment_kwargs=None, render_mode=None, *, task="swingup_sparse", render_quality="medium"
    ):
        super().__init__(task, seed, environment_kwargs, render_mode, render_quality)

    @classmethod
    def factors(cls, task):
        return (
            F.Factor("agent.cart_mass", lambda: F.scalar(0.5, 1.5, 1.0, np.float32), F.GeomMass("cart")),
            F.Factor("agent.cart_shape", F.switch, F.GeomShape("cart")),
            F.agent_color(),
            F.Factor("agent.pole_density", F.density, F.GeomDensity(("pole_1",))),
            *F.floor_factors(),
            *F.gravity_factors(),
            F.light_factor(),
        )

    def goal_qpos(self):
        return np.zeros(self.model.nq)

    def goal_features(self, qpos):
        return np.array([qpos[0], np.cos(qpos[1]), np.sin(qpos[1])])

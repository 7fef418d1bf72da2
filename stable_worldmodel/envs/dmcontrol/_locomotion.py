"""What the locomotion domains (Humanoid, Cheetah, Hopper, Walker, Quadruped) share.

These tasks reward moving (or standing), not reaching a state. Their goal is the model's
reference pose, ``qpos0``: standing upright at the origin, at rest. ``eval_state`` compares the
posture (``qpos`` without the root's horizontal position) within 0.5.
"""

from __future__ import annotations

import numpy as np

from .dmcontrol import DMControlWrapper


class LocomotionWrapper(DMControlWrapper):
    """A :class:`DMControlWrapper` whose goal is the reference pose."""

    GOAL_TOLERANCE = 0.5
    HORIZONTAL_QPOS: tuple[int, ...] = (0,)  # root translation entries left out of the posture

    def goal_features(self, qpos):
        return np.delete(np.asarray(qpos, float), self.HORIZONTAL_QPOS)

"""Experts for ``swm/PushT-v1`` / ``swm/PushT-Discrete-v1``: :class:`.expert.PushTExpert` on upstream's factors.

Upstream's T block (its default, ``block.shape`` = 2) is our ``tee`` at unit 30 whatever its
``block.scale``; the agent disk has radius ``0.375 x agent.scale``. The plan always assumes the
T block (other upstream block shapes are pushed as if they were the T). Actions of the
continuous expert stay in [-1, 1]^2; the discrete one bins them on upstream's polar grid.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ... import keys
from .expert import PushTExpert, _variation
from .shapes import shape_spec
from .v1 import quantize
from .v1_shapes import CIRCLE_RADIUS, TEE_SCALE


class PushTV1Expert(PushTExpert):
    """Batched expert of ``swm/PushT-v1`` (see the module docstring)."""

    def __init__(self, env_id: str = "swm/PushT-v1", **kwargs: Any):
        super().__init__(env_id=env_id, **kwargs)

    def get_action(self, infos: dict[str, Any], **kwargs: Any) -> np.ndarray:
        """``infos[state]``, ``infos[goal_state]``: ``(B, T, 7)`` -> actions ``(B, 2)`` float32."""
        state = np.asarray(infos[keys.STATE], np.float64)[:, -1]
        goal = np.asarray(infos[keys.GOAL_STATE], np.float64)[:, -1]
        block = shape_spec("tee", TEE_SCALE)
        out = np.zeros((state.shape[0], 2), np.float32)
        for i in range(state.shape[0]):
            radius = CIRCLE_RADIUS * _variation(infos, "agent.scale", 40.0, i)
            out[i] = self.act(state[i], goal[i], block, radius)
        return out


class PushTDiscreteV1Expert(PushTV1Expert):
    """:class:`PushTV1Expert` binned on the 16x16 polar grid of ``swm/PushT-Discrete-v1``."""

    def __init__(self, env_id: str = "swm/PushT-Discrete-v1", **kwargs: Any):
        super().__init__(env_id=env_id, **kwargs)

    def get_action(self, infos: dict[str, Any], **kwargs: Any) -> np.ndarray:
        """``(B, 2)`` int64 grid indices."""
        return quantize(super().get_action(infos, **kwargs))


__all__ = ["PushTDiscreteV1Expert", "PushTV1Expert"]

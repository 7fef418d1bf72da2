"""The ImagePositioning expert: move and turn every image straight towards its target."""

from __future__ import annotations

from typing import Any

import numpy as np

from ... import keys
from ...policy import ExpertPolicy
from .env import wrap_angle

# The largest step sizes of the factor ranges: dividing by them never overshoots, whatever the
# env's actual ``step`` factors are (a smaller step only makes the last approach geometric).
MAX_POSITION_STEP = 0.08
MAX_ANGLE_STEP = np.pi / 8
_STEP_KEYS = (f"{keys.VARIATION}.step.position", f"{keys.VARIATION}.step.angle")


class ImagePositioningExpert(ExpertPolicy):
    """Batched proportional expert for ``swm/ImagePositioning-v1``.

    ``get_action(infos)`` reads ``infos["state"]`` and ``infos["goal_state"]`` of shape
    ``(B, T, 3 * N)`` (last history step) and returns ``(B, 3 * N)`` float32 actions in
    ``[-1, 1]``: the position and wrapped angle errors divided by the step sizes, clipped. The
    step sizes are read from ``infos["variation.step.position"]`` / ``["variation.step.angle"]``
    when the world records them, else the largest values of their factor ranges are assumed.
    """

    def __init__(self, env_id: str = "swm/ImagePositioning-v1", **kwargs: Any):
        super().__init__(env_id=env_id, **kwargs)

    def get_action(self, infos: dict[str, np.ndarray], **kwargs: Any) -> np.ndarray:
        cur = np.asarray(infos[keys.STATE], np.float64)[:, -1]
        goal = np.asarray(infos[keys.GOAL_STATE], np.float64)[:, -1]
        b = cur.shape[0]
        pos_step, ang_step = (
            np.asarray(infos[k], np.float64)[:, -1].reshape(b, 1) if k in infos else np.full((b, 1), default)
            for k, default in zip(_STEP_KEYS, (MAX_POSITION_STEP, MAX_ANGLE_STEP), strict=False)
        )
        err = (goal - cur).reshape(b, -1, 3)
        err[..., :2] /= pos_step[:, :, None]
        err[..., 2] = wrap_angle(err[..., 2]) / ang_step
        return np.clip(err, -1.0, 1.0).reshape(b, -1).astype(np.float32)

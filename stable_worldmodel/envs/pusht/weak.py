"""``WeakPolicy``: the random, block-centred collection policy of PushT data recipes (0.0.3 / 0.1.1 name).

Each step it draws a uniform move in ``[-1, 1]^2`` per env, turns it into a target
``agent + action_scale * move``, clips the target into the square of half-side
``dist_constraint`` around the block (so the agent keeps touching the block), and returns the
move that reaches the clipped target, clipped to ``[-1, 1]``. It reads positions from
``infos["state"]`` (agent x, y at 0:2, block x, y at 2:4), so it works with envs in worker
processes. On ``swm/PushT-Discrete-v2`` the move is rounded to the nearest bin, on
``swm/PushT-Discrete-v1`` it is binned on upstream's 16x16 polar grid.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ... import keys
from ...errors import ConfigError
from ...policy import BasePolicy


class WeakPolicy(BasePolicy):
    """Random moves constrained to stay within ``dist_constraint`` (world units) of the block."""

    def __init__(self, dist_constraint: float = 100, seed: int | None = None, **kwargs: Any):
        if (
            isinstance(dist_constraint, bool)
            or not isinstance(dist_constraint, (int, float, np.number))
            or not dist_constraint > 0
        ):
            raise ConfigError(
                f"WeakPolicy requires dist_constraint to be a positive number (world units), got {dist_constraint!r}"
            )
        super().__init__(**kwargs)
        self.type = "weak"
        self.dist_constraint = float(dist_constraint)
        self.discrete = False
        self._scale = np.ones(1)
        self._n_bins: int | None = None
        self._polar = False
        self.set_seed(seed)

    def set_seed(self, seed: int | None) -> None:
        self.seed = seed
        self.rng = np.random.default_rng(seed)

    def set_env(self, env: Any) -> None:
        super().set_env(env)
        spec_id = _env_id(env)
        if spec_id is not None and "PushT" not in spec_id:
            raise ConfigError(f"WeakPolicy requires a PushT environment, got {spec_id!r}")
        self.discrete = spec_id is not None and "Discrete" in spec_id
        scales = env.call("action_scale") if hasattr(env, "call") else [env.unwrapped.action_scale]
        self._scale = np.asarray(scales, np.float64).reshape(-1, 1)
        self._polar = self.discrete and spec_id is not None and spec_id.endswith("-v1")
        if self.discrete and not self._polar:
            bins = env.call("bins") if hasattr(env, "call") else [env.unwrapped.bins]
            self._n_bins = len(np.asarray(bins[0]))

    def get_action(self, info_dict: dict[str, Any], **kwargs: Any) -> np.ndarray:
        state = np.asarray(info_dict[keys.STATE], np.float64)
        state = state[:, -1] if state.ndim == 3 else state.reshape(-1, state.shape[-1])
        agent, block = state[:, 0:2], state[:, 2:4]
        move = self.rng.uniform(-1.0, 1.0, size=agent.shape)
        target = np.clip(agent + move * self._scale, block - self.dist_constraint, block + self.dist_constraint)
        action = np.clip((target - agent) / self._scale, -1.0, 1.0)
        if self._polar:
            from .v1 import quantize

            return quantize(action)
        if self.discrete:
            from .env import nearest_bin

            return nearest_bin(action, self._n_bins)
        return action.astype(np.float32)


def _env_id(env: Any) -> str | None:
    """The Gymnasium id of a single env or of the envs of a World's vector env."""
    spec = getattr(env, "spec", None)
    if spec is None and hasattr(env, "call"):
        spec = env.call("spec")[0]
    return getattr(spec, "id", None)

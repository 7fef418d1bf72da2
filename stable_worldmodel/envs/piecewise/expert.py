"""Scripted expert of ``swm/Piecewise-v0``: inverts the step's motion equation."""

from __future__ import annotations

from typing import Any

import numpy as np

from ... import keys
from ...errors import ConfigError
from ...policy import ExpertPolicy
from .piecewise_env import DYNAMICS, zone_index


class PiecewiseExpert(ExpertPolicy):
    """Batched expert of upstream's Piecewise: ``pos' = pos + speed * action + bias[zone(pos)]``
    solved for the action, ``(goal - pos - bias) / speed``, clipped to ``[-1, 1]`` (upstream's
    ``ExpertPolicy``).

    Reads ``infos[state][:, -1]`` (B, 2), ``infos[goal_state][:, -1]`` (B, 2) and the env's private
    ``infos["_dynamics"][:, -1]`` (grid_n, speed, the zones' biases). ``action_noise`` adds seeded
    Gaussian noise of that std; with ``action_repeat_prob`` each env repeats its previous action with
    that probability, never on an episode's first step (``infos["step_idx"] == 0``), as upstream.
    Returns (B, 2) float32.
    """

    def __init__(
        self,
        env_id: str = "swm/Piecewise-v0",
        action_noise: float = 0.0,
        action_repeat_prob: float = 0.0,
        seed: int | None = None,
        **kwargs: Any,
    ):
        if not 0.0 <= float(action_repeat_prob) <= 1.0:
            raise ConfigError(f"PiecewiseExpert requires action_repeat_prob in [0, 1], got {action_repeat_prob!r}")
        if float(action_noise) < 0.0:
            raise ConfigError(f"PiecewiseExpert requires action_noise >= 0, got {action_noise!r}")
        super().__init__(env_id=env_id, **kwargs)
        self.action_noise, self.action_repeat_prob = float(action_noise), float(action_repeat_prob)
        self.seed = seed
        self.rng = np.random.default_rng(seed)
        self._last: np.ndarray | None = None

    def set_seed(self, seed: int | None) -> None:
        super().set_seed(seed)
        self._last = None

    def get_action(self, infos: dict[str, np.ndarray], **kwargs: Any) -> np.ndarray:
        pos = np.asarray(infos[keys.STATE], np.float32)[:, -1, :2]
        goal = np.asarray(infos[keys.GOAL_STATE], np.float32)[:, -1, :2]
        dyn = np.asarray(infos[DYNAMICS], np.float32)[:, -1]
        grid_n = int(dyn[0, 0])
        speed = dyn[:, 1:2]
        biases = dyn[:, 2:].reshape(len(dyn), -1, 2)
        zone = zone_index(pos, grid_n)
        bias = biases[np.arange(len(dyn)), zone]
        action = (goal - pos - bias) / np.maximum(speed, 1e-6)
        if self.action_noise > 0:
            action = action + self.rng.normal(0.0, self.action_noise, size=action.shape)
        if self._last is not None and self.action_repeat_prob > 0 and self._last.shape == action.shape:
            repeat = self.rng.uniform(size=len(action)) < self.action_repeat_prob
            if keys.STEP_IDX in infos:
                repeat &= np.asarray(infos[keys.STEP_IDX])[:, -1].reshape(-1) > 0
            action[repeat] = self._last[repeat]
        action = np.clip(action, -1.0, 1.0).astype(np.float32)
        self._last = action.copy()
        return action

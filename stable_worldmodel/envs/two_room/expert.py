"""Scripted expert of ``swm/TwoRoom-v2``: straight to the goal, through the best door when it is in the other room."""

from __future__ import annotations

from typing import Any

import numpy as np

from ... import keys
from ...policy import ExpertPolicy as ScriptedExpert
from .env import MAX_DOORS, RADIUS_RANGE, SPEED_RANGE

_R = RADIUS_RANGE[1]  # the expert does not see the radius: it plans for the largest one
_MARGIN = 0.25


class TwoRoomExpert(ScriptedExpert):
    """Batched door-seeking controller reading the layout from the state (no privileged access).

    From ``infos[state][:, -1]`` (B, 10) and ``infos[goal_state][:, -1]`` (B, 10): when the
    goal is across the wall, pick the open door minimising the path length through its
    centre, move in front of it until aligned with the gap, then cross; otherwise go to the
    goal. Proportional control with gain ``1 / max speed`` never overshoots a waypoint.
    ``noise`` adds Gaussian noise of that std to the bounded action (seeded by ``seed``) for data diversity.
    Returns actions (B, 2) in ``[-1, 1]``.
    """

    def __init__(self, env_id: str = "swm/TwoRoom-v2", noise: float = 0.0, seed: int | None = None, **kwargs: Any):
        super().__init__(env_id=env_id, noise=noise, seed=seed, **kwargs)
        self.rng = np.random.default_rng(seed)

    def get_action(self, infos: dict[str, np.ndarray], **kwargs: Any) -> np.ndarray:
        state = np.asarray(infos[keys.STATE], np.float64)[:, -1]
        goal = np.asarray(infos[keys.GOAL_STATE], np.float64)[:, -1, :2]
        target = np.array([self._target(s, g) for s, g in zip(state, goal, strict=True)]).reshape(-1, 2)
        action = (target - state[:, :2]) / SPEED_RANGE[1]
        action = np.clip(action, -1.0, 1.0)
        if self.noise:  # perturbs the bounded action, so saturated commands still vary
            action = np.clip(action + self.noise * self.rng.standard_normal(action.shape), -1.0, 1.0)
        return action.astype(np.float32)

    @staticmethod
    def _target(state: np.ndarray, goal: np.ndarray) -> np.ndarray:
        pos, wall_x, half_t = state[:2], state[2], state[3]
        side, goal_side = np.sign(pos[0] - wall_x), np.sign(goal[0] - wall_x)
        doors = state[4 : 4 + 2 * MAX_DOORS].reshape(MAX_DOORS, 2)
        doors = doors[doors[:, 1] > _R]
        if side == goal_side or side == 0 or not len(doors):
            return goal
        centres = np.stack([np.full(len(doors), wall_x), doors[:, 0]], 1)
        cost = np.linalg.norm(centres - pos, axis=1) + np.linalg.norm(centres - goal, axis=1)
        k = int(np.argmin(cost))
        centre_y, half_h = doors[k]
        clear = half_t + _R + 1.0
        if abs(pos[1] - centre_y) < half_h - _R - _MARGIN:  # aligned with the gap: cross
            return np.array([wall_x + goal_side * clear, centre_y])
        return np.array([wall_x - side * clear, centre_y])  # line up in front of the door


def _controller_for(env: Any) -> type[ScriptedExpert]:
    """The scripted controller of the TwoRoom that ``env`` (a vectorized env, or one env) holds."""
    from .v0 import TwoRoomV0Env
    from .v1 import TwoRoomV1Env

    first = getattr(env, "envs", None)
    base = getattr(first[0] if first else env, "unwrapped", None)
    if isinstance(base, TwoRoomV1Env):
        from .v1_expert import TwoRoomV1Expert

        return TwoRoomV1Expert
    if isinstance(base, TwoRoomV0Env):
        from .v0_expert import TwoRoomV0Expert

        return TwoRoomV0Expert
    return TwoRoomExpert


class ExpertPolicy(ScriptedExpert):
    """The scripted expert of any TwoRoom under the name and arguments of 0.0.3 / 0.1.1's
    ``envs.two_room.ExpertPolicy``: it drives the controller of the env it is set on
    (:class:`~.v1_expert.TwoRoomV1Expert` on ``swm/TwoRoom-v1``, upstream's env;
    :class:`~.v0_expert.TwoRoomV0Expert` on ``swm/TwoRoom-v0``; :class:`TwoRoomExpert` on
    ``swm/TwoRoom-v2`` and before ``set_env``).

    ``action_noise`` is the std of the Gaussian action noise; with probability
    ``action_repeat_prob`` an env repeats its previous action (a sticky-action collector).
    ``door_fit_margin`` (a door fits when its half-extent is that many agent radii) and
    ``door_reach_tol`` (px from the door centre at which the agent turns to the target) tune
    the approach on ``swm/TwoRoom-v1``; the other TwoRoom controllers keep them as attributes.
    """

    def __init__(
        self,
        action_noise: float = 0.0,
        action_repeat_prob: float = 0.0,
        door_fit_margin: float = 1.10,
        door_reach_tol: float | None = None,
        seed: int | None = None,
        **kwargs: Any,
    ):
        from ...errors import ConfigError

        if not 0.0 <= float(action_repeat_prob) <= 1.0:
            raise ConfigError(f"ExpertPolicy requires action_repeat_prob in [0, 1], got {action_repeat_prob!r}")
        super().__init__(seed=seed, **kwargs)
        self.action_noise = float(action_noise)
        self.action_repeat_prob = float(action_repeat_prob)
        self.door_fit_margin = float(door_fit_margin)
        self.door_reach_tol = door_reach_tol
        self._controller: ScriptedExpert = self._make(TwoRoomExpert)
        self.rng = self._repeat_rng(seed)
        self._last: np.ndarray | None = None

    @staticmethod
    def _repeat_rng(seed: int | None) -> np.random.Generator:
        """The stream of the sticky-action draws (apart from the controller's noise stream)."""
        return np.random.default_rng(None if seed is None else (int(seed), 1))

    def _make(self, cls: type[ScriptedExpert]) -> ScriptedExpert:
        controller = cls(noise=self.action_noise, seed=getattr(self, "seed", None))
        if hasattr(controller, "door_fit"):
            controller.door_fit = self.door_fit_margin
            if self.door_reach_tol is not None:
                controller.door_reached = float(self.door_reach_tol)
        return controller

    def set_env(self, env: Any) -> None:
        super().set_env(env)
        cls = _controller_for(env)
        if type(self._controller) is not cls:
            self._controller = self._make(cls)
        self._controller.set_env(env)

    def set_seed(self, seed: int | None) -> None:
        super().set_seed(seed)
        if seed is not None:
            self.rng = self._repeat_rng(seed)
            self._controller.set_seed(seed)
        self._last = None

    def get_action(self, infos: dict[str, np.ndarray], **kwargs: Any) -> np.ndarray:
        action = self._controller.get_action(infos, **kwargs)
        if self.action_repeat_prob > 0 and self._last is not None and self._last.shape == action.shape:
            repeat = self.rng.random(len(action)) < self.action_repeat_prob
            action[repeat] = self._last[repeat]
        self._last = action.copy()
        return action


__all__ = ["ExpertPolicy", "TwoRoomExpert"]

"""A scripted PushT expert: contact-point pushing with hull-avoiding travel.

Each step, for each env (stateless: a function of the current state and goal state):

1. If the block is within ``pos_done`` of its goal position and ``angle_done`` of its goal
   angle, the agent travels to the goal agent position (around the block's grown hull).
2. Otherwise every push candidate of :func:`.planner.contact_plan` is scored: a push of
   depth ``s`` moves the block along a known twist, so the best depth ``s*`` (capped) and the
   decrease of ``|block position error|^2 + (angle_weight * angle error)^2`` it buys follow in
   closed form. The candidate with the best decrease per unit of travel + push length wins.
3. If the agent sits on that candidate's approach line, it pushes (closing the gap plus at
   most ``push_step`` of depth); otherwise it travels to the candidate's pre-contact point.

Moves are turned into actions by inverting one control step of the PD agent: the agent is
kinematic, so one step moves it by exactly ``g_u u + g_v v0`` for a target offset ``u`` and
start velocity ``v0`` (:func:`.physics.pd_gains`). Block shape and scales are read from the infos keys
``variation.block.shape`` / ``variation.block.scale`` / ``variation.agent.scale`` when the
world records them, otherwise the defaults are assumed. Non-circle agents are treated as their
bounding disk.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ... import keys
from ...policy import ExpertPolicy
from .env import nearest_bin
from .physics import WINDOW, pd_gains
from .planner import PRE_MARGIN, SPACING, contact_plan
from .shapes import SHAPES, SYMMETRY, rotation, shape_spec
from .variation import AGENT_UNIT, BLOCK_UNIT

_GAIN_U, _GAIN_V = pd_gains()  # one step's displacement per unit target offset / start velocity


def _wrap(a: float, symmetry: int) -> float:
    """Signed angle difference in [-pi/symmetry, pi/symmetry) (0 for a circle)."""
    if symmetry == 0:
        return 0.0
    period = 2 * np.pi / symmetry
    return float((a + period / 2) % period - period / 2)


def _variation(infos: dict, name: str, default: float, i: int) -> float:
    key = f"{keys.VARIATION}.{name}"
    if key not in infos:
        return default
    return float(np.asarray(infos[key])[i].reshape(-1)[-1])


class PushTExpert(ExpertPolicy):
    """Batched PushT expert (see the module docstring); ``get_action(infos) -> (B, 2)``."""

    def __init__(
        self,
        env_id: str = "swm/PushT-v2",
        action_scale: float = 100.0,
        angle_weight: float = 50.0,
        pos_done: float = 6.0,
        angle_done: float = 0.1,
        push_step: float = 20.0,
        max_move: float = 40.0,
        **kwargs: Any,
    ):
        super().__init__(env_id=env_id, **kwargs)
        self.action_scale = float(action_scale)
        self.angle_weight = float(angle_weight)
        self.pos_done = float(pos_done)
        self.angle_done = float(angle_done)
        self.push_step = float(push_step)
        self.max_move = float(max_move)

    def get_action(self, infos: dict[str, Any], **kwargs: Any) -> np.ndarray:
        """``infos[state]``, ``infos[goal_state]``: ``(B, T, 7)`` -> actions ``(B, 2)`` float32."""
        state = np.asarray(infos[keys.STATE], np.float64)[:, -1]
        goal = np.asarray(infos[keys.GOAL_STATE], np.float64)[:, -1]
        out = np.zeros((state.shape[0], 2), np.float32)
        for i in range(state.shape[0]):
            block = shape_spec(
                SHAPES[int(_variation(infos, "block.shape", SHAPES.index("tee"), i))],
                BLOCK_UNIT * _variation(infos, "block.scale", 1.0, i),
            )
            radius = AGENT_UNIT * _variation(infos, "agent.scale", 1.0, i)
            out[i] = self.act(state[i], goal[i], block, radius)
        return out

    # -- one env -----------------------------------------------------------------------------
    def act(self, s: np.ndarray, g: np.ndarray, block, radius: float) -> np.ndarray:
        """Action in [-1, 1]^2 for state ``s`` (7,) and goal ``g`` (7,)."""
        plan = contact_plan(block, float(radius))
        rot = rotation(s[4])
        to_local = lambda p: (np.asarray(p) - s[2:4]) @ rot  # noqa: E731  (world -> block frame)
        agent = to_local(s[0:2])
        dp = (g[2:4] - s[2:4]) @ rot
        dth = _wrap(g[4] - s[4], SYMMETRY[block.name])
        if np.hypot(*dp) < self.pos_done and abs(dth) < self.angle_done:
            move_local = self._travel(plan, agent, to_local(g[0:2]), s, rot)
        else:
            move_local = self._push(plan, agent, dp, dth, s, rot)
        return self._to_action(move_local @ rot.T, s[5:7])

    def _push(self, plan, agent, dp, dth, s, rot) -> np.ndarray:
        w2 = self.angle_weight**2
        a = (plan.origin_twist**2).sum(1) + w2 * plan.spin**2
        b = plan.origin_twist @ dp + w2 * dth * plan.spin
        depth = np.clip(b / a, 0.0, 3 * self.push_step)
        gain = 2 * depth * b - depth**2 * a
        rel = agent - plan.points
        along = (rel * plan.normals).sum(1)
        lateral = rel[:, 1] * plan.normals[:, 0] - rel[:, 0] * plan.normals[:, 1]  # rel . tangent
        reach = np.linalg.norm(plan.pre - plan.points, axis=1)
        engaged = (np.abs(lateral) < 0.5 * SPACING + 0.5) & (along > 0.0) & (along < reach + 4.0)
        travel = np.linalg.norm(plan.pre - agent, axis=1)
        detour = plan.obstacle.blocked(np.broadcast_to(agent, plan.pre.shape), plan.pre)
        travel = np.where(engaged, 0.0, np.where(detour, 1.5 * travel + 40.0, travel))
        world_pre = plan.pre @ rot.T + s[2:4]
        on_table = np.all((world_pre > 8.0) & (world_pre < WINDOW - 8.0), axis=1)
        score = np.where(on_table & (gain > 0), gain / (depth + travel + 20.0), -np.inf)
        best = int(np.argmax(score))
        if not np.isfinite(score[best]):
            return np.zeros(2)
        if engaged[best]:
            n = plan.normals[best]
            tangent = np.array([-n[1], n[0]])
            gap = along[best] - (reach[best] - PRE_MARGIN)
            return -n * (gap + min(depth[best], self.push_step)) - lateral[best] * tangent
        return self._travel(plan, agent, plan.pre[best], s, rot)

    def _travel(self, plan, agent, target, s, rot) -> np.ndarray:
        obstacle = plan.obstacle
        if obstacle.depth(agent)[0] < 0:  # too close to the block: back off first
            k = int(np.argmax(agent @ obstacle.normals.T - obstacle.offsets))
            return obstacle.normals[k] * (obstacle.offsets[k] - agent @ obstacle.normals[k] + 2.0)
        corners = obstacle.corners @ rot.T + s[2:4]
        valid = np.all((corners > 0) & (corners < WINDOW), axis=1)
        return obstacle.next_waypoint(agent, np.asarray(target, np.float64), valid) - agent

    def _to_action(self, move: np.ndarray, velocity: np.ndarray) -> np.ndarray:
        norm = float(np.hypot(*move))
        if norm > self.max_move:
            move = move * (self.max_move / norm)
        u = (move - _GAIN_V * velocity) / _GAIN_U
        a = u / self.action_scale
        peak = float(np.abs(a).max())
        return a / peak if peak > 1.0 else a


class PushTDiscreteExpert(PushTExpert):
    """:class:`PushTExpert` rounded to the nearest move of ``swm/PushT-Discrete-v2``."""

    def __init__(self, env_id: str = "swm/PushT-Discrete-v2", n_bins: int = 11, **kwargs: Any):
        super().__init__(env_id=env_id, **kwargs)
        self.n_bins = int(n_bins)

    def get_action(self, infos: dict[str, Any], **kwargs: Any) -> np.ndarray:
        """``(B, 2)`` int64 bin indices."""
        return nearest_bin(super().get_action(infos, **kwargs), self.n_bins)


__all__ = ["PushTDiscreteExpert", "PushTExpert"]

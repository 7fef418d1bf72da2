"""Scripted experts of the Fetch envs: batched, stateless, read ``infos["state"]`` only.

``infos["state"]`` (``(B, T, D)``, the last frame used) is the flat observation followed by the
desired goal (see :mod:`.env`); actions are ``(B, 4)`` float32 in ``[-1, 1]``: a gripper
displacement of ``0.05 * action[:3]`` metres per step and the finger command ``action[3]``
(``+1`` opens, ``-1`` closes; ignored by the tasks with a blocked gripper).

- Reach: straight to the goal.
- Push: up to a safe height, over to a point behind the block on the line from the goal through
  the block, down to the table, then push along that line; it goes round again whenever the
  block leaves the line.
- Pick-and-place: over the block with the fingers open, down, close, then carry the block to the
  goal (on the table or in the air).

Slide has none: the closed fingers are two thin plates with a gap between them, so a centred push
wedges the puck's rim into the gap (MuJoCo's box-cylinder contacts then clamp the puck, which stops
with the gripper), and an off-centre strike sends it off at an angle that depends on the strike's
speed and direction; a script would need that calibrated over speed, direction and the friction
and mass factors (a first strike-and-stop script reached 17 %).

Measured with ``World(num_envs=8, image_shape=(64, 64))``, ``evaluate(episodes=100, seed=0,
eval_keys=["is_success"])`` (success = ``is_success`` at the 50th step; these envs never terminate):
Reach 100 %, Push 100 %, Pick-and-place 100 % with the default reset (the looks resampled, as
upstream); with ``options={"variation": ["all"]}`` (positions, size, mass, friction too) 100 %,
99 %, 95 %.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ... import keys
from ...errors import ConfigError
from ...policy import ExpertPolicy

STEP = 0.05  # metres per unit of action


def _toward(src: np.ndarray, dst: np.ndarray, speed: float | np.ndarray = 1.0) -> np.ndarray:
    """(B, 3) actions that move ``src`` to ``dst`` in one step where possible, at most ``speed``."""
    a = (dst - src) / STEP
    norm = np.linalg.norm(a, axis=-1, keepdims=True)
    speed = np.asarray(speed, np.float64).reshape(-1, 1) if np.ndim(speed) else speed
    scale = np.minimum(1.0, speed / np.maximum(norm, 1e-9))
    return np.clip(a * scale, -1.0, 1.0)


def reach(state: np.ndarray) -> np.ndarray:
    """(B, 4) actions for Reach states (B, 13)."""
    out = np.zeros((state.shape[0], 4))
    out[:, :3] = _toward(state[:, 0:3], state[:, -3:])
    return out


def _line(obj: np.ndarray, goal: np.ndarray) -> np.ndarray:
    """Unit xy direction from the object to the goal (B, 2)."""
    d = goal[:, :2] - obj[:, :2]
    return d / np.maximum(np.linalg.norm(d, axis=-1, keepdims=True), 1e-9)


PUSH = {"behind": 0.06, "safe": 0.06, "aligned": 0.012, "speed": 0.6, "done": 0.01}


def push(state: np.ndarray) -> np.ndarray:
    """(B, 4) actions for Push states (B, 28)."""
    p = PUSH
    grip, obj, goal = state[:, 0:3], state[:, 3:6], state[:, -3:]
    line = _line(obj, goal)
    rel = grip[:, :2] - obj[:, :2]
    along = np.sum(rel * line, axis=-1)
    lateral = np.linalg.norm(rel - along[:, None] * line, axis=-1)
    pre = obj.copy()
    pre[:, :2] -= p["behind"] * line
    low = np.abs(grip[:, 2] - obj[:, 2]) < 0.015
    pushing = (along < -0.02) & (along > -p["behind"] - 0.02) & (lateral < p["aligned"]) & low
    at_pre_xy = np.linalg.norm(grip[:, :2] - pre[:, :2], axis=-1) < p["aligned"]
    target = pre.copy()
    safe = obj[:, 2] + p["safe"]
    high_enough = grip[:, 2] > safe - 0.015
    # not over the push point: up first, then across at the safe height; over it: down
    target[:, 2] = np.where(at_pre_xy, obj[:, 2], safe)
    go_up = ~at_pre_xy & ~high_enough
    target[go_up, :2] = grip[go_up, :2]
    out = np.zeros((state.shape[0], 4))
    out[:, :3] = _toward(grip, target)
    # pushing: through the block along the line (lateral errors steer back onto it)
    dest = obj.copy()
    dest[:, :2] = goal[:, :2] - (p["behind"] - 0.035) * line
    dest[:, 2] = obj[:, 2]
    out[pushing, :3] = _toward(grip[pushing], dest[pushing], p["speed"])
    done = np.linalg.norm(obj[:, :2] - goal[:, :2], axis=-1) < p["done"]
    out[done, :3] = 0.0
    return out


PICK = {"above": 0.08, "xy": 0.008, "z": 0.008, "open": 0.09, "still": 1e-3, "held": 0.02}


def pick_and_place(state: np.ndarray) -> np.ndarray:
    """(B, 4) actions for Pick-and-place states (B, 28)."""
    p = PICK
    grip, obj, goal = state[:, 0:3], state[:, 3:6], state[:, -3:]
    width = state[:, 9] + state[:, 10]
    rel = obj - grip
    over = np.linalg.norm(rel[:, :2], axis=-1) < p["xy"]
    at = over & (np.abs(rel[:, 2]) < p["z"])
    # fingers closed on the block: nearly shut, no longer moving, the block between them
    still = np.abs(state[:, 23]) + np.abs(state[:, 24]) < p["still"]
    held = (np.linalg.norm(rel, axis=-1) < p["held"]) & (width < p["open"]) & (width > 0.005) & still
    out = np.zeros((state.shape[0], 4))
    above = obj.copy()
    above[:, 2] += p["above"]
    high_enough = grip[:, 2] > obj[:, 2] + 0.04
    approach = above.copy()
    approach[~high_enough & ~over, :2] = grip[~high_enough & ~over, :2]  # up before going across
    target = np.where(over[:, None], obj, approach)
    out[:, :3] = _toward(grip, target)
    out[:, 3] = 1.0
    closing = at & ~held
    out[closing, :3] = 0.0
    out[closing, 3] = -1.0
    out[held, :3] = _toward(grip[held], goal[held])
    out[held, 3] = -1.0
    return out


POLICIES = {"Reach": reach, "Push": push, "PickAndPlace": pick_and_place}
TASKS = tuple(POLICIES)  # the tasks with an expert


class FetchExpert(ExpertPolicy):
    """The scripted expert of a Fetch task (see the module docstring), batched over World's infos."""

    def __init__(self, env_id: str = "swm/FetchReach-v3", **kwargs: Any):
        super().__init__(env_id=env_id, **kwargs)
        task = next((t for t in TASKS if str(env_id).startswith(f"swm/Fetch{t}")), None)
        if task is None:
            raise ConfigError(
                f"FetchExpert requires a Fetch env id (swm/Fetch<Task>[Dense|Dict]-v3, Task in {list(TASKS)}), "
                f"got {env_id!r}"
            )
        self.task = task
        self._policy = POLICIES[task]

    def get_action(self, infos: dict[str, np.ndarray], **kwargs: Any) -> np.ndarray:
        state = np.asarray(infos[keys.STATE], np.float64)
        if state.ndim == 3:
            state = state[:, -1]
        return self._policy(state.reshape(state.shape[0], -1)).astype(np.float32)

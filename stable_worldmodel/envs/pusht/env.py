"""``swm/PushT-v2`` and ``swm/PushT-Discrete-v2``: push a T-shaped block onto a goal pose.

Our design of the task (``swm/PushT-v1`` / ``swm/PushT-Discrete-v1`` behave as upstream 0.1.1:
:mod:`.v1`, subclasses of these classes).

The block-pushing task of Diffusion Policy and DINO-WM (physics in :mod:`.physics`):

- **Table**: 512x512 world units, walled; physics at 100 Hz, one env step = 10 sub-steps.
- **Agent**: a kinematic disk of radius 15 driven by a PD controller (k_p = 100, k_v = 20)
  towards a target position.
- **Block**: the T of two 120x30 bars (mass 1), pushed quasi-statically (no sliding).
- **Action** (PushT-v2): ``a`` in [-1, 1]^2, a relative move: the PD target is
  ``agent position + action_scale * a`` (``action_scale = 100`` world units by default),
  clipped to the table [0, 512]^2. From rest a full action moves the agent ~30 units in one
  step (:func:`.physics.pd_gains`); holding it, the agent cruises at ~37 units per step.
- **Action** (PushT-Discrete-v2): ``MultiDiscrete([n_bins, n_bins])`` (``n_bins = 11``); index
  ``i`` on an axis is the relative move ``sign(t) t^2`` of PushT-v2 with ``t = -1 + 2 i /
  (n_bins - 1)``: quadratic spacing, fine near 0 (0.04) for precise pushes, 1 at the ends.
- **state** (float64, 7): agent x, y, block x, y (the body origin: the middle of the top
  edge of the T's bar), block angle in [0, 2pi), agent vx, vy. **proprio** (float64, 4):
  agent x, y, vx, vy.
- **Goal**: block pose (256, 256, pi/4) by default (factors ``goal.position``, ``goal.angle``)
  and an agent position 20 units clear of the block's top side at that pose; ``goal_state``
  has the state layout with zero velocity.
- **Success** (as released in 0.0.3): ``||state[:4] - goal[:4]|| < 20`` (agent and block
  positions together) and block angle within pi/9 of the goal's (wrapped; for a block shape
  with rotational symmetry, modulo that symmetry, e.g. pi/2 for the square, any angle for the
  circle). ``terminated`` = success; ``eval_state`` returns ``(success, ||state[:4] - goal[:4]||)``.
- **Reward** (shaped progress in [0, 1], 1 exactly at the goal pose):
  ``1 - 0.5 min(block position error / 256, 1) - 0.5 block angle error / pi``.
- **Start**: agent and block positions and the block angle are drawn from the reset seed
  (gym-pusht's ranges; see :mod:`.variation` for all 17 factors of variation).
- **Rendering**: anti-aliased, drawn directly at ``render_size`` (224x224 by default; World
  sets its ``image_shape`` through :meth:`set_render_size`). Headless (OpenCV, no window).
  The goal silhouette is drawn unless the factor ``rendering.render_goal`` is 0.
- **Info** (upstream's keys and meaning): ``goal``, ``goal_state``, ``goal_proprio``, and
  ``pos_agent`` (2,) agent position, ``vel_agent`` (2,) agent velocity, ``block_pose`` (3,)
  block x, y and angle (not wrapped), ``goal_pose`` (3,) the pose the goal silhouette is
  drawn at (``goal_state[2:5]``), ``n_contacts`` (int) contact points solved during the last
  step divided by its sub-step count, rounded up (0 after reset).
"""

from __future__ import annotations

import math
from typing import Any

import gymnasium as gym
import numpy as np

from ... import keys
from ...errors import ConfigError
from ..base import DatasetResetMixin, apply_variation_options, check_render_size, flatten_values
from .physics import CONTROL_HZ, SIM_HZ, WINDOW, PushTPhysics, body_state, on_post_solve, set_pose
from .render import draw_scene
from .shapes import SHAPES, SYMMETRY, ShapeSpec, angle_error, shape_spec, to_world
from .variation import AGENT_UNIT, BLOCK_UNIT, build_variation_space, draw_seeded

POS_TOLERANCE = 20.0
ANGLE_TOLERANCE = math.pi / 9
GOAL_AGENT_GAP = 20.0
MAX_SPEED = 1e4  # bound of the velocity entries of the observation space (the PD agent stays under ~2000)
_PROPRIO = [0, 1, 5, 6]
_SUBSTEPS = SIM_HZ // CONTROL_HZ

# Info keys of upstream's PushT (kept with their meaning; see the module docstring).
POS_AGENT = "pos_agent"
VEL_AGENT = "vel_agent"
BLOCK_POSE = "block_pose"
GOAL_POSE = "goal_pose"
N_CONTACTS = "n_contacts"


def goal_agent_offset(block: ShapeSpec, agent: ShapeSpec) -> np.ndarray:
    """Where the agent waits at the goal, in the block's local frame: clear of its top side."""
    return np.array([block.cog[0], block.bounds()[1] - agent.reach() - GOAL_AGENT_GAP])


def discrete_bins(n_bins: int) -> np.ndarray:
    """``(n_bins,)`` relative move of each index of one axis of PushT-Discrete (quadratic spacing)."""
    t = np.linspace(-1.0, 1.0, int(n_bins))
    return np.sign(t) * t**2


def nearest_bin(move: Any, n_bins: int) -> np.ndarray:
    """Indices ``(..., 2)`` int64 of the bins of :func:`discrete_bins` nearest to ``move`` (..., 2)."""
    m = np.asarray(move, np.float64)
    return np.abs(m[..., None] - discrete_bins(n_bins)).argmin(-1).astype(np.int64)


def _state_option(value: Any, name: str) -> np.ndarray:
    s = np.asarray(value, np.float64).reshape(-1)
    if s.shape[0] not in (5, 7):
        raise ConfigError(f"PushT requires reset option {name!r} of length 5 or 7, got shape {np.shape(value)}")
    return np.concatenate([s, np.zeros(7 - s.shape[0])])


class PushT(DatasetResetMixin, PushTPhysics, gym.Env):
    """Push the T block onto its goal pose (see the module docstring)."""

    metadata = {"render_modes": ["rgb_array"], "render_fps": CONTROL_HZ}
    reward_range = (0.0, 1.0)

    def __init__(
        self,
        render_mode: str | None = "rgb_array",
        render_size: tuple[int, int] = (224, 224),
        action_scale: float = 100.0,
        resolution: int | None = None,
    ):
        if resolution is not None:  # the original release's name for a square render size
            render_size = (resolution, resolution)
        if render_mode not in (None, "rgb_array"):
            raise ConfigError(f"PushT requires render_mode 'rgb_array' or None, got {render_mode!r}")
        if not float(action_scale) > 0:
            raise ConfigError(f"PushT requires action_scale > 0, got {action_scale!r}")
        self.render_mode = render_mode
        self.render_size = (224, 224)
        self.set_render_size(render_size)
        self.action_scale = float(action_scale)
        box = gym.spaces.Box
        pos, vel = (-WINDOW, 2 * WINDOW), (-MAX_SPEED, MAX_SPEED)  # generous: the agent may overshoot the table
        self.observation_space = gym.spaces.Dict(
            {
                keys.PROPRIO: box(
                    np.array([pos[0]] * 2 + [vel[0]] * 2), np.array([pos[1]] * 2 + [vel[1]] * 2), dtype=np.float64
                ),
                keys.STATE: box(
                    np.array([pos[0]] * 4 + [0.0] + [vel[0]] * 2),
                    np.array([pos[1]] * 4 + [2 * np.pi] + [vel[1]] * 2),
                    dtype=np.float64,
                ),
            }
        )
        self.action_space = box(-1.0, 1.0, (2,), np.float32)
        self.variation_space = build_variation_space()
        self.agent = self.block = None
        self._specs: dict[str, ShapeSpec] = {}
        self._state = np.zeros(7)
        self._goal_state = np.zeros(7)
        self._goal_img: np.ndarray | None = None
        self._values: dict[str, Any] = self.variation_space.value
        self._contact_points = 0  # counted by _count_contacts during a step
        self._n_contacts = 0

    # -- protocol hooks ---------------------------------------------------------------------
    def set_render_size(self, size: tuple[int, int]) -> None:
        """Make :meth:`render` (and the goal image) ``size`` = (H, W) frames."""
        self.render_size = check_render_size("PushT", size)
        self._goal_img = None

    def eval_state(self, goal_state: np.ndarray, cur_state: np.ndarray):
        """``(success, distance)``: see the module docstring. Works on ``(..., 7)`` arrays too."""
        g, c = np.asarray(goal_state, np.float64), np.asarray(cur_state, np.float64)
        dist = np.linalg.norm(g[..., :4] - c[..., :4], axis=-1)
        success = (dist < POS_TOLERANCE) & (angle_error(g[..., 4], c[..., 4], self._symmetry()) < ANGLE_TOLERANCE)
        if np.ndim(dist) == 0:
            return bool(success), float(dist)
        return success, dist

    def fix_action_sample(self, action: Any) -> np.ndarray:
        """Project an action (or a ``(..., 2)`` batch) onto :attr:`action_space`."""
        return np.clip(np.asarray(action, np.float32), -1.0, 1.0)

    # -- gym API ----------------------------------------------------------------------------
    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None):
        super().reset(seed=seed)
        options = dict(options or {})
        apply_variation_options(self.variation_space, options, self.np_random)
        v = self.variation_space.value
        agent_spec = shape_spec(SHAPES[int(v["agent"]["shape"])], AGENT_UNIT * float(v["agent"]["scale"]))
        block_spec = shape_spec(SHAPES[int(v["block"]["shape"])], BLOCK_UNIT * float(v["block"]["scale"]))
        given = set(flatten_values(options.get(keys.VARIATION_VALUES) or {}))
        draw_seeded(self.variation_space, given, agent_spec, block_spec, self.np_random)
        v = self._values = self.variation_space.value  # read by _draw (reading the space is slow)
        goal_spec = shape_spec(block_spec.name, block_spec.unit * float(v["goal"]["scale"]))
        self._specs = {"agent": agent_spec, "block": block_spec, "goal": goal_spec}

        self.new_space()
        on_post_solve(self.space, self._count_contacts)
        self._contact_points = self._n_contacts = 0
        self.agent = self.add_spec(agent_spec, v["agent"]["start_position"], float(v["agent"]["angle"]), kinematic=True)
        self.agent.velocity = tuple(float(x) for x in v["agent"]["velocity"])
        self.block = self.add_spec(block_spec, v["block"]["start_position"], float(v["block"]["angle"]))
        if options.get(keys.STATE) is not None:
            s = _state_option(options[keys.STATE], keys.STATE)
            self.agent.position, self.agent.velocity = (s[0], s[1]), (s[5], s[6])
            set_pose(self.block, s[2:4], s[4])

        gpos, gangle = np.asarray(v["goal"]["position"], np.float64), float(v["goal"]["angle"])
        gagent = to_world(goal_agent_offset(block_spec, agent_spec)[None], gpos, gangle)[0]
        self._goal_state = np.array([*gagent, *gpos, gangle % (2 * np.pi), 0.0, 0.0])
        if options.get(keys.GOAL_STATE) is not None:
            self._goal_state = _state_option(options[keys.GOAL_STATE], keys.GOAL_STATE)
        self._goal_img = None
        self._state = body_state(self.agent, self.block)
        return self._obs(), self._info()

    def step(self, action):
        mx, my = self._relative_move(action)
        x, y = self.agent.position
        target = (min(max(x + self.action_scale * mx, 0.0), WINDOW), min(max(y + self.action_scale * my, 0.0), WINDOW))
        self._contact_points = 0
        self.pd_step(self.agent, self.space, target)
        self._n_contacts = -(-self._contact_points // _SUBSTEPS)  # ceil, as upstream
        self._state = body_state(self.agent, self.block)
        success, _ = self.eval_state(self._goal_state, self._state)
        return self._obs(), self._reward(self._state), success, False, self._info()

    def _set_state(self, state: Any) -> None:
        """Put the agent and block at ``state`` (7 numbers, or 5 with zero agent velocity), as 0.0.3's PushT.

        Used by ``evaluate_from_dataset(callables=[{"method": "_set_state", ...}])``.
        """
        s = _state_option(state, keys.STATE)
        self.agent.position, self.agent.velocity = (s[0], s[1]), (s[5], s[6])
        set_pose(self.block, s[2:4], s[4])
        self._state = body_state(self.agent, self.block)

    def _set_goal_state(self, goal_state: Any) -> None:
        """Use ``goal_state`` (7 numbers) as the goal from now on (success, reward and goal image)."""
        self._goal_state = _state_option(goal_state, keys.GOAL_STATE)
        self._goal_img = None

    def render(self) -> np.ndarray:
        """The current scene as an ``(H, W, 3)`` uint8 frame at :attr:`render_size`."""
        s = self._state
        return self._draw(s[0:2], float(self.agent.angle), s[2:4], s[4])

    def close(self) -> None:
        self.space = self.agent = self.block = None

    # -- internals --------------------------------------------------------------------------
    def _relative_move(self, action: Any) -> tuple[float, float]:
        """The relative move in [-1, 1]^2 that ``action`` stands for."""
        a = np.asarray(action, np.float64).reshape(-1)
        if a.shape != (2,) or not (math.isfinite(a[0]) and math.isfinite(a[1])):
            raise ConfigError(f"{type(self).__name__} requires a finite action of shape (2,), got {action!r}")
        return min(max(float(a[0]), -1.0), 1.0), min(max(float(a[1]), -1.0), 1.0)

    def _reward(self, state: np.ndarray) -> float:
        g = self._goal_state
        pos = min(float(np.hypot(*(state[2:4] - g[2:4]))) / (WINDOW / 2), 1.0)
        return float(1.0 - 0.5 * pos - 0.5 * float(angle_error(state[4], g[4], self._symmetry())) / np.pi)

    def _count_contacts(self, arbiter, space, data) -> None:
        self._contact_points += len(arbiter.contact_point_set.points)

    def _symmetry(self) -> int:
        return SYMMETRY[self._specs["block"].name] if self._specs else 1

    def _obs(self) -> dict[str, np.ndarray]:
        return {keys.PROPRIO: self._state[_PROPRIO].copy(), keys.STATE: self._state.copy()}

    def _info(self) -> dict[str, Any]:
        if self._goal_img is None:  # drawn once per reset (and render size); copied out
            g = self._goal_state
            self._goal_img = self._draw(g[0:2], float(self.agent.angle), g[2:4], g[4])
        return {
            keys.GOAL: self._goal_img.copy(),
            keys.GOAL_STATE: self._goal_state.copy(),
            keys.GOAL_PROPRIO: self._goal_state[_PROPRIO].copy(),
            POS_AGENT: self._state[0:2].copy(),
            VEL_AGENT: self._state[5:7].copy(),
            BLOCK_POSE: np.array([*self.block.position, self.block.angle], np.float64),
            GOAL_POSE: self._goal_state[2:5].copy(),
            N_CONTACTS: self._n_contacts,
        }

    def _draw(self, agent_xy, agent_angle: float, block_xy, block_angle: float) -> np.ndarray:
        v = self._values
        g = self._goal_state
        goal = (self._specs["goal"], g[2:4], g[4], v["goal"]["color"]) if int(v["rendering"]["render_goal"]) else None
        return draw_scene(
            self.render_size,
            v["background"]["color"],
            goal,
            (self._specs["block"], block_xy, block_angle, v["block"]["color"]),
            (self._specs["agent"], agent_xy, agent_angle, v["agent"]["color"]),
        )


class PushTDiscrete(PushT):
    """PushT with ``MultiDiscrete([n_bins, n_bins])`` relative moves (see the module docstring)."""

    def __init__(self, n_bins: int = 11, **kwargs: Any):
        if isinstance(n_bins, bool) or not isinstance(n_bins, (int, np.integer)) or n_bins < 3 or n_bins % 2 == 0:
            raise ConfigError(f"PushTDiscrete requires an odd integer n_bins >= 3 (so 0 is a move), got {n_bins!r}")
        super().__init__(**kwargs)
        self.n_bins = int(n_bins)
        self._bins = discrete_bins(self.n_bins)
        self.action_space = gym.spaces.MultiDiscrete([self.n_bins, self.n_bins])

    def bins(self) -> np.ndarray:
        """``(n_bins,)`` relative move of each index on one axis (see :func:`discrete_bins`)."""
        return discrete_bins(self.n_bins)

    def fix_action_sample(self, action: Any) -> np.ndarray:
        """Round and clip bin indices (or a ``(..., 2)`` batch) onto :attr:`action_space`."""
        return np.clip(np.rint(np.asarray(action, np.float64)), 0, self.n_bins - 1).astype(np.int64)

    def to_index(self, move: Any) -> np.ndarray:
        """The nearest bin indices ``(..., 2)`` of relative moves ``(..., 2)`` in [-1, 1]."""
        return nearest_bin(move, self.n_bins)

    def _relative_move(self, action: Any) -> np.ndarray:
        a = np.asarray(action).reshape(-1)
        if a.shape != (2,) or not np.issubdtype(a.dtype, np.integer) or a.min() < 0 or a.max() >= self.n_bins:
            raise ConfigError(
                f"PushTDiscrete requires an action of 2 integers in [0, {self.n_bins - 1}], got {action!r}"
            )
        bins = self._bins
        return float(bins[a[0]]), float(bins[a[1]])

"""``swm/PushT-v1`` and ``swm/PushT-Discrete-v1`` with the behaviour of upstream 0.1.1.

Our own design lives on as ``swm/PushT-v2`` / ``swm/PushT-Discrete-v2`` (:mod:`.env`); these
subclasses change only what upstream does differently:

- **Action**: the PD target is ``agent position + 100 * action`` (the product formed in the
  action's dtype), neither the action nor the target is clipped. ``relative=False`` makes the
  action the absolute target.
- **Discrete**: ``MultiDiscrete([16, 16])`` polar grid: index ``(i, j)`` is the move of length
  ``(i + 0.5) / 16`` at angle ``(j + 0.5) / 16 * 2 pi`` (:func:`dequantize`).
- **Reward**: ``-||goal_state - state||`` over the 7 numbers.
- **Success** (``terminated``): ``||state[:4] - goal[:4]|| < 20`` and block angle within pi/9;
  ``eval_state`` returns ``(success, ||goal - state||)`` over the 7 numbers.
- **Reset**: the variation space is seeded with the reset seed (as upstream, so a seed draws
  upstream's start, goal and factors; without a seed, from the env's generator), reset to its
  defaults, and ``agent.start_position``, ``block.start_position`` and ``block.angle`` are
  resampled unless ``options["variation"]`` names others; with no ``goal_state`` option the goal
  is a second draw of those three factors (agent velocity: the ``agent.velocity`` factor). The
  env puts the bodies at the goal, takes one physics step (10 ms), renders the goal image,
  then puts them at the start and takes one more step; ``n_contacts`` at reset counts both.
- **Factors**: upstream's names, ranges and defaults (:func:`build_v1_variation_space`);
  ``*.scale`` is an absolute size in [20, 60] (default 40; the agent disk's radius is
  0.375 x scale, the T ignores it); shapes index ``V1_SHAPES``.
- **Frames**: :mod:`.v1_render` (upstream's look: 512 canvas resized); the silhouette is drawn
  at ``goal.position`` / ``goal.angle`` (``info["goal_pose"]``), not at the goal state.
- **Info**: as :mod:`.env` plus ``env_name`` = ``"PushT"``.
- **Spaces**: upstream's observation layout (``proprio`` agent x, y, vx, vy; ``state`` agent x,
  y, block x, y, block angle in [0, 2pi), agent vx, vy) with unbounded positions and velocities
  (upstream declares [0, 512], which its own unclipped states leave).
"""

from __future__ import annotations

import math
from typing import Any

import gymnasium as gym
import numpy as np

from ... import keys, spaces
from ...errors import ConfigError
from ..base import check_variation_option
from .env import GOAL_POSE, PushT, _state_option
from .physics import CONTROL_HZ, K_P, K_V, SIM_HZ, WINDOW, body_state, on_post_solve
from .v1_render import draw_v1_scene
from .v1_shapes import V1_SHAPES, body_outline, make_body

DEFAULT_VARIATIONS = ("agent.start_position", "block.start_position", "block.angle")
ENV_NAME = "env_name"
N_RADIAL = N_ANGULAR = 16
MAX_MOVE = 1.0
_DT = 1.0 / SIM_HZ
_SUBSTEPS = SIM_HZ // CONTROL_HZ


def build_v1_variation_space() -> spaces.Dict:
    """Upstream 0.1.1's PushT factors (names, ranges, defaults, sampling order)."""
    two_pi = 2 * np.pi

    def box(low, high, init, shape=(), dtype=np.float64):
        return spaces.Box(low, high, shape=shape, dtype=dtype, init_value=np.asarray(init, dtype))

    def rgb(c):
        return spaces.RGBBox(init_value=np.asarray(c, np.uint8))

    # Keys in alphabetical order at every level, as Gymnasium sorts upstream's plain dicts: the
    # per-key seeds and the sampling order inside each group follow it, so a reset seed draws
    # the factors upstream draws.
    return spaces.Dict(
        {
            "agent": spaces.Dict(
                {
                    "angle": box(-two_pi, two_pi, 0.0),
                    "color": rgb((65, 105, 225)),
                    "scale": box(20, 60, 40, dtype=np.float32),
                    "shape": spaces.Discrete(len(V1_SHAPES), start=0, init_value=0),
                    "start_position": box(50, 450, (256.0, 400.0), (2,)),
                    "velocity": box(0, WINDOW, (0.0, 0.0), (2,)),
                }
            ),
            "background": spaces.Dict({"color": rgb((255, 255, 255))}),
            "block": spaces.Dict(
                {
                    "angle": box(-two_pi, two_pi, 0.0),
                    "color": rgb((119, 136, 153)),
                    "scale": box(20, 60, 40, dtype=np.float32),
                    "shape": spaces.Discrete(len(V1_SHAPES) - 1, start=1, init_value=2),
                    "start_position": box(100, 400, (400.0, 100.0), (2,)),
                }
            ),
            "goal": spaces.Dict(
                {
                    "angle": box(-two_pi, two_pi, np.pi / 4),
                    "color": rgb((144, 238, 144)),
                    "position": box(50, 450, (256.0, 256.0), (2,)),
                    "scale": box(20, 60, 40, dtype=np.float32),
                }
            ),
            "rendering": spaces.Dict({"render_goal": spaces.Discrete(2, init_value=1)}),
        },
        sampling_order=["background", "goal", "block", "agent", "rendering"],
    )


def dequantize(index: Any) -> np.ndarray:
    """``(..., 2)`` float32 moves of polar grid indices ``(..., 2)`` (radius bin, angle bin)."""
    idx = np.asarray(index)
    radius = (idx[..., 0] + 0.5) / N_RADIAL * MAX_MOVE
    theta = (idx[..., 1] + 0.5) / N_ANGULAR * 2 * np.pi
    return np.stack([radius * np.cos(theta), radius * np.sin(theta)], -1).astype(np.float32)


def quantize(move: Any) -> np.ndarray:
    """``(..., 2)`` int64 polar grid indices of moves ``(..., 2)`` (upstream's binning)."""
    m = np.asarray(move, np.float64)
    radius = np.linalg.norm(m, axis=-1)
    theta = np.arctan2(m[..., 1], m[..., 0]) % (2 * np.pi)
    r_bin = np.clip(radius / MAX_MOVE * N_RADIAL, 0, N_RADIAL - 1).astype(np.int64)
    t_bin = np.clip(theta / (2 * np.pi) * N_ANGULAR, 0, N_ANGULAR - 1).astype(np.int64)
    return np.stack([r_bin, t_bin], -1)


class PushTV1(PushT):
    """PushT as upstream 0.1.1 (see the module docstring)."""

    reward_range = (-math.inf, 0.0)

    def __init__(
        self,
        render_mode: str | None = "rgb_array",
        render_size: tuple[int, int] = (224, 224),
        resolution: int | None = None,
        with_target: bool = True,
        relative: bool = True,
        block_cog: Any = None,
        damping: float | None = None,
        init_value: dict | None = None,
        action_scale: float = 100,
    ):
        super().__init__(
            render_mode=render_mode, render_size=render_size, action_scale=action_scale, resolution=resolution
        )
        self.action_scale = action_scale  # kept as given: upstream forms action * 100 in the action's dtype
        self.with_target, self.relative = bool(with_target), bool(relative)
        self.block_cog, self.damping = block_cog, damping
        self.env_name = "PushT"
        # Upstream's layout; its declared bounds ([0, 512] positions, |v| <= 512) are widened to
        # everything reachable: without clips the kinematic agent leaves the table and outruns 512.
        inf, two_pi = np.inf, 2 * np.pi
        self.observation_space = gym.spaces.Dict(
            {
                keys.PROPRIO: gym.spaces.Box(-inf, inf, (4,), np.float64),
                keys.STATE: gym.spaces.Box(
                    np.array([-inf] * 4 + [0.0] + [-inf] * 2),
                    np.array([inf] * 4 + [two_pi] + [inf] * 2),
                    dtype=np.float64,
                ),
            }
        )
        self.variation_space = build_v1_variation_space()
        if init_value is not None:
            self.variation_space.set_init_value(init_value)
        self._outlines: dict[str, tuple] = {}
        self._goal_pose = np.zeros(3)

    # -- gym API ----------------------------------------------------------------------------
    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None):
        gym.Env.reset(self, seed=seed)
        options = dict(options or {})
        if seed is None:  # upstream reseeds from fresh entropy here: draw from the env's generator instead
            seed = int(self.np_random.integers(0, 2**31 - 1))
        check_variation_option(options, self.variation_space.names())
        spaces.reset_variation_space(self.variation_space, seed, options, DEFAULT_VARIATIONS)
        vs = self.variation_space
        v = self._values = vs.value

        self.new_space()
        on_post_solve(self.space, self._count_contacts)
        self._contact_points = 0
        self.agent = make_body(self.space, V1_SHAPES[int(v["agent"]["shape"])], float(v["agent"]["scale"]))
        self.block = make_body(self.space, V1_SHAPES[int(v["block"]["shape"])], float(v["block"]["scale"]))
        if self.block_cog is not None:
            self.block.center_of_gravity = tuple(self.block_cog)
        if self.damping is not None:
            self.space.damping = float(self.damping)
        self._outlines = {"agent": body_outline(self.agent), "block": body_outline(self.block)}
        self._goal_pose = np.array([*v["goal"]["position"], v["goal"]["angle"]], np.float64)

        if options.get(keys.GOAL_STATE) is not None:
            goal = _state_option(options[keys.GOAL_STATE], keys.GOAL_STATE)
        else:
            agent_xy = vs["agent"]["start_position"].sample(set_value=False)
            block_xy = vs["block"]["start_position"].sample(set_value=False)
            angle = vs["block"]["angle"].sample(set_value=False)
            goal = np.array([*agent_xy, *block_xy, angle, *v["agent"]["velocity"]], np.float64)
        self._put(goal)
        self._goal_state = goal
        self._goal_img = self.render()
        if options.get(keys.STATE) is not None:
            start = _state_option(options[keys.STATE], keys.STATE)
        else:
            start = np.array(
                [
                    *v["agent"]["start_position"],
                    *v["block"]["start_position"],
                    v["block"]["angle"],
                    *v["agent"]["velocity"],
                ],
                np.float64,
            )
        self._put(start)
        self._n_contacts = -(-self._contact_points // _SUBSTEPS)
        return self._obs(), self._info()

    def step(self, action):
        a = np.asarray(action)
        if a.shape != (2,) or not np.all(np.isfinite(a)):
            raise ConfigError(f"{type(self).__name__} requires a finite action of shape (2,), got {action!r}")
        move = (
            a * self.action_scale if np.issubdtype(a.dtype, np.floating) else a.astype(np.float64) * self.action_scale
        )
        # Scalars keep the action's dtype, as upstream's Vec2d arithmetic does (float32 actions
        # make the whole PD update float32 under NumPy 2's promotion rules).
        if self.relative:
            px, py = self.agent.position
            tx, ty = px + move[0], py + move[1]
        else:
            tx, ty = move[0], move[1]
        self._contact_points = 0
        self._drive(tx, ty)
        self._n_contacts = -(-self._contact_points // _SUBSTEPS)
        self._state = body_state(self.agent, self.block)
        success, dist = self.eval_state(self._goal_state, self._state)
        return self._obs(), -dist, success, False, self._info()

    def _drive(self, tx, ty) -> None:
        """One control step of physics: the PD controller pulls the agent towards ``(tx, ty)``."""
        agent, step = self.agent, self.space.step
        for _ in range(_SUBSTEPS):
            px, py = agent.position
            vx, vy = agent.velocity
            agent.velocity = (
                vx + (K_P * (tx - px) + K_V * (0.0 - vx)) * _DT,
                vy + (K_P * (ty - py) + K_V * (0.0 - vy)) * _DT,
            )
            step(_DT)

    def eval_state(self, goal_state: np.ndarray, cur_state: np.ndarray):
        """``(success, ||goal - state||)`` over the 7 numbers; works on ``(..., 7)`` arrays too."""
        g, c = np.asarray(goal_state, np.float64), np.asarray(cur_state, np.float64)
        pos = np.linalg.norm(g[..., :4] - c[..., :4], axis=-1)
        angle = np.abs(g[..., 4] - c[..., 4])
        angle = np.minimum(angle, 2 * np.pi - angle)
        success = (pos < 20) & (angle < np.pi / 9)
        dist = np.linalg.norm(g - c, axis=-1)
        if np.ndim(dist) == 0:
            return bool(success), float(dist)
        return success, dist

    def fix_action_sample(self, action: Any) -> np.ndarray:
        """Upstream does not clip actions; samples are only cast to float32."""
        return np.asarray(action, np.float32)

    def _set_state(self, state: Any) -> None:
        """Put the bodies at ``state`` (7 numbers, or 5 with zero agent velocity) and take one physics step."""
        self._put(_state_option(state, keys.STATE))

    # -- internals --------------------------------------------------------------------------
    def _put(self, s: np.ndarray) -> None:
        self.agent.velocity = (float(s[5]), float(s[6]))
        self.agent.position = (float(s[0]), float(s[1]))
        self.block.angle = float(s[4])
        self.block.position = (float(s[2]), float(s[3]))
        self.space.step(_DT)
        self._state = body_state(self.agent, self.block)

    def _reward(self, state: np.ndarray) -> float:
        return -float(np.linalg.norm(np.asarray(self._goal_state, np.float64) - state))

    def _info(self) -> dict[str, Any]:
        if self._goal_img is None:  # render size changed since reset: redraw from the goal state
            g = self._goal_state
            self._goal_img = self._draw(g[0:2], float(self.agent.angle), g[2:4], g[4])
        info = super()._info()
        info[GOAL_POSE] = self._goal_pose.copy()
        info[ENV_NAME] = self.env_name
        return info

    def render(self) -> np.ndarray:
        """The current scene as an ``(H, W, 3)`` uint8 frame at :attr:`render_size`."""
        return self._draw(self.agent.position, float(self.agent.angle), self.block.position, float(self.block.angle))

    def _draw(self, agent_xy, agent_angle: float, block_xy, block_angle: float) -> np.ndarray:
        v = self._values
        show_goal = bool(int(v["rendering"]["render_goal"])) and self.with_target
        colors = {
            "background": v["background"]["color"],
            "goal": v["goal"]["color"] if show_goal else None,
            "block": v["block"]["color"],
            "agent": v["agent"]["color"],
        }
        agent = (*self._outlines["agent"], np.array([*agent_xy, agent_angle], np.float64))
        block = (*self._outlines["block"], np.array([*block_xy, block_angle], np.float64))
        return draw_v1_scene(self.render_size, colors, self._goal_pose, block, agent)


class PushTDiscreteV1(PushTV1):
    """PushT-v1 with upstream's 16x16 polar grid of moves (see the module docstring)."""

    def __init__(self, quantizer: Any = None, **kwargs: Any):
        if quantizer is not None:
            raise ConfigError(
                f"PushTDiscreteV1 has upstream's fixed 16x16 polar grid; got a custom quantizer {quantizer!r}"
            )
        super().__init__(**kwargs)
        self.action_space = gym.spaces.MultiDiscrete([N_RADIAL, N_ANGULAR])

    def fix_action_sample(self, action: Any) -> np.ndarray:
        """Round and clip grid indices (or a ``(..., 2)`` batch) onto :attr:`action_space`."""
        return np.clip(np.rint(np.asarray(action, np.float64)), 0, [N_RADIAL - 1, N_ANGULAR - 1]).astype(np.int64)

    def to_index(self, move: Any) -> np.ndarray:
        """The grid indices ``(..., 2)`` of moves ``(..., 2)`` (upstream's ``quantize``)."""
        return quantize(move)

    def step(self, action):
        a = np.asarray(action).reshape(-1)
        if (
            a.shape != (2,)
            or not np.issubdtype(a.dtype, np.integer)
            or a.min() < 0
            or a[0] >= N_RADIAL
            or a[1] >= N_ANGULAR
        ):
            raise ConfigError(f"PushTDiscreteV1 requires an action of 2 integers in [0, 15], got {action!r}")
        return super().step(dequantize(a))

"""``swm/Craftax*-v1``: Craftax and Craftax-Classic (JAX, extra ``craftax``) as Gymnasium envs with factors.

Written from the behaviour of upstream's ``stable_worldmodel/envs/craftax/craftax.py`` (same ids,
module, class names, observations and actions), on ``craftax``'s own game (its world generation,
rules, rewards and renderers):

- **Ids**: ``swm/CraftaxPixels-v1`` / ``swm/CraftaxSymbolic-v1`` (Craftax, 43 actions) and
  ``swm/CraftaxClassicPixels-v1`` / ``swm/CraftaxClassicSymbolic-v1`` (Craftax-Classic, 17
  actions). Constructor: ``seed=0`` (the first reset's key when it gets no seed), ``backend=None``
  (JAX's), ``render_mode="rgb_array"`` (or None), ``render_size=None`` (the native frame),
  ``fast_compile=False`` (see Compilation).
- **Observation** (upstream's): float32 in ``[0, 1]``; Pixels: craftax's agent view, ``(130, 110,
  3)`` (Classic ``(63, 63, 3)``); Symbolic: craftax's symbolic vector, ``(8268,)`` (Classic
  ``(1345,)``). **Action**: ``Discrete(43)`` (Classic ``Discrete(17)``), craftax's actions.
- **Step**: craftax's step without auto-reset; the reward is craftax's (achievements unlocked and
  health changes). ``terminated`` when craftax's game is over before its time limit (death,
  Classic's lava, Craftax's boss beaten), ``truncated`` when its time limit
  (``max_timesteps``: 100000, Classic 10000 steps) is reached.
- **Keys**: ``reset(seed=s)`` starts from ``jax.random.PRNGKey(s)``; each reset and step splits the
  key as upstream, so a seed gives upstream's worlds and (with the default factors) upstream's
  episodes. A reset without a seed goes on from the current key.
- **Factors** (``variation_space``; upstream has none): craftax's ``EnvParams``, which change the
  game without recompiling it. Classic (10): ``world.day_length``, ``world.always_diamond``,
  ``mobs.zombie_health``, ``mobs.cow_health``, ``mobs.skeleton_health``,
  ``mobs.despawn_distance``, ``spawn.cow_chance``, ``spawn.zombie_base_chance``,
  ``spawn.zombie_night_chance``, ``spawn.skeleton_chance``. Craftax (5): ``world.day_length``,
  ``world.always_diamond``, ``mobs.despawn_distance``, ``player.max_attribute``,
  ``player.god_mode``. Defaults are craftax's; every factor keeps its default unless
  ``options["variation"]`` / ``["variation_values"]`` names it.
- **State**: ``info["state"]`` is the whole craftax ``EnvState`` flattened to float32 (exact: maps,
  mobs, timers; its ``uint32`` random key as two 16-bit halves), the player's fields first:
  position (row, column), then (Craftax) the level, then the other player fields; ``proprio`` is
  that player block (position, level, direction, vitals, inventory...: 20 numbers, Craftax 45).
  ``options["state"]`` restores such a state.
- **Goal**: Craftax has no goal of its own. ``goal_state`` is the start state (or
  ``options["goal_state"]``, e.g. a dataset row's state), ``goal`` its frame, ``goal_proprio`` its
  player block; ``eval_state(goal_state, state)`` is ``(success, distance)``: success when the player
  stands where the goal state's player stands (same level and cell), distance the cells between them
  (plus 48 per level).
- **Info**: upstream's ``env_name`` and craftax's per-step info (``Achievements/<name>``,
  ``discount``; after a reset zeros), plus ``state``, ``proprio``, ``goal``, ``goal_state``,
  ``goal_proprio``.
- **Rendering**: craftax's pixel renderer (the Pixels observation, for the Symbolic ids too) as
  uint8, resized with OpenCV's area filter to ``render_size`` (``set_render_size``).
- **Compilation**: reset, step (both observations) and the observation of a restored state are
  jitted once per process and game (``jax.jit(...).lower(...).compile()``), shared by every env of
  that game; the first reset of a game in a process compiles for a while (CPU time here: Classic
  ~20 s, Craftax ~70 s; ``fast_compile=True`` takes ~40 % less with XLA's cheapest optimisation,
  and makes each step 3 to 4 times slower). JAX's persistent cache
  (``JAX_COMPILATION_CACHE_DIR``) keeps compilations across processes. A step costs about 1.5 ms
  (Craftax ~7 ms) of CPU, mostly craftax's pixel renderer, which the Symbolic ids skip when made
  with ``render_mode=None`` (``render()`` then raises).

Deliberate differences from upstream: factors of variation (upstream: ``variation_space = None``);
the state, goal and proprio infos and ``eval_state``; ``terminated`` / ``truncated`` split
(upstream: ``terminated`` for any game over); frames for the Symbolic ids and at any size
(upstream: Pixels ids only, at the native size, and only with ``render_mode="rgb_array"``); typed
errors.
"""

from __future__ import annotations

import contextlib
import dataclasses
import io
import threading
from typing import Any

import gymnasium as gym
import numpy as np

from ... import keys, spaces
from ..._optional import require
from ...errors import ConfigError, unknown_name
from ..base import DatasetResetMixin, apply_variation_options, check_render_size

__all__ = [
    "CraftaxClassicPixelsWrapper",
    "CraftaxClassicSymbolicWrapper",
    "CraftaxPixelsWrapper",
    "CraftaxSymbolicWrapper",
    "CraftaxWrapper",
]

_WHY = "the Craftax envs (swm/Craftax*-v1)"
jax = require("jax", extra="craftax", purpose=_WHY)
_craftax_env = require("craftax.craftax_env", extra="craftax", purpose=_WHY)


def _make(name: str) -> Any:
    """craftax's env ``name`` without auto-reset (quietly: craftax prints as it loads its textures)."""
    with contextlib.redirect_stdout(io.StringIO()):
        return _craftax_env.make_craftax_env_from_name(name, auto_reset=False)


#: XLA options of ``fast_compile=True``: compiling takes ~40 % less CPU time, a step 3 to 4 times more
COMPILER_OPTIONS = {"xla_backend_optimization_level": 0, "xla_llvm_disable_expensive_passes": True}
LEVEL_SPAN = 48  # eval_state: cells counted per level of difference

# the game's EnvParams fields behind each factor, with their ranges (defaults are craftax's)
_INT, _BOOL, _FLOAT = "int", "bool", "float"
_FACTORS = {
    "classic": {
        "world.day_length": ("day_length", _INT, 100, 600),
        "world.always_diamond": ("always_diamond", _BOOL, 0, 1),
        "mobs.zombie_health": ("zombie_health", _INT, 1, 10),
        "mobs.cow_health": ("cow_health", _INT, 1, 6),
        "mobs.skeleton_health": ("skeleton_health", _INT, 1, 6),
        "mobs.despawn_distance": ("mob_despawn_distance", _INT, 8, 20),
        "spawn.cow_chance": ("spawn_cow_chance", _FLOAT, 0.0, 0.3),
        "spawn.zombie_base_chance": ("spawn_zombie_base_chance", _FLOAT, 0.0, 0.1),
        "spawn.zombie_night_chance": ("spawn_zombie_night_chance", _FLOAT, 0.0, 0.3),
        "spawn.skeleton_chance": ("spawn_skeleton_chance", _FLOAT, 0.0, 0.15),
    },
    "full": {
        "world.day_length": ("day_length", _INT, 100, 600),
        "world.always_diamond": ("always_diamond", _BOOL, 0, 1),
        "mobs.despawn_distance": ("mob_despawn_distance", _INT, 8, 20),
        "player.max_attribute": ("max_attribute", _INT, 1, 10),
        "player.god_mode": ("god_mode", _BOOL, 0, 1),
    },
}
# the player's fields, first in the flat state (position first, then the level where there is one)
_PLAYER = {
    "classic": (
        "player_position",
        "player_direction",
        "player_health",
        "player_food",
        "player_drink",
        "player_energy",
        "is_sleeping",
        "inventory",
    ),
    "full": (
        "player_position",
        "player_level",
        "player_direction",
        "player_health",
        "player_food",
        "player_drink",
        "player_energy",
        "player_mana",
        "is_sleeping",
        "is_resting",
        "player_xp",
        "player_dexterity",
        "player_strength",
        "player_intelligence",
        "inventory",
    ),
}


class _Game:
    """One craftax game (Classic or Craftax) compiled once per process: reset, step and the
    observations of a state, each returning the state and both observations."""

    def __init__(self, game: str, backend: str | None, fast_compile: bool):
        classic = game == "classic"
        self.game, self.fast_compile = game, fast_compile
        sym_name = "Craftax-Classic-Symbolic-v1" if classic else "Craftax-Symbolic-v1"
        pix_name = "Craftax-Classic-Pixels-v1" if classic else "Craftax-Pixels-v1"
        self.symbolic, self.pixels = _make(sym_name), _make(pix_name)
        self.num_actions = int(self.symbolic.num_actions)
        self.default_params = self.symbolic.default_params
        self.backend = backend
        self._lock = threading.Lock()
        self._compiled: dict[str, Any] = {}
        self.spec: list[tuple[str, Any, list[tuple[tuple[int, ...], np.dtype]]]] | None = None
        self.player_size = self.size = 0
        self.info_layout: list[tuple[str, tuple[int, ...]]] = []

    # -- the jitted functions ----------------------------------------------------------------------
    def _fns(self) -> dict[str, Any]:
        sym, pix = self.symbolic, self.pixels
        jnp = jax.numpy
        flatten = self._flatten_traced

        def reset(key, params):
            key, sub = jax.random.split(key)
            obs, state = sym.reset_env(sub, params)
            return key, state, flatten(state), obs, pix.get_obs(state).astype(jnp.float32)

        def step(key, state, action, params, pixels=True):
            key, sub = jax.random.split(key)
            obs, state, reward, done, info = sym.step_env(sub, state, action, params)
            names = sorted(info)
            self.info_layout = [(k, tuple(jnp.shape(info[k]))) for k in names]  # noted while tracing
            values = jnp.concatenate([jnp.asarray(info[k], jnp.float32).reshape(-1) for k in names])
            timeout = state.timestep >= params.max_timesteps
            frame = pix.get_obs(state).astype(jnp.float32) if pixels else jnp.zeros((0,), jnp.float32)
            return key, state, flatten(state), reward, done, timeout, values, obs, frame

        def observe(state):
            return flatten(state), sym.get_obs(state), pix.get_obs(state).astype(jnp.float32)

        def step_symbolic(key, state, action, params):  # no frame: Symbolic ids with render_mode None
            return step(key, state, action, params, pixels=False)

        return {"reset": reset, "step": step, "step_symbolic": step_symbolic, "observe": observe}

    def _flatten_traced(self, state) -> Any:
        """``state`` as one float32 vector, in :meth:`_order` (uint32 leaves as two 16-bit halves)."""
        jnp = jax.numpy
        parts = []
        for name in self._order(state):
            for leaf in jax.tree_util.tree_leaves(getattr(state, name)):
                leaf = jnp.asarray(leaf)
                if leaf.dtype == jnp.uint32:
                    leaf = jnp.stack([leaf >> 16, leaf & 0xFFFF], -1)
                parts.append(leaf.astype(jnp.float32).reshape(-1))
        return jnp.concatenate(parts)

    def compiled(self, name: str, *args: Any) -> Any:
        """The compiled ``name`` for these argument types (compiled on first use, once per process)."""
        with self._lock:
            if name not in self._compiled:
                fn = self._fns()[name]
                jitted = jax.jit(fn, backend=self.backend) if self.backend else jax.jit(fn)
                lowered = jitted.lower(*args)
                self._compiled[name] = lowered.compile(COMPILER_OPTIONS if self.fast_compile else None)
            return self._compiled[name]

    def params(self, values: dict[str, Any]) -> Any:
        """craftax's ``EnvParams`` with ``values`` (field -> value), every leaf a typed numpy scalar, so
        that one compilation serves every factor value."""
        out = {}
        for f in dataclasses.fields(self.default_params):
            v = values.get(f.name, getattr(self.default_params, f.name))
            if f.name == "fractal_noise_angles":
                out[f.name] = v
            elif isinstance(getattr(self.default_params, f.name), bool):
                out[f.name] = np.bool_(bool(v))
            elif isinstance(getattr(self.default_params, f.name), int):
                out[f.name] = np.int32(int(v))
            else:
                out[f.name] = np.float32(float(v))
        return self.default_params.replace(**out)

    # -- flat states ------------------------------------------------------------------------------
    def _order(self, state) -> list[str]:
        names = [f.name for f in dataclasses.fields(state)]
        player = list(_PLAYER[self.game])
        return player + [n for n in names if n not in player]

    def learn_spec(self, state) -> None:
        """The flat layout of ``state`` (field, tree structure, leaf shapes and dtypes), once."""
        if self.spec is not None:
            return
        spec = []
        for name in self._order(state):
            leaves, tree = jax.tree_util.tree_flatten(getattr(state, name))
            spec.append((name, tree, [(tuple(np.shape(leaf)), np.dtype(leaf.dtype)) for leaf in leaves]))
        self.spec = spec
        self.player_size = sum(
            _flat_size(shape, dtype)
            for name, _, leaves in spec
            if name in _PLAYER[self.game]
            for shape, dtype in leaves
        )
        self.size = sum(_flat_size(shape, dtype) for _, _, leaves in spec for shape, dtype in leaves)

    def unflatten(self, flat: np.ndarray, template) -> Any:
        """The ``EnvState`` of a vector from :meth:`flatten` (``template`` gives the structure)."""
        flat = np.asarray(flat, np.float64).reshape(-1)
        if flat.shape[0] != self.size:
            raise ConfigError(f"Craftax requires a state of {self.size} numbers (info['state']), got {flat.shape[0]}")
        fields, i = {}, 0
        for name, tree, leaves in self.spec:
            values = []
            for shape, dtype in leaves:
                n = _flat_size(shape, dtype)
                chunk = flat[i : i + n]
                i += n
                if dtype == np.uint32:
                    halves = np.rint(chunk).astype(np.uint64).reshape(*shape, 2)
                    values.append(((halves[..., 0] << 16) | halves[..., 1]).astype(np.uint32))
                elif dtype == np.bool_:
                    values.append((chunk.reshape(shape) > 0.5).astype(np.bool_))
                elif np.issubdtype(dtype, np.integer):
                    values.append(np.rint(chunk).astype(dtype).reshape(shape))
                else:
                    values.append(chunk.astype(dtype).reshape(shape))
            fields[name] = jax.tree_util.tree_unflatten(tree, values)
        return template.replace(**fields)


def _flat_size(shape: tuple[int, ...], dtype: np.dtype) -> int:
    return int(np.prod(shape, dtype=np.int64)) * (2 if dtype == np.uint32 else 1)


_GAMES: dict[tuple[str, str | None, bool], _Game] = {}
_GAMES_LOCK = threading.Lock()


def _game(game: str, backend: str | None, fast_compile: bool) -> _Game:
    with _GAMES_LOCK:
        key = (game, backend, fast_compile)
        if key not in _GAMES:
            _GAMES[key] = _Game(game, backend, fast_compile)
        return _GAMES[key]


def _factor_space(game: str) -> spaces.Dict:
    defaults = _make("Craftax-Classic-Symbolic-v1" if game == "classic" else "Craftax-Symbolic-v1").default_params
    groups: dict[str, dict[str, Any]] = {}
    for name, (field, kind, low, high) in _FACTORS[game].items():
        group, leaf = name.split(".")
        init = getattr(defaults, field)
        if kind == _FLOAT:
            space = spaces.Box(low, high, shape=(), dtype=np.float32, init_value=np.float32(init))
        else:
            space = spaces.Discrete(high - low + 1, start=low, init_value=int(init))
        groups.setdefault(group, {})[leaf] = space
    return spaces.Dict(
        {g: spaces.Dict(v, sampling_order=list(v)) for g, v in groups.items()}, sampling_order=list(groups)
    )


class CraftaxWrapper(DatasetResetMixin, gym.Env):
    """A craftax game as a Gymnasium env (see the module docstring); the subclasses pick the id."""

    metadata = {"render_modes": ["rgb_array"], "render_fps": 10}
    ENV_NAMES = {
        "Craftax-Pixels-v1": ("full", True),
        "Craftax-Symbolic-v1": ("full", False),
        "Craftax-Classic-Pixels-v1": ("classic", True),
        "Craftax-Classic-Symbolic-v1": ("classic", False),
    }
    OBS_SHAPES = {
        ("full", True): (130, 110, 3),
        ("full", False): (8268,),
        ("classic", True): (63, 63, 3),
        ("classic", False): (1345,),
    }

    def __init__(
        self,
        env_name: str,
        obs_shape: tuple[int, ...] | None = None,
        seed: int = 0,
        backend: str | None = None,
        render_mode: str | None = "rgb_array",
        render_size: tuple[int, int] | None = None,
        fast_compile: bool = False,
    ):
        owner = type(self).__name__
        if env_name not in self.ENV_NAMES:
            raise unknown_name("Craftax env_name", str(env_name), list(self.ENV_NAMES))
        if render_mode not in (None, "rgb_array"):
            raise ConfigError(f"{owner} requires render_mode 'rgb_array' or None, got {render_mode!r}")
        if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
            raise ConfigError(f"{owner} requires seed to be an int >= 0, got {seed!r}")
        game, is_pixels = self.ENV_NAMES[env_name]
        native = self.OBS_SHAPES[(game, is_pixels)]
        if obs_shape is not None and tuple(obs_shape) != native:
            raise ConfigError(f"{owner} requires obs_shape {native} for {env_name}, got {tuple(obs_shape)}")
        self.craftax_name, self.game_name, self._is_pixels = env_name, game, is_pixels
        self.render_mode, self.backend = render_mode, backend
        self.env_name = owner.replace("Wrapper", "") if owner != "CraftaxWrapper" else env_name
        self._game = _game(game, backend, bool(fast_compile))
        # the Symbolic ids without rendering skip craftax's pixel renderer (most of a step's time)
        self._step_name = "step_symbolic" if render_mode is None and not is_pixels else "step"
        self.observation_space = gym.spaces.Box(0.0, 1.0, shape=native, dtype=np.float32)
        self.action_space = gym.spaces.Discrete(self._game.num_actions)
        self.variation_space = _factor_space(game)
        frame = self.OBS_SHAPES[(game, True)][:2]
        self.render_size = frame if render_size is None else check_render_size(owner, render_size)
        self._key = jax.random.PRNGKey(int(seed))
        self._state: Any = None
        self._params: Any = None
        self._obs: np.ndarray | None = None
        self._frame: np.ndarray | None = None
        self._flat: np.ndarray | None = None
        self._step_info: dict[str, np.ndarray] = {}
        self._goal_state: np.ndarray | None = None
        self._goal_frame: np.ndarray | None = None

    @property
    def craftax_env(self) -> Any:
        """The underlying craftax env (upstream's accessor; the symbolic one of this game)."""
        return self._game.symbolic

    # -- gym API ----------------------------------------------------------------------------------
    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None):
        super().reset(seed=seed)
        options = dict(options or {})
        apply_variation_options(self.variation_space, options, self.np_random)
        game = self._game
        self._params = game.params(
            {field: self.variation_space[name].value for name, (field, _, _, _) in _FACTORS[self.game_name].items()}
        )
        if seed is not None:
            self._key = jax.random.PRNGKey(int(seed))
        reset = game.compiled("reset", self._key, self._params)
        self._key, self._state, flat, sym, pix = reset(self._key, self._params)
        game.learn_spec(self._state)
        if options.get(keys.STATE) is not None:
            self._state = game.unflatten(options[keys.STATE], self._state)
            flat, sym, pix = game.compiled("observe", self._state)(self._state)
        self._set_obs(flat, sym, pix)
        game.compiled(self._step_name, self._key, self._state, np.int32(0), self._params)  # compiled here, once
        self._step_info = {k: np.zeros(shape, np.float32) for k, shape in game.info_layout}
        if options.get(keys.GOAL_STATE) is not None:
            goal = game.unflatten(options[keys.GOAL_STATE], self._state)
            goal_flat, _, goal_pix = game.compiled("observe", goal)(goal)
            self._goal_state = np.asarray(goal_flat, np.float32)
            self._goal_pixels = np.asarray(goal_pix)
        else:
            self._goal_state = self._flat.copy()
            self._goal_pixels = np.asarray(pix)
        self._goal_frame = None
        return self._obs.copy(), self._info()

    def step(self, action):
        if self._state is None:
            raise ConfigError(f"{type(self).__name__}.step requires reset() first")
        game = self._game
        action = np.int32(int(np.asarray(action).reshape(())))
        step = game.compiled(self._step_name, self._key, self._state, action, self._params)
        self._key, self._state, flat, reward, done, timeout, info, sym, pix = step(
            self._key, self._state, action, self._params
        )
        self._set_obs(flat, sym, pix)
        values, i = np.asarray(info), 0
        for k, shape in game.info_layout:
            n = int(np.prod(shape, dtype=np.int64))
            self._step_info[k] = values[i : i + n].reshape(shape)
            i += n
        done, timeout = bool(done), bool(timeout)
        return self._obs.copy(), float(reward), done and not timeout, done and timeout, self._info()

    def render(self) -> np.ndarray:
        """craftax's pixel view of the current state, ``(*render_size, 3)`` uint8."""
        if self._frame is None:
            raise ConfigError(
                f"{type(self).__name__}.render requires reset() first"
                + (
                    " and render_mode 'rgb_array' (this env was made with render_mode None)"
                    if self._state is not None
                    else ""
                )
            )
        return self._sized(self._frame)

    def set_render_size(self, size: tuple[int, int]) -> None:
        """Draw frames and the goal image at ``size`` = (H, W) from now on."""
        self.render_size = check_render_size(type(self).__name__, size)
        self._goal_frame = None

    def eval_state(self, goal_state: np.ndarray, cur_state: np.ndarray) -> tuple[bool, float]:
        """``(success, distance)``: the player where ``goal_state``'s player is (level and cell);
        distance in cells, plus 48 per level between them."""
        g = np.asarray(goal_state, np.float64).reshape(-1)
        c = np.asarray(cur_state, np.float64).reshape(-1)
        n = 3 if self.game_name == "full" else 2
        if g.shape[0] < n or c.shape[0] < n:
            raise ConfigError(
                f"{type(self).__name__}.eval_state requires states of at least {n} numbers (info['state']), "
                f"got {g.shape[0]} and {c.shape[0]}"
            )
        cells = float(np.abs(g[:2] - c[:2]).sum())
        levels = float(abs(g[2] - c[2])) if n == 3 else 0.0
        return bool(cells == 0 and levels == 0), cells + LEVEL_SPAN * levels

    # -- internals --------------------------------------------------------------------------------
    def _set_obs(self, flat, sym, pix) -> None:
        pix = np.asarray(pix, np.float32)
        self._obs = pix if self._is_pixels else np.asarray(sym, np.float32)
        # upstream's conversion; a step without a frame (render_mode None) keeps none
        self._frame = (np.clip(pix, 0.0, 1.0) * 255.0).astype(np.uint8) if pix.size else None
        self._flat = np.asarray(flat, np.float32)

    def _sized(self, frame: np.ndarray) -> np.ndarray:
        h, w = self.render_size
        if frame.shape[:2] == (h, w):
            return frame.copy()
        import cv2

        return cv2.resize(frame, (w, h), interpolation=cv2.INTER_AREA)

    def _info(self) -> dict[str, Any]:
        if self._goal_frame is None:
            self._goal_frame = self._sized((np.clip(self._goal_pixels, 0.0, 1.0) * 255.0).astype(np.uint8))
        player = self._game.player_size
        return {
            "env_name": self.env_name,
            **{k: v.copy() for k, v in self._step_info.items()},
            keys.STATE: self._flat.copy(),
            keys.PROPRIO: self._flat[:player].copy(),
            keys.GOAL: self._goal_frame.copy(),
            keys.GOAL_STATE: self._goal_state.copy(),
            keys.GOAL_PROPRIO: self._goal_state[:player].copy(),
        }


class CraftaxPixelsWrapper(CraftaxWrapper):
    """``swm/CraftaxPixels-v1``: Craftax, pixel observations ``(130, 110, 3)``."""

    def __init__(self, **kwargs: Any):
        super().__init__(env_name="Craftax-Pixels-v1", **kwargs)


class CraftaxSymbolicWrapper(CraftaxWrapper):
    """``swm/CraftaxSymbolic-v1``: Craftax, symbolic observations ``(8268,)``."""

    def __init__(self, **kwargs: Any):
        super().__init__(env_name="Craftax-Symbolic-v1", **kwargs)


class CraftaxClassicPixelsWrapper(CraftaxWrapper):
    """``swm/CraftaxClassicPixels-v1``: Craftax-Classic, pixel observations ``(63, 63, 3)``."""

    def __init__(self, **kwargs: Any):
        super().__init__(env_name="Craftax-Classic-Pixels-v1", **kwargs)


class CraftaxClassicSymbolicWrapper(CraftaxWrapper):
    """``swm/CraftaxClassicSymbolic-v1``: Craftax-Classic, symbolic observations ``(1345,)``."""

    def __init__(self, **kwargs: Any):
        super().__init__(env_name="Craftax-Classic-Symbolic-v1", **kwargs)

"""``swm/<Name>DMControl-v0``: upstream 0.1.1's DeepMind Control envs, with factors of variation.

Written from the observed behaviour of stable-worldmodel 0.1.1, so datasets recorded and models
trained on upstream's envs work here unchanged. Each domain module (``cartpole.py`` ...) names
its dm_control task, factors, goal and extra info; this module does the rest:

- **Task**: the dm_control suite task upstream uses (``cartpole`` ``swingup_sparse``, ``reacher``
  ``hard`` ...), driven directly: ``before_step``, ``physics.step(n_sub_steps)``, ``after_step``,
  ``get_reward``, with dm_control's control timestep of the task.
- **Step**: the action (``Box(-1, 1)``, float64) is clipped, mapped linearly onto the actuators'
  control ranges (as dm_control's ``action_scale`` wrapper does) and applied
  ``action_repeat = 2`` times; the reward is the sum of the two dm_control rewards. Never
  terminated (unless the task terminates) nor truncated (``environment_kwargs["time_limit"]``
  sets a truncation time).
- **Observation**: dm_control's observation dict flattened in its order, float32.
- **Reset**: the variation space is reset to its defaults, then ``options["variation"]`` /
  ``["variation_values"]`` resample / set factors (seeded from the env's generator); the task's
  ``RandomState`` is ``RandomState(seed)`` on a seeded reset (so ``reset(seed=s)`` starts where
  ``suite.load(..., task_kwargs={"random": s})`` starts) and continues otherwise.
  ``options["state"]`` (``[qpos, qvel, act]``) starts from that state; ``options["goal_state"]``
  sets the goal (tasks with a target move it there: Reacher, Finger, Manipulator).
- **Factors**: colors, light, gravity, friction, target visibility and site shapes are written
  into the compiled model; densities, masses, sizes, geom shapes and the floor tilt recompile it
  (textures left out: ~1 ms), only when one of them changed; the floor color rewrites the grid
  texture (the renderers are then made again). See ``_factors.py`` and ``_model.py``.
- **Info**: upstream's ``env_name``, ``success``, ``qpos``, ``qvel``, ``score`` (return / 1000)
  and the domain's extras (``speed``, ``target_pos`` ...); plus ``state`` (``[qpos, qvel, act]``),
  ``proprio`` (the agent's joints), ``goal`` (the goal state rendered like the frames),
  ``goal_state`` and ``goal_proprio``. ``success`` is :meth:`eval_state` of the state against the
  goal (1.0 or 0.0).
- **Rendering**: ``224 x 224`` from the domain's camera (0; Quadruped 2) through
  :class:`~stable_worldmodel.envs.mujoco_render.MjRenderer` on the physics' own model and data
  (at ``render_quality="high"`` the frames equal ``physics.render``'s). ``set_render_size``
  draws at that size directly. Renderers are made on the first render, never at import or in
  ``__init__``.

Deliberate differences from upstream 0.1.1:

- Upstream never ends an episode and silently restarts the dm_control episode once its time
  limit is reached (after 500 steps for most ids), so longer rollouts jump to a new episode;
  here the physics just goes on. ``environment_kwargs={"time_limit": seconds}`` truncates.
- ``success`` is 1.0 / 0.0 from :meth:`eval_state` in every domain (upstream: NaN, which
  Gymnasium's determinism check cannot compare, except BallInCup's ball-in-cup flag, which our
  BallInCup goal reproduces); the reward is always a float (upstream: the int 0 when none).
- The factor values drawn for a seed differ from upstream's draws (the sampling itself is ours);
  set them with ``options["variation_values"]`` to replay upstream episodes.
- The constructor's ``seed`` seeds the first reset (upstream ignores it for resets);
  ``environment_kwargs`` takes ``control_timestep``, ``n_sub_steps``, ``time_limit`` and
  ``flat_observation`` and applies them (upstream stores them unused, or fails).
- dm_control's own tasks of each domain, plus two of upstream's custom goals: Cheetah
  ``run-backward`` and Hopper ``hop-backward`` (same rewards as upstream). Upstream's other
  custom Cheetah, Hopper and Walker goals and its Reacher ``qpos_match`` task (with
  ``set_target_qpos``) are not offered; every id's default task is the same. Cartpole and
  Acrobot also take a keyword-only ``task``.
- Frames are drawn at the requested size (upstream draws 224 x 224 and the World resizes);
  ``render_quality="medium"`` (the default) uses a smaller shadow map, ``"high"`` draws
  upstream's frames exactly.
- Several upstream factors change nothing; the issue's kinds (densities, shapes, colors) are made
  to work with the default reproducing upstream's model, the rest (``*_locked``,
  Manipulator's ``upper_arm_length``) stay no-ops. Each domain module lists its factors;
  Walker's floor tilt turns about the origin (upstream's turns about x = 248 m).
- Upstream's internal hooks (``compile_model``, ``modify_mjcf_model``,
  ``apply_runtime_variations``, ``mark_dirty``) are not offered; ``set_state(qpos, qvel)`` and
  ``set_gravity`` are. ``eval_state`` takes ``(goal_state, cur_state)`` (BallInCup's also
  takes none, as upstream).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import Any

from ..mujoco_render import MjRenderer, check_render_quality, setup_gl

setup_gl()  # before mujoco / dm_control pick their GL backend

import gymnasium as gym  # noqa: E402
import mujoco  # noqa: E402
import numpy as np  # noqa: E402

from ... import keys  # noqa: E402
from ...errors import ConfigError, SpaceError, did_you_mean, unknown_name  # noqa: E402
from ..base import DatasetResetMixin, apply_variation_options, check_render_size  # noqa: E402
from . import _factors, _model  # noqa: E402

IMG_SIZE = 224
ENV_KWARGS = ("control_timestep", "n_sub_steps", "time_limit", "flat_observation")
_JOINT_WIDTH = {0: (7, 6), 1: (4, 3), 2: (1, 1), 3: (1, 1)}  # mjtJoint free, ball, slide, hinge: (nq, nv)


class DMControlWrapper(DatasetResetMixin, gym.Env):
    """Base of the DeepMind Control envs (see the module docstring); subclasses fill the class attributes."""

    metadata = {"render_modes": ["rgb_array"], "render_fps": 25}
    ENV_NAME = ""
    TASKS: Mapping[str, Callable[[np.random.RandomState], Any]] = {}  # name -> dm_control Task factory
    DEFAULT_TASK = ""
    PHYSICS: type | None = None  # the domain's dm_control Physics class
    CONTROL_TIMESTEP: float | None = None  # None: the model's timestep
    CAMERA_ID = 0
    ACTION_REPEAT = 2
    AGENT_JOINTS: tuple[str, ...] | None = None  # proprio joints (None: all)
    GOAL_TOLERANCE = 0.1  # eval_state: success when the goal features are this close

    def __init__(
        self,
        task: str | None = None,
        seed: int | None = None,
        environment_kwargs: dict | None = None,
        render_mode: str | None = None,
        render_quality: str = "medium",
    ):
        owner = type(self).__name__
        task = self.DEFAULT_TASK if task is None else task
        if task not in self.TASKS:
            raise unknown_name(f"{owner} task", str(task), self.TASKS)
        if render_mode not in (None, "rgb_array"):
            raise ConfigError(f"{owner} requires render_mode 'rgb_array' or None, got {render_mode!r}")
        if seed is not None and (isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0):
            raise ConfigError(f"{owner} requires seed to be None or an int >= 0, got {seed!r}")
        self.render_quality = check_render_quality(owner, render_quality)
        env_kwargs = _check_env_kwargs(owner, environment_kwargs)
        self.task_name, self.render_mode, self.env_name, self._seed = task, render_mode, self.ENV_NAME, seed
        self.action_repeat, self.camera_id = self.ACTION_REPEAT, self.CAMERA_ID
        self._factor_list = self.factors(task)
        self.variation_space = _factors.build_space(self._factor_list)
        self._build_physics(task)
        self._set_timing(env_kwargs)
        self._task = self.TASKS[task](np.random.RandomState(seed))
        with self._physics.reset_context():
            self._task.initialize_episode(self._physics)
        n_obs = self._observation().shape[0]
        self.observation_space = gym.spaces.Box(-np.inf, np.inf, (n_obs,), np.float32)
        self.action_space = gym.spaces.Box(-1.0, 1.0, (self.model.nu,), np.float64)
        low, high = self.model.actuator_ctrlrange.T.copy()
        self._ctrl_low, self._ctrl_scale = low, (high - low) / 2.0
        self._qidx, self._vidx = self._joint_indices(self.AGENT_JOINTS)
        self.render_size = (IMG_SIZE, IMG_SIZE)
        self._renderers: dict[tuple[int, int], MjRenderer] = {}
        self._goal = np.zeros(self.model.nq + self.model.nv + self.model.na)
        self._goal_image: np.ndarray | None = None
        self._return, self._dm_steps, self._reset_once = 0.0, 0, False

    # -- hooks of the domain modules --------------------------------------------------------------
    @classmethod
    def factors(cls, task: str) -> tuple[_factors.Factor, ...]:
        """The factors of variation (in upstream's order) of ``task``."""
        raise NotImplementedError("factors(task) -> tuple of Factor")

    def model_source(self, task: str) -> tuple[str, Mapping[str, bytes]]:
        """(XML, assets) of ``task``'s model (default: the domain module's ``get_model_and_assets``)."""
        xml, assets = self._suite_module().get_model_and_assets()
        return xml.decode() if isinstance(xml, bytes) else xml, assets

    def goal_qpos(self) -> np.ndarray:
        """The default goal configuration of the current episode (default: the model's ``qpos0``)."""
        return self.model.qpos0.copy()

    def place_goal(self, qpos: np.ndarray) -> None:
        """Move the task's target to where the goal configuration ``qpos`` puts it (default: nothing)."""

    def goal_features(self, qpos: np.ndarray) -> np.ndarray:
        """What :meth:`eval_state` compares (default: ``qpos``)."""
        return np.asarray(qpos, float)

    def extra_info(self) -> dict[str, Any]:
        """The domain's extra info keys (upstream's)."""
        return {}

    # -- construction -----------------------------------------------------------------------------
    def _suite_module(self):
        import importlib

        return importlib.import_module(self.PHYSICS.__module__)

    def _build_physics(self, task: str) -> None:
        from dm_control.mujoco import wrapper

        xml, assets = self.model_source(task)
        defaults = [(f.effect, self._default(f.name)) for f in self._factor_list if f.effect.structural]
        live = _model.cached_model((type(self), task), lambda: _model.build_default(xml, assets, defaults))
        self._editor = _model.ModelEditor(xml, assets)
        self._physics = self.PHYSICS.from_model(wrapper.MjModel(live))
        self.model = live
        self._scratch = mujoco.MjData(live)
        self._compiled = {f.name: self._default(f.name) for f in self._factor_list}
        self._defaults = {k: np.array(getattr(live, k)) for k in ("site_size", "site_group", "geom_rgba")}

    def _default(self, name: str) -> np.ndarray:
        return np.asarray(self.variation_space[name].init_value)

    def _set_timing(self, env_kwargs: dict[str, Any]) -> None:
        dt = float(self.model.opt.timestep)
        control = env_kwargs.get("control_timestep", self.CONTROL_TIMESTEP) or dt
        n_sub = env_kwargs.get("n_sub_steps")
        self._n_sub_steps = int(n_sub) if n_sub is not None else max(1, int(round(float(control) / dt)))
        limit = env_kwargs.get("time_limit")
        step_time = self._n_sub_steps * dt
        self._step_limit = None if limit is None else max(1, int(round(float(limit) / step_time)))
        self.metadata = {**self.metadata, "render_fps": int(round(1.0 / (step_time * self.ACTION_REPEAT)))}

    def _joint_indices(self, joints: tuple[str, ...] | None) -> tuple[np.ndarray, np.ndarray]:
        m = self.model
        if joints is None:
            return np.arange(m.nq), np.arange(m.nv)
        q, v = [], []
        for name in joints:
            j = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, name)
            nq, nv = _JOINT_WIDTH[int(m.jnt_type[j])]
            q.extend(range(m.jnt_qposadr[j], m.jnt_qposadr[j] + nq))
            v.extend(range(m.jnt_dofadr[j], m.jnt_dofadr[j] + nv))
        return np.array(q, int), np.array(v, int)

    # -- gym API ----------------------------------------------------------------------------------
    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None):
        if seed is None and not self._reset_once:
            seed = self._seed
        self._reset_once = True
        super().reset(seed=seed)
        options = dict(options or {})
        apply_variation_options(self.variation_space, options, self.np_random)
        values = {f.name: np.asarray(self.variation_space[f.name].value) for f in self._factor_list}
        self._recompile(values)
        self._apply_runtime(values, after_task=False)
        if seed is not None:
            self._task = self.TASKS[self.task_name](np.random.RandomState(seed))
        with self._physics.reset_context():
            self._task.initialize_episode(self._physics)
        self._apply_runtime(values, after_task=True)
        self._physics.forward()
        if options.get(keys.STATE) is not None:
            self._set_full_state(self._check_state(options[keys.STATE], keys.STATE))
        if options.get(keys.GOAL_STATE) is not None:
            self._goal = self._check_state(options[keys.GOAL_STATE], keys.GOAL_STATE, fill=False)
            self.place_goal(self._goal[: self.model.nq])
            self._physics.forward()
        else:
            self._goal = np.concatenate([self.goal_qpos(), np.zeros(self.model.nv + self.model.na)])
        self._goal_image = None
        self._return, self._dm_steps = 0.0, 0
        return self._observation(), self._info()

    def step(self, action):
        a = np.asarray(action, dtype=np.float64)
        if a.size != self.action_space.shape[0] or not np.all(np.isfinite(a)):
            raise SpaceError(
                f"{type(self).__name__}.step requires {self.action_space.shape[0]} finite action values, got {action!r}"
            )
        ctrl = self._ctrl_low + self._ctrl_scale * (np.clip(a.reshape(-1), -1.0, 1.0) + 1.0)
        reward, terminated, physics = 0.0, False, self._physics
        for _ in range(self.ACTION_REPEAT):
            self._task.before_step(ctrl, physics)
            physics.step(self._n_sub_steps)
            self._task.after_step(physics)
            reward += float(self._task.get_reward(physics))
            self._dm_steps += 1
            if self._task.get_termination(physics) is not None:
                terminated = True
                break
        self._return += reward
        truncated = self._step_limit is not None and self._dm_steps >= self._step_limit and not terminated
        return self._observation(), reward, terminated, truncated, self._info()

    def render(self, width: int | None = None, height: int | None = None, camera_id: int | None = None) -> np.ndarray:
        """The current frame, ``(height, width, 3)`` uint8 (``render_size`` unless given), from ``camera_id``."""
        h, w = (
            self.render_size
            if width is None and height is None
            else check_render_size(type(self).__name__, (height or self.render_size[0], width or self.render_size[1]))
        )
        cam = self.CAMERA_ID if camera_id is None else camera_id
        return self._renderer(h, w).render(self._physics.data.ptr, cam)

    def set_render_size(self, size: tuple[int, int]) -> None:
        """Draw frames and the goal image at ``size`` = (H, W)."""
        size = check_render_size(type(self).__name__, size)
        if size != self.render_size:
            self.render_size, self._goal_image = size, None

    def close(self) -> None:
        """Free the renderers (the env stays usable: they are made again when needed)."""
        for r in self._renderers.values():
            r.close()
        self._renderers = {}

    # -- goals ------------------------------------------------------------------------------------
    def eval_state(self, goal_state: np.ndarray, cur_state: np.ndarray) -> tuple[bool, float]:
        """``(success, distance)``: the goal features of ``cur_state`` within ``GOAL_TOLERANCE`` of ``goal_state``'s."""
        nq = self.model.nq
        g = np.asarray(goal_state, float).reshape(-1)[:nq]
        c = np.asarray(cur_state, float).reshape(-1)[:nq]
        if g.shape[0] != nq or c.shape[0] != nq:
            raise ConfigError(
                f"{type(self).__name__}.eval_state requires states of at least {nq} numbers (qpos first), "
                f"got {np.size(goal_state)} and {np.size(cur_state)}"
            )
        dist = float(np.linalg.norm(self.goal_features(c) - self.goal_features(g)))
        return dist <= self.GOAL_TOLERANCE, dist

    def kinematics(self, qpos: np.ndarray) -> mujoco.MjData:
        """A scratch ``MjData`` holding the positions of configuration ``qpos`` (the live data is untouched)."""
        d = self._scratch
        d.qpos[:] = qpos
        mujoco.mj_kinematics(self.model, d)
        return d

    def solve_ik(
        self, qpos: np.ndarray, index: list[int], point: Callable[[mujoco.MjData], np.ndarray], target: np.ndarray
    ) -> np.ndarray:
        """``qpos`` with the hinge angles at ``index`` moved so that ``point(data)`` reaches ``target``
        (see :func:`._model.solve_ik`)."""
        return _model.solve_ik(self.model, self.kinematics, qpos, index, point, target)

    # -- upstream's setters -----------------------------------------------------------------------
    def set_state(self, qpos: np.ndarray, qvel: np.ndarray) -> None:
        """Put the physics in configuration ``qpos`` with velocities ``qvel`` (time unchanged)."""
        nq, nv = self.model.nq, self.model.nv
        self._set_full_state(
            np.concatenate(
                [self._check_len(qpos, nq, "qpos"), self._check_len(qvel, nv, "qvel"), self._physics.data.act]
            )
        )

    def set_gravity(self, gravity: np.ndarray) -> None:
        """Set the gravity vector (x, y, z) until the next reset applies the ``gravity`` factors again."""
        self.model.opt.gravity[:] = self._check_len(gravity, 3, "gravity")

    # -- internals --------------------------------------------------------------------------------
    def _recompile(self, values: dict[str, np.ndarray]) -> None:
        """Recompile the model when a structural factor differs from the compiled one."""
        structural = [f for f in self._factor_list if f.effect.structural]
        if any(not np.array_equal(values[f.name], self._compiled[f.name]) for f in structural):
            self._editor.recompile_into(self.model, [(f.effect, values[f.name]) for f in structural])
            self._compiled.update({f.name: values[f.name] for f in structural})

    def _apply_runtime(self, values: dict[str, np.ndarray], after_task: bool) -> None:
        for f in self._factor_list:
            if f.effect.structural or f.effect.after_task != after_task:
                continue
            if isinstance(f.effect, _factors.FloorRGB):
                self._apply_floor(values[f.name], f.name)
            else:
                f.effect.apply(self.model, values[f.name], self._defaults)

    def _apply_floor(self, rgb: np.ndarray, name: str) -> None:
        if np.array_equal(rgb, self._compiled[name]):
            return
        texture = _model.grid_texture(self.model, rgb)
        if texture is not None:
            where, data = texture
            self.model.tex_data[where] = data
            self.close()  # renderers upload textures when made: make new ones
        self._compiled[name] = rgb

    def _renderer(self, h: int, w: int) -> MjRenderer:
        r = self._renderers.get((h, w))
        if r is None:
            r = self._renderers[(h, w)] = MjRenderer(self.model, h, w, self.render_quality)
        return r

    def _check_len(self, value: Any, n: int, what: str) -> np.ndarray:
        arr = np.asarray(value, float).reshape(-1)
        if arr.shape[0] != n or not np.all(np.isfinite(arr)):
            raise ConfigError(f"{type(self).__name__} requires {what} of {n} finite numbers, got {value!r}")
        return arr

    def _check_state(self, value: Any, what: str, fill: bool = True) -> np.ndarray:
        """``value`` as ``[qpos, qvel, act]``; ``[qpos, qvel]`` gets the current activations (zeros unless ``fill``)."""
        m = self.model
        arr = np.asarray(value, float).reshape(-1)
        full, short = m.nq + m.nv + m.na, m.nq + m.nv
        if arr.shape[0] == short and short != full:
            arr = np.concatenate([arr, self._physics.data.act if fill else np.zeros(m.na)])
        if arr.shape[0] != full or not np.all(np.isfinite(arr)):
            raise ConfigError(
                f"{type(self).__name__} requires reset option {what!r} of {full} finite numbers "
                f"([qpos ({m.nq}), qvel ({m.nv}), act ({m.na})]), got shape {np.shape(value)}"
            )
        return arr

    def _set_full_state(self, state: np.ndarray) -> None:
        m, d = self.model, self._physics.data
        d.qpos[:], d.qvel[:], d.act[:] = state[: m.nq], state[m.nq : m.nq + m.nv], state[m.nq + m.nv :]
        self._physics.forward()

    def _state(self) -> np.ndarray:
        d = self._physics.data
        return np.concatenate([d.qpos, d.qvel, d.act]).astype(np.float64)

    def _proprio(self, state: np.ndarray) -> np.ndarray:
        nq = self.model.nq
        return np.concatenate([state[self._qidx], state[nq + self._vidx]])

    def _observation(self) -> np.ndarray:
        obs = self._task.get_observation(self._physics)
        return np.concatenate([np.asarray(v, np.float64).reshape(-1) for v in obs.values()]).astype(np.float32)

    def _render_goal(self) -> np.ndarray:
        if self._goal_image is None:
            m, d, g = self.model, self._scratch, self._goal
            d.qpos[:], d.qvel[:], d.act[:] = g[: m.nq], g[m.nq : m.nq + m.nv], g[m.nq + m.nv :]
            mujoco.mj_forward(m, d)
            self._goal_image = self._renderer(*self.render_size).render(d, self.CAMERA_ID)
        return self._goal_image

    def _info(self) -> dict[str, Any]:
        d, state = self._physics.data, self._state()
        success, _ = self.eval_state(self._goal, state)
        info = {
            "env_name": self.env_name,
            "success": float(success),
            "qpos": d.qpos.copy(),
            "qvel": d.qvel.copy(),
            "score": self._return / 1000.0,
            **self.extra_info(),
        }
        info[keys.STATE], info[keys.PROPRIO] = state, self._proprio(state)
        info[keys.GOAL] = self._render_goal().copy()
        info[keys.GOAL_STATE], info[keys.GOAL_PROPRIO] = self._goal.copy(), self._proprio(self._goal)
        return info


def _check_env_kwargs(owner: str, kwargs: dict | None) -> dict[str, Any]:
    """``environment_kwargs`` validated: known keys, positive times, an int ``n_sub_steps`` >= 1."""
    if kwargs is not None and not isinstance(kwargs, Mapping):
        raise ConfigError(f"{owner} requires environment_kwargs as a dict or None, got {kwargs!r}")
    kwargs = dict(kwargs or {})
    for k, v in kwargs.items():
        if k not in ENV_KWARGS:
            raise ConfigError(
                f"{owner} requires environment_kwargs keys among {list(ENV_KWARGS)}, got {k!r}."
                f"{did_you_mean(str(k), ENV_KWARGS)}"
            )
        if v is None or k == "flat_observation":  # observations are always flat
            continue
        ok = isinstance(v, (int, float, np.integer, np.floating)) and not isinstance(v, bool) and v > 0
        if k == "n_sub_steps":
            ok = ok and float(v) == int(v)
        if not ok:
            need = "an int >= 1" if k == "n_sub_steps" else "a number > 0"
            raise ConfigError(f"{owner} requires environment_kwargs[{k!r}] to be {need}, got {v!r}")
    return kwargs

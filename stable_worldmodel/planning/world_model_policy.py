"""WorldModelPolicy: receding-horizon model-predictive control with a planning solver."""

from __future__ import annotations

import inspect
import logging
from collections.abc import Callable, Mapping
from typing import Any

import gymnasium as gym
import numpy as np
import torch
from gymnasium.vector.utils import batch_space

from .. import keys
from ..errors import ConfigError, UnknownNameError
from ..policy import BasePolicy, PlanConfig, Transformable
from ..solver.solver import Solver
from .io import apply_process, prepare_info, to_env_actions

logger = logging.getLogger(__name__)

__all__ = ["WorldModelPolicy"]


def _is_solver(obj: Any) -> bool:
    """``isinstance(obj, Solver)`` without evaluating properties (which may need ``configure`` first)."""
    missing = object()
    names = ("configure", "solve", "action_dim", "n_envs", "horizon")
    return all(inspect.getattr_static(obj, name, missing) is not missing for name in names)


class WorldModelPolicy(BasePolicy):
    """Plan with ``solver`` every ``receding_horizon`` blocks, act from the plan in between.

    - :meth:`set_env` configures the solver with the env's batched action space and
      ``num_envs``; a single env (no ``num_envs``) is planned for as a batch of one, and
      :meth:`get_action` then takes its infos ``(T, ...)`` and returns one action shaped like
      its ``action_space``. When ``process["action"]`` exists and the Box bounds are finite,
      the solver gets the bounds mapped through ``process["action"].transform`` (it plans in
      the model's normalized action units).
    - :meth:`get_action` (``info_dict``: the World's numpy infos ``(B, T, ...)``) replans
      only when its action buffer is empty: infos go through
      :func:`~stable_worldmodel.planning.io.prepare_info` (``process`` then ``transform``),
      the solver plans ``(B, H, A)``, and the first ``receding_horizon`` blocks
      (``receding_horizon * action_block`` env steps) are queued after
      ``process["action"].inverse_transform``. With ``config.warm_start`` the rest of the
      plan ``(B, H - receding_horizon, A)`` warm-starts the next solve.
    - Returns actions shaped like ``env.action_space`` ``(B, ...)``.

    The model gets the last ``config.history_len`` frames of each info ``(B, T, ...)`` (a World
    with a longer ``history_size`` gives more; the rest are dropped: a model encoding more frames
    than it was planned for would score the wrong action blocks). When an env starts a new
    episode mid-plan or at a plan's end (its ``step_idx`` info is 0), every env replans without
    warm start, so no env acts on, or starts from, a plan made for its previous episode;
    :meth:`reset_plan` forces a replan too.
    """

    def __init__(
        self,
        solver: Solver,
        config: PlanConfig,
        process: Mapping[str, Transformable] | None = None,
        transform: Mapping[str, Callable[[Any], Any]] | None = None,
        **kwargs: Any,
    ):
        super().__init__(**kwargs)
        if not _is_solver(solver):
            raise ConfigError(f"WorldModelPolicy requires a Solver (configure/solve/horizon/...), got {solver!r}")
        if not isinstance(config, PlanConfig):
            raise ConfigError(f"WorldModelPolicy requires a PlanConfig, got {config!r}")
        for key, proc in (process or {}).items():
            if not isinstance(proc, Transformable):
                raise ConfigError(
                    f"WorldModelPolicy requires process[{key!r}] with transform/inverse_transform, got {proc!r}"
                )
        self.type = "world_model"
        self.solver, self.cfg = solver, config
        self.process = process if process is not None else {}
        self.transform = transform if transform is not None else {}
        self.last_plan: dict | None = None
        #: optional ``(info, executed action blocks (B, R, A)) -> (B, S, S, 3)`` uint8, called after
        #: each plan (see :class:`stable_worldmodel.wm.frame.PredictionPanel`); its frames are
        #: kept in ``predicted_frames`` and shown by ``World.record_video``
        self.prediction_panel: Callable[[dict, torch.Tensor], np.ndarray] | None = None
        #: optional ``info -> info`` called on the prepared infos (torch) before each solve: it may
        #: add the model's cached embeddings (e.g. a waypoint as ``goal_emb``, see
        #: :mod:`stable_worldmodel.planning.subgoals`) to redirect the plan
        self.info_hook: Callable[[dict], dict] | None = None
        self.predicted_frames: np.ndarray | None = None
        self._space: gym.Space | None = None  # the batched action space planned for
        self._single = False  # the env has no num_envs: actions are returned without the batch axis
        self.reset_plan()

    @property
    def config(self) -> PlanConfig:
        """The planning configuration."""
        return self.cfg

    @property
    def flatten_receding_horizon(self) -> int:
        """Env steps executed per plan: ``receding_horizon * action_block``."""
        return self.cfg.receding_horizon * self.cfg.action_block

    def reset_plan(self) -> None:
        """Forget the queued actions and the warm start: the next call replans from scratch."""
        self._queue: np.ndarray | None = None
        self._pos = 0
        self._next_init: torch.Tensor | None = None
        self.predicted_frames = None
        if callable(getattr(self.info_hook, "reset", None)):  # e.g. the subgoal hook's progress per env
            self.info_hook.reset()

    def set_env(self, env: Any) -> None:
        """Attach the env and configure the solver for its batched action space.

        A vector env gives ``num_envs`` and a batched ``action_space``; an env without
        ``num_envs`` is one env, and its action space is batched here (B = 1).
        """
        super().set_env(env)
        self._single = not hasattr(env, "num_envs")
        self._space = batch_space(env.action_space, 1) if self._single else env.action_space
        n_envs = 1 if self._single else int(env.num_envs)
        self.solver.configure(action_space=self._planning_space(self._space), n_envs=n_envs, config=self.cfg)
        self.reset_plan()

    def set_seed(self, seed: int | None) -> None:
        """Restart the solver's random stream and drop the current plan."""
        if seed is None:
            return
        super().set_seed(seed)
        if callable(getattr(self.solver, "set_seed", None)):  # a user Solver may not have it
            self.solver.set_seed(seed)
        self.reset_plan()

    def _planning_space(self, space: gym.Space) -> gym.Space:
        proc = self.process.get(keys.ACTION)
        if proc is None or not isinstance(space, gym.spaces.Box) or not space.is_bounded("both"):
            return space
        bounds = apply_process(proc.transform, np.stack([space.low, space.high]).astype(np.float64))
        low, high = np.minimum(bounds[0], bounds[1]), np.maximum(bounds[0], bounds[1])
        low, high = low.reshape(space.shape).astype(np.float32), high.reshape(space.shape).astype(np.float32)
        return gym.spaces.Box(low, high, dtype=np.float32)

    def get_action(self, info_dict: Mapping[str, Any], **kwargs: Any) -> np.ndarray:
        """The next env actions ``(B, ...)`` (one env: its action); replans when the buffer is empty."""
        self._require_env()
        if self.solver.n_envs is None or self._space is None:
            raise ConfigError("WorldModelPolicy requires set_env(env) before get_action (it configures the solver)")
        if self._single:  # one env's infos: give them the batch axis the solver plans over
            info_dict = {k: v[None] if hasattr(v, "shape") else np.asarray(v)[None] for k, v in info_dict.items()}
        restarted = self._env_restarted(info_dict)  # first: at a plan boundary it still drops the warm start
        if restarted or self._queue is None or self._pos >= self._queue.shape[1]:
            self._replan(info_dict)
        action = self._queue[:, self._pos]
        self._pos += 1
        return action[0] if self._single else action

    def _env_restarted(self, info_dict: Mapping[str, Any]) -> bool:
        """True when an env started a new episode since the last plan (its ``step_idx`` is 0
        after the policy acted on that plan, mid-plan or at its end): its queued actions and
        the warm start belong to the old episode, so every env replans without warm start."""
        if self._pos == 0 or keys.STEP_IDX not in info_dict:
            return False
        step = np.asarray(info_dict[keys.STEP_IDX])
        restarted = bool(np.any(step.reshape(step.shape[0], -1)[:, -1] == 0))
        if restarted:
            self._next_init = None
        return restarted

    def _last_frames(self, info_dict: Mapping[str, Any]) -> Mapping[str, Any]:
        """The last ``history_len`` frames of World infos: their time axis is the length of
        ``step_idx`` ``(B, T)``; infos without it are passed as they are."""
        h, step = self.cfg.history_len, info_dict.get(keys.STEP_IDX)
        t = step.shape[1] if getattr(step, "ndim", 0) == 2 else None
        if t is None or t <= h:
            return info_dict
        return {k: v[:, -h:] if getattr(v, "ndim", 0) >= 2 and v.shape[1] == t else v for k, v in info_dict.items()}

    def _replan(self, info_dict: Mapping[str, Any]) -> None:
        info_dict = self._last_frames(info_dict)
        info = prepare_info(info_dict, self.process, self.transform)
        if self.info_hook is not None:
            info = self.info_hook(info)
        try:
            result = self.solver.solve(info, init_action=self._next_init)
        except KeyError as exc:
            missing = exc.args[0] if exc.args else None
            if isinstance(missing, str) and missing not in info:
                raise UnknownNameError(
                    f"WorldModelPolicy requires info key {missing!r} for the cost model, got keys {sorted(info)}; "
                    "check the World's options (goal_conditioned, history_size) and the env's observations"
                ) from exc
            raise
        plan = result["actions"]
        rh = self.cfg.receding_horizon
        self._next_init = plan[:, rh:] if self.cfg.warm_start and rh < plan.shape[1] else None
        self._queue = to_env_actions(plan[:, :rh], self.process, self._space, steps=True)
        self._pos = 0
        self.last_plan = result
        if self.prediction_panel is not None:
            self.predicted_frames = self.prediction_panel(info, plan[:, :rh])

"""Policies: what :class:`~stable_worldmodel.World` asks for actions.

A policy gets the batched info dict of the world (every entry ``(B, T, ...)``) and returns
actions shaped like the world's batched action space. ``WorldModelPolicy``,
``AutoCostModel`` and ``AutoActionableModel`` plan through a world model; they live in
:mod:`stable_worldmodel.planning` and are re-exported here lazily (they need torch).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Protocol, runtime_checkable

import numpy as np

from ._lazy import lazy_getattr
from .errors import ConfigError

__all__ = [
    "AutoActionableModel",
    "AutoCostModel",
    "BasePolicy",
    "ExpertPolicy",
    "FeedForwardPolicy",
    "PlanConfig",
    "RandomPolicy",
    "Transformable",
    "WorldModelPolicy",
]

_LAZY = {
    "WorldModelPolicy": "stable_worldmodel.planning",
    "AutoCostModel": "stable_worldmodel.planning",
    "AutoActionableModel": "stable_worldmodel.planning",
}


__getattr__ = lazy_getattr(__name__, _LAZY)


@runtime_checkable
class Transformable(Protocol):
    """A fitted pre-processor (e.g. a normalizer) applied to one info key."""

    def transform(self, x: Any) -> Any:
        """Pre-process ``x``."""

    def inverse_transform(self, x: Any) -> Any:
        """Revert :meth:`transform`."""


@dataclass(frozen=True)
class PlanConfig:
    """Configuration of receding-horizon planning.

    - ``horizon``: number of action blocks planned.
    - ``receding_horizon``: blocks executed before replanning (``<= horizon``).
    - ``history_len``: frames of history given to the model.
    - ``action_block``: env actions per planned block (the model's frame skip).
    - ``warm_start``: start the next plan from the rest of the previous one.
    """

    horizon: int
    receding_horizon: int
    history_len: int = 1
    action_block: int = 1
    warm_start: bool = True

    def __post_init__(self) -> None:
        for name in ("horizon", "receding_horizon", "history_len", "action_block"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 1:
                raise ConfigError(f"PlanConfig requires {name} to be an integer >= 1, got {value!r}")
        if self.receding_horizon > self.horizon:
            raise ConfigError(
                f"PlanConfig requires receding_horizon <= horizon, got receding_horizon={self.receding_horizon} "
                f"and horizon={self.horizon}"
            )
        if not isinstance(self.warm_start, (bool, np.bool_)):
            raise ConfigError(f"PlanConfig requires warm_start to be a bool (True or False), got {self.warm_start!r}")

    @property
    def plan_len(self) -> int:
        """Env steps covered by one plan: ``horizon * action_block``."""
        return self.horizon * self.action_block


class BasePolicy:
    """Base class of policies: keeps its keyword arguments and the env it acts in."""

    def __init__(self, **kwargs: Any):
        self.env = None
        self.type = "base"
        self.kwargs = dict(kwargs)
        for key, value in kwargs.items():
            setattr(self, key, value)

    def set_env(self, env: Any) -> None:
        """Attach the (vectorized) env whose batched action space the policy must fill."""
        self.env = env

    def set_seed(self, seed: int | None) -> None:
        """Restart the policy's random stream from ``seed`` (its ``rng``, if it has one); None keeps it.

        ``World.evaluate(seed=s)`` and ``World.record_dataset(seed=s)`` call it, so that the same
        seed gives the same episodes however often the policy was used before.
        """
        if seed is None:
            return
        self.seed = seed
        if isinstance(getattr(self, "rng", None), np.random.Generator):
            self.rng = np.random.default_rng(seed)

    def get_action(self, obs: Any, **kwargs: Any) -> Any:
        raise NotImplementedError("get_action(info_dict) -> actions shaped like env.action_space")

    def _require_env(self) -> Any:
        if self.env is None:
            raise RuntimeError(
                f"{type(self).__name__} has no env: call world.set_policy(policy) (or policy.set_env(env)) first"
            )
        return self.env


class RandomPolicy(BasePolicy):
    """Samples the env's batched action space; seeded with ``seed`` / :meth:`set_seed`."""

    def __init__(self, seed: int | None = None, **kwargs: Any):
        super().__init__(**kwargs)
        self.type = "random"
        self.seed = seed

    def set_env(self, env: Any) -> None:
        super().set_env(env)
        space = env.action_space
        # a bounded float Box is sampled directly from the space's generator: the same draws
        # as Box.sample(), without its per-call bookkeeping
        self._uniform_box = (
            type(space).__name__ == "Box" and np.dtype(space.dtype).kind == "f" and bool(space.is_bounded("both"))
        )
        if self.seed is not None:
            space.seed(self.seed)

    def set_seed(self, seed: int | None) -> None:
        self.seed = seed
        if self.env is not None and seed is not None:
            self.env.action_space.seed(seed)

    def get_action(self, obs: Any, **kwargs: Any) -> Any:
        space = self._require_env().action_space
        if self._uniform_box:
            return space.np_random.uniform(space.low, space.high).astype(space.dtype)
        return space.sample()


class ExpertPolicy(BasePolicy):
    """Base of the scripted experts of the built-in envs (see ``swm.envs.expert_policy``)."""

    def __init__(self, **kwargs: Any):
        super().__init__(**kwargs)
        self.type = "expert"

    def get_action(self, obs: Any, goal_obs: Any = None, **kwargs: Any) -> Any:
        raise NotImplementedError("get_action(info_dict) -> actions shaped like env.action_space")


class FeedForwardPolicy(BasePolicy):
    """Acts with ``model.get_action(info)`` on torch tensors (a behaviour-cloning style policy).

    ``process[key].transform`` and ``transform[key]`` are applied to the inputs like in
    ``WorldModelPolicy``; ``process["action"].inverse_transform`` to the output.
    """

    def __init__(self, model: Any, process: dict[str, Transformable] | None = None, transform: dict | None = None, **kwargs: Any):
        super().__init__(**kwargs)
        self.type = "feed_forward"
        self.model = model
        self.process = dict(process or {})
        self.transform = dict(transform or {})

    def get_action(self, info_dict: dict, **kwargs: Any) -> np.ndarray:
        import torch

        from .planning.io import prepare_info, to_env_actions

        env = self._require_env()
        info = prepare_info(info_dict, self.process, self.transform)
        with torch.no_grad():
            action = self.model.get_action(info)
        return to_env_actions(action, self.process, env.action_space)

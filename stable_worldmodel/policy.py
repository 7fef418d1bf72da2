"""Policies: what :class:`~stable_worldmodel.World` asks for actions.

A policy gets the batched info dict of the world (every entry ``(B, T, ...)``) and returns
actions shaped like the world's batched action space. ``WorldModelPolicy``,
``AutoCostModel`` and ``AutoActionableModel`` plan through a world model; they live in
:mod:`stable_worldmodel.planning` and are re-exported here lazily (they need torch).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Protocol, runtime_checkable

import numpy as np

from . import keys
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
    "RepeatActionPolicy",
    "Transformable",
    "WorldModelPolicy",
]

_LAZY = {
    "WorldModelPolicy": "stable_worldmodel.planning",
    "AutoCostModel": "stable_worldmodel.planning",
    "AutoActionableModel": "stable_worldmodel.planning",
    "_load_model_with_attribute": "stable_worldmodel.planning.auto",  # seed 000's helper
}


__getattr__ = lazy_getattr(__name__, _LAZY)

if TYPE_CHECKING:  # pragma: no cover
    from .planning import AutoActionableModel, AutoCostModel, WorldModelPolicy  # noqa: F401 (lazy re-exports)


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

    def _prepare_info(self, info_dict: dict) -> dict:
        """The World's numpy infos -> a new dict of torch tensors for a model (needs torch).

        Applies the policy's ``process`` (fitted normalizers) and ``transform`` (callables,
        e.g. image transforms) when it has them; see
        :func:`~stable_worldmodel.planning.io.prepare_info`. ``info_dict`` is not modified.
        """
        from .planning.io import prepare_info

        return prepare_info(info_dict, getattr(self, "process", None), getattr(self, "transform", None))

    def _require_env(self) -> Any:
        if self.env is None:
            raise RuntimeError(
                f"{type(self).__name__} has no env: call world.set_policy(policy) (or policy.set_env(env)) first"
            )
        return self.env


class RandomPolicy(BasePolicy):
    """Samples the env's batched action space.

    ``seed`` is applied by :meth:`set_seed`, which ``World.set_policy`` calls once after
    :meth:`set_env`; :meth:`set_env` itself leaves the space's random stream alone.
    """

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

    def set_seed(self, seed: int | None) -> None:
        self.seed = seed
        if self.env is not None and seed is not None:
            self.env.action_space.seed(seed)

    def get_action(self, obs: Any, **kwargs: Any) -> Any:
        space = self._require_env().action_space
        if self._uniform_box:
            return space.np_random.uniform(space.low, space.high).astype(space.dtype)
        return space.sample()


#: second word of the repeats' seed: their stream stays apart from the inner policy's
_REPEAT_STREAM = 0x5E9EA7


class RepeatActionPolicy(BasePolicy):
    """``policy``'s actions, where each env repeats its previous action with probability
    ``repeat_prob`` (sticky actions: the collectors of upstream's datasets, e.g. TwoRoom's
    ``ExpertPolicy(action_repeat_prob=0.05)``; a repeat may cross an episode boundary, as there).

    The repeats are drawn from their own generator, seeded with ``seed`` (or the seed
    :meth:`set_seed` gets, which is passed on to ``policy``).
    """

    def __init__(self, policy: BasePolicy, repeat_prob: float, seed: int | None = None, **kwargs: Any):
        if isinstance(repeat_prob, bool) or not isinstance(repeat_prob, (int, float, np.number)):
            raise ConfigError(f"RepeatActionPolicy requires repeat_prob to be a number in [0, 1], got {repeat_prob!r}")
        if not 0.0 <= float(repeat_prob) <= 1.0:
            raise ConfigError(f"RepeatActionPolicy requires repeat_prob in [0, 1], got {repeat_prob!r}")
        super().__init__(**kwargs)
        self.type = f"repeat({getattr(policy, 'type', type(policy).__name__)})"
        self.policy, self.repeat_prob = policy, float(repeat_prob)
        self.seed = seed if seed is not None else getattr(policy, "seed", None)
        self.rng = np.random.default_rng(None if self.seed is None else [self.seed, _REPEAT_STREAM])
        self._last: np.ndarray | None = None

    def set_env(self, env: Any) -> None:
        super().set_env(env)
        self.policy.set_env(env)
        self._last = None

    def set_seed(self, seed: int | None) -> None:
        if seed is None:
            return
        self.seed = seed
        self.rng = np.random.default_rng([seed, _REPEAT_STREAM])
        self.policy.set_seed(seed)
        self._last = None

    def get_action(self, obs: Any, **kwargs: Any) -> Any:
        action = np.array(self.policy.get_action(obs, **kwargs), copy=True)
        if self._last is not None and self._last.shape == action.shape and action.ndim >= 1 and self.repeat_prob > 0:
            repeat = self.rng.random(len(action)) < self.repeat_prob
            action[repeat] = self._last[repeat]
        self._last = action.copy()
        return action


class ExpertPolicy(BasePolicy):
    """Base of the scripted experts of the built-in envs (see ``swm.envs.expert_policy``).

    Subclasses override :meth:`get_action`; the base returns None (no expert action).
    """

    def __init__(self, **kwargs: Any):
        super().__init__(**kwargs)
        self.type = "expert"

    def get_action(self, obs: Any, goal_obs: Any = None, **kwargs: Any) -> Any:
        """The expert's actions shaped like ``env.action_space``; None here (no expert logic)."""
        return None


class FeedForwardPolicy(BasePolicy):
    """Acts with ``model.get_action(info)`` on torch tensors (a behaviour-cloning style policy).

    - Inputs: ``process[key].transform`` then ``transform[key]`` as in ``WorldModelPolicy``
      (:meth:`_prepare_info`); ``goal`` is also given as ``goal_pixels`` (the GCBC models'
      key); tensors are moved to the model's device.
    - Output: the model's actions as a numpy array, through ``process["action"].inverse_transform``
      (on the ``(-1, A)`` view), reshaped to ``env.action_space.shape`` when it has that many
      numbers. They are not clipped or cast: the env receives what the model asked for.
    - ``process`` and ``transform`` are kept as the given objects (later changes are seen);
      the model is put in eval mode.
    """

    def __init__(
        self, model: Any, process: dict[str, Transformable] | None = None, transform: dict | None = None, **kwargs: Any
    ):
        super().__init__(**kwargs)
        self.type = "feed_forward"
        self.model = model
        if callable(getattr(model, "eval", None)):
            model.eval()
        self.process = process if process is not None else {}
        self.transform = transform if transform is not None else {}

    def get_action(self, info_dict: dict, **kwargs: Any) -> np.ndarray:
        import torch

        from .planning.io import apply_process

        env = self._require_env()
        info = self._prepare_info(info_dict)
        if keys.GOAL in info:
            info.setdefault(keys.goal_key(keys.PIXELS), info[keys.GOAL])
        params = self.model.parameters() if callable(getattr(self.model, "parameters", None)) else ()
        param = next(iter(params), None)
        if param is not None:
            info = {k: v.to(param.device) if torch.is_tensor(v) else v for k, v in info.items()}
        with torch.no_grad():
            action = self.model.get_action(info)
        action = action.detach().cpu().numpy() if torch.is_tensor(action) else np.asarray(action)
        proc = self.process.get(keys.ACTION)
        if proc is not None:
            action = apply_process(proc.inverse_transform, action)
        shape = tuple(getattr(env.action_space, "shape", None) or ())
        if shape and action.shape != shape and action.size == int(np.prod(shape)):
            action = action.reshape(shape)
        return action

"""VariationWrapper: batched variation spaces on a vector env."""

from __future__ import annotations

from typing import Any

import gymnasium as gym
from gymnasium.spaces.utils import is_space_dtype_shape_equiv
from gymnasium.vector.utils import batch_space

from ..errors import ConfigError

MODES = ("same", "different")


class VariationWrapper(gym.vector.VectorWrapper):
    """Exposes ``single_variation_space`` and a batched ``variation_space`` on a vector env.

    - ``"same"``: every env has the same variation space; ``variation_space`` is it batched.
    - ``"different"``: each env keeps its own; ``variation_space`` is a ``Tuple`` of them.
    - a ``gym.Space``: used as the single variation space of every env.
    A base env without ``variation_space`` gives ``None`` for both. The sub-envs must share
    the shape and dtype of their observation and action spaces (:class:`ConfigError`, a
    ``ValueError``, otherwise). :attr:`envs` lists the sub-envs when the vector env has them.
    """

    def __init__(self, env, variation_mode: str | gym.Space = "same"):
        super().__init__(env)
        if not isinstance(variation_mode, gym.Space) and variation_mode not in MODES:
            raise ConfigError(
                f"VariationWrapper requires variation_mode in {MODES} or a gym.Space (Invalid `variation_mode`), "
                f"got {variation_mode!r}"
            )
        _check_sub_spaces(env, variation_mode)
        if isinstance(variation_mode, gym.Space):
            self.single_variation_space = variation_mode
            self.variation_space = batch_space(variation_mode, env.num_envs)
            self.variation_mode = "same"
            return
        self.variation_mode = variation_mode
        spaces = _sub_variation_spaces(env)
        if spaces is None or spaces[0] is None:
            self.single_variation_space = None
            self.variation_space = None
        elif variation_mode == "same":
            first = spaces[0]
            for other in spaces[1:]:
                if (
                    other is not None
                    and getattr(other, "names", lambda: None)() != getattr(first, "names", lambda: None)()
                ):
                    raise ConfigError(
                        "VariationWrapper(variation_mode='same') requires identical sub-env variation spaces"
                    )
            self.single_variation_space = first
            self.variation_space = batch_space(first, env.num_envs)
        else:
            self.single_variation_space = spaces[0]
            self.variation_space = gym.spaces.Tuple(spaces)

    @property
    def envs(self) -> list[gym.Env] | None:
        """The sub-envs of the wrapped vector env (None when it has no ``envs``, e.g. async)."""
        return getattr(self.env, "envs", None)


def _sub_attr(env, name: str) -> list | None:
    """Attribute ``name`` of every sub-env (None when the vector env cannot tell)."""
    envs = getattr(env, "envs", None)
    if envs is not None:
        return [getattr(e, name, None) for e in envs]
    try:
        return list(env.get_attr(name))
    except (AttributeError, NotImplementedError):
        return None


def _check_sub_spaces(env, mode: Any) -> None:
    """ConfigError unless every sub-env's observation and action spaces match the vector env's single ones."""
    for kind in ("observation", "action"):
        single = getattr(env, f"single_{kind}_space", None)
        for i, space in enumerate(_sub_attr(env, f"{kind}_space") or ()):
            if single is None or space is None or _equivalent(space, single):
                continue
            raise ConfigError(
                f"VariationWrapper(..., variation_mode={mode!r}) requires sub-envs whose {kind} spaces share "
                f"a common shape and dtype (the sub-environments {kind} spaces do not share a common shape and "
                f"dtype), got single_{kind}_space={single} and {space} for sub-env {i}"
            )


def _equivalent(space: gym.Space, single: gym.Space) -> bool:
    """Same shape and dtype (gymnasium's rule); spaces it cannot compare (Text, Graph ...) pass."""
    try:
        return is_space_dtype_shape_equiv(space, single)
    except (NotImplementedError, TypeError):
        return True


def _sub_variation_spaces(env) -> list | None:
    """Variation space of each sub-env (from the vector env's own accessor when it has one)."""
    getter = getattr(env, "sub_variation_spaces", None)
    if getter is not None:
        return getter()
    try:
        return list(env.get_attr("variation_space"))
    except AttributeError:
        return None

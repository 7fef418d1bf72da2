"""VariationWrapper: batched variation spaces on a vector env."""

from __future__ import annotations

import gymnasium as gym
from gymnasium.vector.utils import batch_space

from ..errors import ConfigError

MODES = ("same", "different")


class VariationWrapper(gym.vector.VectorWrapper):
    """Exposes ``single_variation_space`` and a batched ``variation_space`` on a vector env.

    - ``"same"``: every env has the same variation space; ``variation_space`` is it batched.
    - ``"different"``: each env keeps its own; ``variation_space`` is a ``Tuple`` of them.
    A base env without ``variation_space`` gives ``None`` for both.
    """

    def __init__(self, env, variation_mode: str | gym.Space = "same"):
        super().__init__(env)
        if isinstance(variation_mode, gym.Space):
            self.single_variation_space = variation_mode
            self.variation_space = batch_space(variation_mode, env.num_envs)
            self.variation_mode = "same"
            return
        if variation_mode not in MODES:
            raise ConfigError(f"VariationWrapper requires variation_mode in {MODES}, got {variation_mode!r}")
        self.variation_mode = variation_mode
        spaces = _sub_variation_spaces(env)
        if spaces is None or spaces[0] is None:
            self.single_variation_space = None
            self.variation_space = None
        elif variation_mode == "same":
            first = spaces[0]
            for other in spaces[1:]:
                if other is not None and getattr(other, "names", lambda: None)() != getattr(first, "names", lambda: None)():
                    raise ConfigError("VariationWrapper(variation_mode='same') requires identical sub-env variation spaces")
            self.single_variation_space = first
            self.variation_space = batch_space(first, env.num_envs)
        else:
            self.single_variation_space = spaces[0]
            self.variation_space = gym.spaces.Tuple(spaces)


def _sub_variation_spaces(env) -> list | None:
    """Variation space of each sub-env (from the vector env's own accessor when it has one)."""
    getter = getattr(env, "sub_variation_spaces", None)
    if getter is not None:
        return getter()
    try:
        return list(env.get_attr("variation_space"))
    except AttributeError:
        return None

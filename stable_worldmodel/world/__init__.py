"""The World: vectorized envs, policies, evaluation and recording."""

from .world import World

__all__ = ["World"]

"""The World: vectorized envs, policies, evaluation and recording."""

from .env_pool import EnvPool
from .world import World

__all__ = ["EnvPool", "World"]

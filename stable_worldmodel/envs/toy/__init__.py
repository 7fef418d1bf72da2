"""A tiny deterministic point-reaching env used by tests, docs and benchmarks."""

from .env import ToyEnv, ToyExpert

__all__ = ["ToyEnv", "ToyExpert"]

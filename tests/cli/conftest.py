"""Fixtures of the CLI tests: small toy datasets recorded by the tests (the runner is in ../conftest.py)."""

from __future__ import annotations

import pytest

TOY = "swm/Toy-v0"


@pytest.fixture
def record_toy():
    """``record_toy(name, episodes=2, variation=None)`` records a 16x16 toy dataset in the cache."""
    from stable_worldmodel import World
    from stable_worldmodel.envs import expert_policy

    def record(name: str, episodes: int = 2, variation: list[str] | None = None):
        with World(TOY, 1, (16, 16), max_episode_steps=20, verbose=0) as world:
            world.set_policy(expert_policy(TOY))
            options = {"variation": variation} if variation else None
            return world.record_dataset(name, episodes=episodes, seed=0, options=options)

    return record

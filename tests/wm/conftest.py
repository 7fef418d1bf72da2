"""Fixtures of the wm tests: tiny seeded models and moving-dot clips (see ``_tiny.py``)."""

from __future__ import annotations

import pytest
from _tiny import make_tiny, moving_dot


@pytest.fixture(autouse=True)
def _one_thread(one_torch_thread):
    """Every wm test runs torch on one thread (see ../conftest.py)."""


@pytest.fixture
def make_model():
    """``make_model(name, seed=0, **overrides)``: a seeded tiny model (``TINY`` plus ``overrides``)."""
    return make_tiny


@pytest.fixture
def dot_data():
    """The :func:`_tiny.moving_dot` factory."""
    return moving_dot


@pytest.fixture(scope="session")
def _recorded_toy(tmp_path_factory):
    """swm/Toy-v0 expert episodes at 16x16 (its ``reward`` column included), recorded once."""
    from stable_worldmodel import World
    from stable_worldmodel.envs import expert_policy

    root = tmp_path_factory.mktemp("toy")
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("STABLEWM_HOME", str(root))
        with World("swm/Toy-v0", 1, (16, 16), max_episode_steps=20, verbose=0) as world:
            world.set_policy(expert_policy("swm/Toy-v0"))
            return world.record_dataset("toy", episodes=6, seed=0, cache_dir=root)


@pytest.fixture
def toy(_recorded_toy, _stablewm_home) -> str:
    """The name of the recorded toy dataset (``"toy"``), copied into this test's cache."""
    import shutil

    _stablewm_home.mkdir(parents=True, exist_ok=True)
    shutil.copy(_recorded_toy, _stablewm_home / "toy.h5")
    return "toy"

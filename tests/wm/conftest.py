"""Fixtures of the wm tests: tiny seeded models and moving-dot clips (see ``_tiny.py``)."""

from __future__ import annotations

import pytest
import torch
from _tiny import make_tiny, moving_dot


@pytest.fixture(autouse=True)
def _one_thread():
    """Width-8 models are fastest on one thread; several threads on a busy CPU are 50x slower."""
    threads = torch.get_num_threads()
    torch.set_num_threads(1)
    yield
    torch.set_num_threads(threads)


@pytest.fixture
def make_model():
    """``make_model(name, seed=0, **overrides)``: a seeded tiny model (``TINY`` plus ``overrides``)."""
    return make_tiny


@pytest.fixture
def dot_data():
    """The :func:`_tiny.moving_dot` factory."""
    return moving_dot

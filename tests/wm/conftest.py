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

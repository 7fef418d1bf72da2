"""Shared fixtures: every test gets its own empty cache directory."""

from __future__ import annotations

import pytest


@pytest.fixture(autouse=True)
def _stablewm_home(tmp_path, monkeypatch):
    """Point ``STABLEWM_HOME`` at a fresh temp dir so no test touches ``~``."""
    home = tmp_path / "stablewm_home"
    monkeypatch.setenv("STABLEWM_HOME", str(home))
    return home

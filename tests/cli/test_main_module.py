"""``python -m stable_worldmodel`` is the swm command."""

from __future__ import annotations

import subprocess
import sys

from stable_worldmodel import __version__


def test_python_dash_m_package_runs_the_cli():
    out = subprocess.run(
        [sys.executable, "-m", "stable_worldmodel", "--version"], capture_output=True, text=True, timeout=60
    )
    assert out.returncode == 0
    assert __version__ in out.stdout

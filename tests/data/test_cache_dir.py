"""get_cache_dir and the cheap import of stable_worldmodel.data."""

from __future__ import annotations

import subprocess
import sys

import stable_worldmodel.data as data
from stable_worldmodel.data.utils import resolve_dataset_path


def test_cache_dir_reads_env_at_call_time_and_creates_it(tmp_path, monkeypatch):
    target = tmp_path / "a" / "b"
    monkeypatch.setenv("STABLEWM_HOME", str(target))
    assert data.get_cache_dir() == target
    assert target.is_dir()
    other = tmp_path / "c"
    monkeypatch.setenv("STABLEWM_HOME", str(other))
    assert data.get_cache_dir() == other


def test_cache_dir_defaults_to_home(tmp_path, monkeypatch):
    monkeypatch.delenv("STABLEWM_HOME")
    monkeypatch.setenv("HOME", str(tmp_path))
    assert data.get_cache_dir() == tmp_path / ".stable_worldmodel"


def test_resolve_dataset_path(tmp_path):
    assert resolve_dataset_path("name", tmp_path) == tmp_path / "name.h5"
    assert resolve_dataset_path("name") == data.get_cache_dir() / "name.h5"
    assert resolve_dataset_path(tmp_path / "x.h5") == tmp_path / "x.h5"


def test_import_is_lazy():
    code = (
        "import sys, stable_worldmodel.data as d; d.get_cache_dir; print('h5py' in sys.modules, 'torch' in sys.modules)"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.split()
    assert out == ["False", "False"]


def test_every_public_name_resolves():
    for name in data.__all__:
        assert getattr(data, name) is not None, name

"""``swm envs`` keeps the factor counts of the built-in envs on disk (envs/factor_index.py): a second listing builds
no env, and new sources, a foreign env or a broken cache file never give a stale or missing count."""

from __future__ import annotations

import json

import gymnasium as gym
import pytest

from stable_worldmodel.envs import factor_index
from stable_worldmodel.envs.factor_index import FactorCounts, sources_fingerprint
from stable_worldmodel.envs.toy.env import ToyEnv

TOY = "swm/Toy-v0"


@pytest.fixture
def builds(monkeypatch):
    """The env ids whose variation space was built (counted by wrapping ``variation_space_of``)."""
    from stable_worldmodel.planning import policies

    built: list[str] = []
    real = policies.variation_space_of

    def counting(env_id):
        built.append(env_id)
        return real(env_id)

    monkeypatch.setattr(policies, "variation_space_of", counting)
    return built


def _cache_file(home):
    return home / "envs" / factor_index.FILE_NAME


def test_counts_are_built_once_then_read_from_the_cache(builds, _stablewm_home):
    from stable_worldmodel.planning.policies import variation_space_of

    first = FactorCounts()
    n = first.get(TOY)
    assert builds == [TOY] and n == len(variation_space_of(TOY).names()) > 0
    first.save()
    stored = json.loads(_cache_file(_stablewm_home).read_text())
    assert stored == {"key": sources_fingerprint(), "counts": {TOY: n}}
    builds.clear()
    assert FactorCounts().get(TOY) == n and builds == []


def test_new_sources_recount(builds, monkeypatch, _stablewm_home):
    counts = FactorCounts()
    counts.get(TOY)
    counts.save()
    monkeypatch.setattr(factor_index, "sources_fingerprint", lambda: "0.2.0:edited")
    builds.clear()
    again = FactorCounts()
    assert again.get(TOY) > 0 and builds == [TOY]
    again.save()
    assert json.loads(_cache_file(_stablewm_home).read_text())["key"] == "0.2.0:edited"


def test_fingerprint_follows_size_and_mtime_of_python_files(tmp_path):
    import os

    (tmp_path / "sub").mkdir()
    (tmp_path / "sub" / "env.py").write_text("A = 1\n")
    (tmp_path / "notes.txt").write_text("ignored")
    before = sources_fingerprint(tmp_path)
    assert sources_fingerprint(tmp_path) == before
    (tmp_path / "notes.txt").write_text("still ignored, not a .py file")
    assert sources_fingerprint(tmp_path) == before
    stat = os.stat(tmp_path / "sub" / "env.py")
    os.utime(tmp_path / "sub" / "env.py", ns=(stat.st_atime_ns, stat.st_mtime_ns + 1_000_000))
    assert sources_fingerprint(tmp_path) != before


class _OutsideToy(ToyEnv):
    """An env class that lives outside the package (here: in a test module)."""


def test_envs_registered_from_outside_the_package_are_never_cached(builds, _stablewm_home):
    from stable_worldmodel.envs import _registry, register

    try:
        register("swm/OutsideToy-v0", _OutsideToy)
        counts = FactorCounts()
        assert counts.get("swm/OutsideToy-v0") == counts.get("swm/OutsideToy-v0") > 0
        assert builds == ["swm/OutsideToy-v0"] * 2
        counts.save()
        assert not _cache_file(_stablewm_home).exists()  # nothing built-in was counted: nothing written
    finally:
        _registry._ENTRIES.pop("swm/OutsideToy-v0", None)
        _registry.WORLDS.discard("swm/OutsideToy-v0")
        gym.registry.pop("swm/OutsideToy-v0", None)


@pytest.mark.parametrize("content", ["{not json", '["a list"]', '{"key": "KEY", "counts": {"swm/Toy-v0": "9"}}'])
def test_a_broken_cache_file_is_recounted_and_replaced(builds, _stablewm_home, content):
    path = _cache_file(_stablewm_home)
    path.parent.mkdir(parents=True)
    path.write_text(content.replace("KEY", sources_fingerprint()))
    counts = FactorCounts()
    n = counts.get(TOY)
    assert builds == [TOY] and n > 0
    counts.save()
    assert json.loads(path.read_text())["counts"] == {TOY: n}


def test_an_unusable_cache_folder_only_costs_time(builds, monkeypatch, tmp_path):
    home = tmp_path / "a_file"
    home.write_text("not a folder")
    monkeypatch.setenv("STABLEWM_HOME", str(home))
    counts = FactorCounts()
    assert counts.path is None and counts.get(TOY) > 0
    counts.save()  # nothing to write to: no error
    assert home.read_text() == "not a folder"


def test_swm_envs_builds_each_env_once_across_calls(swm, builds, _stablewm_home):
    first = swm("envs", "--tag", "toy")
    assert first.exit_code == 0, first.output
    toys = sorted(set(builds))
    assert TOY in toys
    builds.clear()
    second = swm("envs", "--tag", "toy")
    assert second.exit_code == 0 and builds == []
    assert second.output == first.output

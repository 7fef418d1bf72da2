"""Tests of stable_worldmodel.utils (seed examples verbatim, then errors and pretraining)."""

from __future__ import annotations

import json
import sys
import types

import pytest

from stable_worldmodel import utils
from stable_worldmodel.errors import ConfigError
from stable_worldmodel.utils import flatten_dict, get_in, pretraining


def test_seed_flatten_dict_examples():
    info = {"a": {"b": {"c": 42, "d": 43}}, "e": 44}
    assert repr(flatten_dict(info)) == "{'a.b.c': 42, 'a.b.d': 43, 'e': 44}"
    assert repr(flatten_dict({"a": {"b": 2}, "a.b": 3})) == "{'a.b': 3}"


def test_flatten_dict_options():
    assert flatten_dict({1: {2: "x"}, (3, 4): 5}) == {"1.2": "x", "(3, 4)": 5}
    assert flatten_dict({"a": {"b": 1}}, parent_key="root", sep="/") == {"root/a/b": 1}
    assert flatten_dict({"a": {}, "b": None}) == {"b": None}
    assert flatten_dict({}) == {}
    nested = {"x": {"y": 1}}
    flatten_dict(nested)
    assert nested == {"x": {"y": 1}}  # input untouched


def test_seed_get_in_example():
    variations = {"a": {"b": {"c": 42}}}
    assert get_in(variations, ["a", "b", "c"]) == 42


def test_get_in_empty_path_and_iterables():
    d = {"a": {"b": 1}}
    assert get_in(d, []) is d
    assert get_in(d, iter(["a"])) is d["a"]
    assert get_in(d, ("a", "b")) == 1
    assert get_in({0: {1: "x"}}, [0, 1]) == "x"


def test_get_in_missing_key_names_key_and_path():
    d = {"a": {"color": 1}}
    with pytest.raises(KeyError, match=r"'colour' at \['a'\] of path \['a', 'colour'\].*Did you mean 'color'"):
        get_in(d, ["a", "colour"])
    with pytest.raises(KeyError, match="got a int"):
        get_in(d, ["a", "color", "deeper"])


SCRIPT = """
import json, sys
with open(sys.argv[1], "w") as f:
    json.dump(sys.argv[2:], f)
sys.exit(int(sys.argv[2]) if sys.argv[2].isdigit() else 0)
"""


@pytest.fixture
def script(tmp_path):
    path = tmp_path / "train.py"
    path.write_text(SCRIPT)
    return path


def test_pretraining_success_passes_arguments(script, tmp_path):
    out = tmp_path / "argv.json"
    rc = pretraining(str(script), "pusht", "my model", args=f"{out} 'lr=0.1' seed=3")
    assert rc == 0
    assert json.loads(out.read_text()) == [
        "lr=0.1",
        "seed=3",
        "++dump_object=True",
        "dataset_name=pusht",
        "output_model_name=my model",
    ]
    pretraining(script, "d", "m", dump_object=False, args=str(out))
    assert "++dump_object=False" in json.loads(out.read_text())


def test_pretraining_failure_exits_with_child_code(script, tmp_path):
    with pytest.raises(SystemExit) as info:
        pretraining(str(script), "d", "m", args=f"{tmp_path / 'argv.json'} 7")
    assert info.value.code == 7


def test_pretraining_missing_script(tmp_path):
    with pytest.raises(ValueError, match="existing script") as info:
        pretraining(str(tmp_path / "nope.py"), "d", "m")
    assert isinstance(info.value, ConfigError)
    with pytest.raises(ValueError):
        pretraining(str(tmp_path), "d", "m")  # a directory is not a script


def test_record_video_from_dataset_forwards(monkeypatch):
    calls = []
    fake = types.ModuleType("stable_worldmodel.data.video")
    fake.record_video_from_dataset = lambda *a, **kw: calls.append((a, kw)) or "done"
    monkeypatch.setitem(sys.modules, "stable_worldmodel.data.video", fake)
    assert utils.record_video_from_dataset("v.mp4", "ds", [0, 1], fps=10) == "done"
    assert calls == [(("v.mp4", "ds", [0, 1]), {"max_steps": 500, "fps": 10, "viewname": "pixels"})]


def test_pretraining_runs_the_script_unbuffered(tmp_path, monkeypatch):
    """As 0.0.3: ``PYTHONUNBUFFERED=1`` unless the caller set it."""
    monkeypatch.delenv("PYTHONUNBUFFERED", raising=False)
    script = tmp_path / "env.py"
    script.write_text("import os, sys\nopen(sys.argv[1], 'w').write(os.environ.get('PYTHONUNBUFFERED', ''))\n")
    pretraining(str(script), "d", "m", args=str(tmp_path / "out.txt"))
    assert (tmp_path / "out.txt").read_text() == "1"

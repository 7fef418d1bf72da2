"""Attribute access reaches submodules through the lazy packages, as in the original releases
(issue 28: ``swm.wm.utils.load_pretrained(...)`` in the LeWM authors' scripts), and stays cheap."""

from __future__ import annotations

import subprocess
import sys

import pytest

PAIRS = [
    ("wm.utils", "load_pretrained"),
    ("wm.lewm", "LeWM"),
    ("wm.prejepa", "PreJEPA"),
    ("wm.gcrl", "GCRL"),
    ("wm.gcbc", "GCBC"),
    ("wm.loss", "SIGReg"),
    ("data.utils", "load_dataset"),
    ("solver.cem", "CEMSolver"),
]

# One child interpreter imports torch and ``stable_worldmodel`` (which imports no submodule), then forks once per
# pair: each fork starts from that state, so each pair's attribute chain is resolved by the lazy packages alone
# (one interpreter start and one torch import instead of one of each per pair).
_CHILD = """
import json, os, sys
import torch  # noqa: F401 (imported once, before the forks)
import stable_worldmodel as swm
assert "stable_worldmodel.wm" not in sys.modules and "stable_worldmodel.solver" not in sys.modules
results = {}
for path, name in json.loads(sys.argv[1]):
    read, write = os.pipe()
    pid = os.fork()
    if pid == 0:
        os.close(read)
        try:
            obj = swm
            for part in path.split("."):
                obj = getattr(obj, part)
            answer = str(getattr(obj, name).__module__.startswith("stable_worldmodel"))
        except BaseException as exc:
            answer = f"{type(exc).__name__}: {exc}"
        os.write(write, answer.encode())
        os._exit(0)
    os.close(write)
    with os.fdopen(read) as pipe:
        results[f"{path}.{name}"] = pipe.read()
    os.waitpid(pid, 0)
print(json.dumps(results))
"""


@pytest.fixture(scope="module")
def resolved() -> dict[str, str]:
    import json

    out = subprocess.run([sys.executable, "-c", _CHILD, json.dumps(PAIRS)], capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr[-2000:]
    return json.loads(out.stdout.strip().splitlines()[-1])


@pytest.mark.parametrize("path, name", PAIRS)
def test_submodules_are_attributes_of_their_package(resolved, path, name):
    assert resolved[f"{path}.{name}"] == "True"


def test_unknown_names_stay_attribute_errors():
    import stable_worldmodel as swm

    with pytest.raises(AttributeError, match="has no attribute 'utilz'"):
        swm.wm.utilz  # noqa: B018 (the attribute access is the test)
    assert not hasattr(swm.wm, "_private") and not hasattr(swm.data, "nothing_here")

"""``import stable_worldmodel`` is cheap: no heavy modules, fast, and every public name resolves."""

from __future__ import annotations

import importlib
import json
import subprocess
import sys

import pytest

import stable_worldmodel as swm

HEAVY = ("torch", "h5py", "cv2", "mujoco", "matplotlib", "imageio")
IMPORT_BUDGET_S = 0.3  # the target (STYLE.md)
ASSERT_BOUND_S = 1.0  # what the test enforces, generous for a loaded machine

_PROBE = """
import json, sys, time
t0 = time.perf_counter()
import stable_worldmodel
dt = time.perf_counter() - t0
print(json.dumps({"seconds": dt, "modules": sorted(sys.modules)}))
"""


def _fresh_import() -> dict:
    out = subprocess.run([sys.executable, "-c", _PROBE], capture_output=True, text=True, check=True, timeout=120)
    return json.loads(out.stdout.strip().splitlines()[-1])


def test_import_pulls_in_no_heavy_module():
    modules = set(_fresh_import()["modules"])
    loaded = [m for m in HEAVY if m in modules or any(k.startswith(m + ".") for k in modules)]
    assert not loaded, f"import stable_worldmodel imported {loaded}"


def test_import_is_fast():
    best = min(_fresh_import()["seconds"] for _ in range(3))
    print(f"import stable_worldmodel: {best * 1000:.0f} ms (min of 3; target {IMPORT_BUDGET_S * 1000:.0f} ms)")
    assert best < ASSERT_BOUND_S


def test_all_names_are_listed_in_dir():
    assert set(swm.__all__) <= set(dir(swm))


@pytest.mark.parametrize("name", swm.__all__)
def test_public_name_resolves(name):
    value = getattr(swm, name)  # a missing submodule fails here (every public name is written)
    assert value is not None
    if name in {"World", "PlanConfig"}:
        assert isinstance(value, type)


def test_unknown_attribute_raises_attribute_error():
    with pytest.raises(AttributeError, match="no_such_name"):
        swm.no_such_name  # noqa: B018


@pytest.mark.parametrize("module", ["stable_worldmodel.spaces", "stable_worldmodel.utils"])
def test_light_modules_stay_light(module):
    code = f"import sys, {module}; print(','.join(m for m in {HEAVY!r} if m in sys.modules))"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True, timeout=120)
    assert out.stdout.strip() == "", f"{module} imported {out.stdout.strip()}"
    assert importlib.import_module(module)

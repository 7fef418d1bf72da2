"""The one table of older releases' module paths (``stable_worldmodel._compat.MODULE_PATHS``): each
old path imports, and every name research code takes from it is the object of its current home."""

from __future__ import annotations

import importlib

import pytest

from stable_worldmodel._compat import MODULE_PATHS, world_compat_args
from stable_worldmodel.errors import ConfigError


@pytest.mark.parametrize("old", sorted(MODULE_PATHS))
def test_an_old_module_path_gives_the_current_objects(old):
    release, new, names = MODULE_PATHS[old]
    assert release in ("seed 000", "0.0.3", "0.1.1")
    if any(part in old for part in ("ogbench", "dmcontrol")):
        pytest.importorskip("mujoco")
    if "simple_nav" in old:
        pytest.importorskip("minigrid")
    old_module, new_module = importlib.import_module(old), importlib.import_module(new)
    for name in names:
        assert getattr(old_module, name) is getattr(new_module, name), f"{old}.{name}"


def test_world_compat_args_are_taken_out_of_the_env_kwargs():
    kwargs = {"add_pixels": False, "vectorization_mode": "sync", "pre_wrappers": None, "goal_shape": (8, 8), "size": 3}
    args = world_compat_args(kwargs)
    assert kwargs == {"size": 3}
    assert (args.add_pixels, args.vectorization_mode, args.pre_wrappers, args.goal_shape) == (False, "sync", [], (8, 8))
    with pytest.raises(ConfigError, match="add_pixels to be a bool"):
        world_compat_args({"add_pixels": "yes"})

"""The boundary of what exists only for older releases (0.0.3, the seeds' release, and upstream 0.1.1).

Research code written against those releases imports their module paths and passes their keyword
arguments; both are kept here in one place, each entry naming the release it comes from, and
``tests/test_compat_paths.py`` checks every one. New code should use the current names.

Upstream-faithful environments are named by the version of theirs they reproduce
(``envs/two_room/v0.py`` is 0.0.3's ``TwoRoom``, ``envs/two_room/v1.py`` and ``envs/pusht/v1.py``
upstream 0.1.1's), not as "legacy" code: they are supported designs of their own.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from .errors import ConfigError

__all__ = ["MODULE_PATHS", "WorldCompatArgs", "world_compat_args"]

#: old module path -> (release it comes from, where the names live now, names research code imports)
MODULE_PATHS: dict[str, tuple[str, str, tuple[str, ...]]] = {
    "stable_worldmodel.wrappers": ("seed 000", "stable_worldmodel.wrapper", ("MegaWrapper", "EverythingToInfoWrapper")),
    "stable_worldmodel.envs.ogbench_cube": ("0.0.3", "stable_worldmodel.envs.ogbench.cube_env", ("CubeEnv",)),
    "stable_worldmodel.envs.ogbench_scene": ("0.0.3", "stable_worldmodel.envs.ogbench.scene_env", ("SceneEnv",)),
    "stable_worldmodel.envs.ogbench_manip": (
        "0.0.3",
        "stable_worldmodel.envs.ogbench",
        ("CubeEnv", "SceneEnv", "ExpertPolicy"),
    ),
    "stable_worldmodel.envs.ogbench_manip.cube_env": ("0.0.3", "stable_worldmodel.envs.ogbench.cube_env", ("CubeEnv",)),
    "stable_worldmodel.envs.ogbench_manip.scene_env": (
        "0.0.3",
        "stable_worldmodel.envs.ogbench.scene_env",
        ("SceneEnv",),
    ),
    "stable_worldmodel.envs.ogbench_manip.expert_policy": (
        "0.0.3",
        "stable_worldmodel.envs.ogbench.expert_policy",
        ("ExpertPolicy",),
    ),
    # 0.0.3's own path (the env lives there; its module env.py holds the class and ellers_maze)
    "stable_worldmodel.envs.simple_nav": (
        "0.0.3",
        "stable_worldmodel.envs.simple_nav.env",
        ("SimpleNavigationEnv", "ellers_maze"),
    ),
    "stable_worldmodel.envs.dmcontrol.expert_policy": (
        "0.1.1",
        "stable_worldmodel.envs.dmcontrol.expert",
        ("ExpertPolicy",),
    ),
    "stable_worldmodel.wm.dinowm": (
        "seed 000",
        "stable_worldmodel.wm.prejepa",
        ("PreJEPA", "CausalPredictor", "Embedder"),
    ),
    "stable_worldmodel.planning.solver": ("0.1.1", "stable_worldmodel.planning.solver.cem", ("CEMSolver",)),
}


@dataclass(frozen=True)
class WorldCompatArgs:
    """The ``World`` keyword arguments of older releases, taken out of its ``**kwargs`` before the
    rest goes to the env constructor."""

    #: upstream 0.1.1: ``False`` for envs without pixels
    add_pixels: bool = True
    #: upstream 0.1.1: ``"sync"`` / ``"async"`` (ours also ``"auto"``)
    vectorization_mode: str = "auto"
    #: upstream 0.1.1: wrappers of the raw env, before the standard pipeline
    pre_wrappers: list[Any] = field(default_factory=list)
    #: upstream 0.1.1: PIL's resampling filter (images here are resized with OpenCV's area / linear filters)
    image_resample: Any = None
    #: seed 000: goal images of another size than the observations
    goal_shape: tuple[int, int] | None = None


def world_compat_args(kwargs: dict[str, Any]) -> WorldCompatArgs:
    """Pop the older releases' ``World`` arguments from ``kwargs`` (in place) and check them."""
    add_pixels = kwargs.pop("add_pixels", True)
    if not isinstance(add_pixels, bool):
        raise ConfigError(f"World requires add_pixels to be a bool, got {add_pixels!r}")
    return WorldCompatArgs(
        add_pixels=add_pixels,
        vectorization_mode=kwargs.pop("vectorization_mode", "auto"),
        pre_wrappers=list(kwargs.pop("pre_wrappers", None) or []),
        image_resample=kwargs.pop("image_resample", None),
        goal_shape=kwargs.pop("goal_shape", None),
    )

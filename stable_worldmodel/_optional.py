"""The one place that probes optional dependencies."""

from __future__ import annotations

import importlib
import importlib.util
from types import ModuleType

from .errors import DependencyNotInstalled

# module name -> extra that installs it
EXTRAS = {
    "nevergrad": "nevergrad",
    "mujoco": "mujoco",
    "av": "video",
    "decord": "video",
    "hypothesis": "dev",
    "transformers": "vit",
    "dm_control": "mujoco",
    "ogbench": "mujoco",
    "ray": "ray",
    "minigrid": "minigrid",
    "lance": "lance",
    # -- the env families of issue 31 insert their modules right below this line --
    "PyFlyt": "pyflyt",
    "pybullet": "pyflyt",
    "craftax": "craftax",
    "jax": "craftax",
    "gymnasium_robotics": "robotics",
    "ale_py": "ale",
}
#: env tag -> the modules its extra installs (``swm envs`` marks envs whose extra is missing)
EXTRA_MODULES = {
    "mujoco": ("mujoco", "dm_control", "ogbench"),
    "minigrid": ("minigrid",),
    # -- the env families of issue 31 insert their extras right below this line --
    "pyflyt": ("PyFlyt", "pybullet"),
    "craftax": ("craftax", "jax"),
    "robotics": ("gymnasium_robotics", "mujoco"),
    "ale": ("ale_py",),
}


def missing_extra(tags) -> str | None:
    """The extra an env with ``tags`` needs and that is not (fully) installed, else None."""
    for extra, modules in EXTRA_MODULES.items():
        if extra in tags and not all(is_available(m) for m in modules):
            return extra
    return None


def is_available(module: str) -> bool:
    """True when ``module`` can be imported (without importing it)."""
    return importlib.util.find_spec(module) is not None


def require(module: str, extra: str | None = None, purpose: str = "") -> ModuleType:
    """Import ``module`` or raise :class:`DependencyNotInstalled` with the pip command."""
    try:
        return importlib.import_module(module)
    except ImportError as exc:
        extra = extra or EXTRAS.get(module)
        target = f'"stable-worldmodel[{extra}]"' if extra else module
        why = f" for {purpose}" if purpose else ""
        raise DependencyNotInstalled(
            f"{module!r} is required{why} but is not installed. Install it with: pip install {target}"
        ) from exc

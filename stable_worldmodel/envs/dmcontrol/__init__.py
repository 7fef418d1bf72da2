"""DeepMind Control envs (``swm/<Name>DMControl-v0``) with factors of variation.

Importing this package imports nothing heavy: the env classes (one module per domain, named as
upstream 0.1.1's) and the experts resolve on first use. Behaviour and the differences from
upstream are in :mod:`.dmcontrol`; each domain module lists its factors.
"""

from __future__ import annotations

import importlib
from typing import Any

DOMAINS = {
    "Humanoid": "humanoid",
    "Cheetah": "cheetah",
    "Hopper": "hopper",
    "Reacher": "reacher",
    "Walker": "walker",
    "Acrobot": "acrobot",
    "Pendulum": "pendulum",
    "Cartpole": "cartpole",
    "BallInCup": "ball_in_cup",
    "Finger": "finger",
    "Manipulator": "manipulator",
    "Quadruped": "quadruped",
}
_LAZY = {
    **{f"{name}DMControlWrapper": module for name, module in DOMAINS.items()},
    "DMControlWrapper": "dmcontrol",
    "DMControlExpert": "expert",
    "ExpertPolicy": "expert",
}
__all__ = sorted(_LAZY)


def __getattr__(name: str) -> Any:
    if name not in _LAZY:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    return getattr(importlib.import_module(f"{__name__}.{_LAZY[name]}"), name)


def __dir__() -> list[str]:
    return sorted([*globals(), *_LAZY])

"""The world-model registry: name -> light config class (``"module:Class"`` strings, imported
on lookup). ``make(name, preset, action_dim=..., **overrides)`` builds a model."""

from __future__ import annotations

import importlib
from typing import Any

from ..errors import ConfigError, unknown_name

__all__ = ["get_config", "get_config_class", "list_models", "make", "register_model"]

_P = "stable_worldmodel.wm"
_ENTRIES: dict[str, Any] = {
    "lewm": f"{_P}.lewm.config:LeWMConfig",
    "pldm": f"{_P}.pldm.config:PLDMConfig",
    "dummy": f"{_P}.dummy_config:DummyConfig",
    "gcbc": f"{_P}.gcrl.config:GCBCConfig",
    "gcivl": f"{_P}.gcrl.config:GCIVLConfig",
    "gciql": f"{_P}.gcrl.config:GCIQLConfig",
    "prejepa": f"{_P}.prejepa.config:PreJEPAConfig",
    "dinowm": f"{_P}.prejepa.config:PreJEPAConfig",
    "frame": f"{_P}.frame.config:FrameConfig",
    "tdmpc2": f"{_P}.tdmpc2.config:TDMPC2Config",
    "dreamer": f"{_P}.dreamer.config:DreamerConfig",
}


def register_model(name: str, config_class: type | str) -> None:
    """Make ``config_class`` (a :class:`~stable_worldmodel.wm.config.JEPAConfig` subclass, or
    its ``"module:Class"`` path) available as ``make(name)`` and ``swm train name``."""
    if not isinstance(name, str) or not name or name in _ENTRIES:
        raise ConfigError(f"register_model requires a new non-empty name, got {name!r} (taken: {sorted(_ENTRIES)})")
    _ENTRIES[name] = config_class


def list_models() -> list[str]:
    """Registered world-model names."""
    return sorted(_ENTRIES)


def get_config_class(name: str) -> type:
    """The config class registered as ``name``."""
    if name not in _ENTRIES:
        raise unknown_name("world model", name, _ENTRIES)
    entry = _ENTRIES[name]
    if isinstance(entry, str):
        module, _, attr = entry.partition(":")
        entry = _ENTRIES[name] = getattr(importlib.import_module(module), attr)
    return entry


def get_config(name: str, preset: str = "tiny", **overrides: Any) -> Any:
    """The config of model ``name`` at ``preset`` with ``overrides``."""
    return get_config_class(name).from_preset(preset, **overrides)


def make(name: str, preset: str = "tiny", *, action_dim: int, **overrides: Any) -> Any:
    """Build model ``name`` (``preset`` plus ``overrides``) for env actions of ``action_dim`` numbers."""
    from .utils import instantiate

    if isinstance(action_dim, bool) or not isinstance(action_dim, int) or action_dim < 1:
        raise ConfigError(f"wm.make requires action_dim to be a positive int, got {action_dim!r}")
    return instantiate(get_config(name, preset, **overrides).target_tree(action_dim))

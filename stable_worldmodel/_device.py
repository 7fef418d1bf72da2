"""Choosing the torch device of training, planning and evaluation (torch imported when called)."""

from __future__ import annotations

from typing import Any

from .errors import ConfigError

__all__ = ["resolve_device"]


def resolve_device(device: Any = "auto", who: str = "Training") -> Any:
    """``auto`` -> cuda when available, else mps, else cpu; other names (``cpu``, ``cuda``,
    ``cuda:N``, ``mps``, a ``torch.device``) are checked: a device torch cannot use is a
    :class:`~stable_worldmodel.errors.ConfigError` naming ``who`` needs it and what to use instead."""
    import torch

    if str(device) == "auto":
        if torch.cuda.is_available():
            return torch.device("cuda")
        if getattr(torch.backends, "mps", None) is not None and torch.backends.mps.is_available():
            return torch.device("mps")
        return torch.device("cpu")
    try:
        dev = torch.device(device)
    except (RuntimeError, TypeError) as exc:
        raise ConfigError(f"{who} requires a device among auto, cpu, cuda, cuda:N, mps, got {device!r}") from exc
    if dev.type == "cuda" and not torch.cuda.is_available():
        raise ConfigError(
            f"{who} requires an available device, got {device!r} but torch sees no CUDA GPU; use --device auto or cpu"
        )
    if dev.type == "mps" and not (getattr(torch.backends, "mps", None) and torch.backends.mps.is_available()):
        raise ConfigError(f"{who} requires an available device, got {device!r} but MPS is not available")
    return dev

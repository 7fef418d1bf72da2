"""Load a pickled model from the cache and pick the sub-module that plans or acts."""

from __future__ import annotations

import logging
from pathlib import Path
from typing import Any

from ..errors import ConfigError, UnknownNameError, did_you_mean

logger = logging.getLogger(__name__)

__all__ = ["AutoActionableModel", "AutoCostModel", "list_model_checkpoints", "model_cache_dir"]

SUFFIX = "_object.ckpt"


def model_cache_dir(cache_dir: str | Path | None = None) -> Path:
    """``cache_dir`` or the package cache (``$STABLEWM_HOME``, else ``~/.stable_worldmodel``)."""
    if cache_dir is not None:
        return Path(cache_dir).expanduser()
    from ..data import get_cache_dir

    return get_cache_dir()


def list_model_checkpoints(cache_dir: str | Path | None = None) -> list[str]:
    """Names that :func:`AutoCostModel` accepts: ``<name>_object.ckpt`` files and folders holding some."""
    root = model_cache_dir(cache_dir)
    if not root.is_dir():
        return []
    names = {p.name[: -len(SUFFIX)] for p in root.glob(f"*{SUFFIX}")}
    names |= {p.name for p in root.iterdir() if p.is_dir() and any(p.rglob(f"*{SUFFIX}"))}
    return sorted(names)


def _checkpoint_path(model_name: str | Path, cache_dir: str | Path | None) -> Path:
    root = model_cache_dir(cache_dir)
    path = Path(model_name).expanduser()
    path = path if path.is_absolute() else root / path
    if path.is_file():
        return path
    candidates = [Path(f"{path}{SUFFIX}")] if Path(f"{path}{SUFFIX}").is_file() else []
    if path.is_dir():
        candidates += list(path.rglob(f"*{SUFFIX}"))
    if not candidates:
        available = list_model_checkpoints(root)
        raise UnknownNameError(
            f"Model loading requires {path}{SUFFIX} or a folder of *{SUFFIX}, got {str(model_name)!r}."
            f"{did_you_mean(str(model_name), available)} Available in {root}: {', '.join(available) or '(none)'}"
        )
    return max(candidates, key=lambda p: p.stat().st_mtime)


def _find_module(obj: Any, method: str) -> Any:
    """``obj`` itself or its first sub-module (depth-first) with a callable ``method``."""
    if callable(getattr(obj, method, None)):
        return obj
    import torch

    if isinstance(obj, torch.nn.Module):
        for module in obj.modules():
            if callable(getattr(module, method, None)):
                return module
    return None


def _load_with(model_name: str | Path, method: str, cache_dir: str | Path | None) -> Any:
    import torch

    path = _checkpoint_path(model_name, cache_dir)
    logger.info("loading %s from %s", method, path)
    map_location = None if torch.cuda.is_available() else "cpu"
    obj = torch.load(path, map_location=map_location, weights_only=False)
    module = _find_module(obj, method)
    if module is None:
        raise ConfigError(f"Auto model loading requires a module with {method}() in {path}, got {type(obj).__name__}")
    if isinstance(module, torch.nn.Module):
        module.eval()
    return module


def AutoCostModel(model_name: str | Path, cache_dir: str | Path | None = None) -> Any:  # noqa: N802 (seed name)
    """Load the newest ``<cache>/<model_name>_object.ckpt`` and return its module with ``get_cost``.

    ``model_name`` may also be a checkpoint file, or a folder (absolute or under the
    cache) searched for ``*_object.ckpt``; the newest file wins. The checkpoint is a whole
    pickled module (``torch.load(weights_only=False)``): unpickling runs arbitrary code,
    so only load files you trust. The module found (the object itself or its first
    sub-module with ``get_cost``) is put in eval mode.
    """
    return _load_with(model_name, "get_cost", cache_dir)


def AutoActionableModel(model_name: str | Path, cache_dir: str | Path | None = None) -> Any:  # noqa: N802
    """Like :func:`AutoCostModel`, returning the module with ``get_action`` (for FeedForwardPolicy).

    Only load trusted files: the checkpoint is unpickled with ``weights_only=False``.
    """
    return _load_with(model_name, "get_action", cache_dir)

"""Load a world model from the cache and pick the sub-module that plans or acts.

Two layouts are understood, the first that matches wins:

    <cache>/checkpoints/<run>/              a checkpoint folder (see :mod:`stable_worldmodel.wm.utils`):
        weights.pt  config.json  [protocol.json]   state_dict + ``_target_`` tree, rebuilt without pickle
    <cache>/checkpoints/models--<user>--<repo>/    the same, named ``<user>/<repo>`` (else the Hugging Face
                                            cache's snapshot of it, see ``resolve_checkpoint``)
    <cache>/<name>_object.ckpt              older runs: a whole pickled module (or a folder holding one)
"""

from __future__ import annotations

import logging
from pathlib import Path
from typing import Any

from ..errors import ConfigError, UnknownNameError, did_you_mean
from ..wm.trust import PICKLE_ENV, pickles_refused

logger = logging.getLogger(__name__)

__all__ = [
    "AutoActionableModel",
    "AutoCostModel",
    "MissingAttributeError",
    "list_model_checkpoints",
    "model_cache_dir",
]

SUFFIX = "_object.ckpt"


class MissingAttributeError(ConfigError, RuntimeError):
    """A loaded checkpoint in which no module has the requested method or attribute.

    A :class:`~stable_worldmodel.errors.ConfigError` (so a ``ValueError``) and, as the original
    release documented for ``AutoCostModel``/``AutoActionableModel``, a ``RuntimeError``.
    """


def model_cache_dir(cache_dir: str | Path | None = None) -> Path:
    """``cache_dir`` or the package cache (``$STABLEWM_HOME``, else ``~/.stable_worldmodel``)."""
    if cache_dir is not None:
        return Path(cache_dir).expanduser()
    from ..data import get_cache_dir

    return get_cache_dir()


def _pickles_in(folder: Path) -> list[Path]:
    return sorted(p for p in folder.glob(f"*{SUFFIX}") if p.is_file())


def _pickled_names(root: Path) -> set[str]:
    """``<name>`` of every ``<name>_object.ckpt`` in ``root``, and folders holding exactly one (not searched deeper)."""
    names = {p.name[: -len(SUFFIX)] for p in _pickles_in(root)}
    return names | {p.name for p in root.iterdir() if p.is_dir() and len(_pickles_in(p)) == 1}


def list_model_checkpoints(cache_dir: str | Path | None = None) -> list[str]:
    """Names that :func:`AutoCostModel` accepts: checkpoint folders under ``checkpoints/`` (as
    their path relative to it), ``<name>_object.ckpt`` files and folders holding some."""
    from ..wm.utils import list_checkpoints

    root = model_cache_dir(cache_dir)
    if not root.is_dir():
        return []
    return sorted(_pickled_names(root) | set(list_checkpoints(root)))


def _new_layout_weights(model_name: str | Path, root: Path) -> Path | None:
    """The weights file of ``model_name`` in the checkpoint-folder layout, or None when it is not one."""
    from ..wm.utils import CONFIG_NAME, resolve_checkpoint

    try:
        weights = resolve_checkpoint(model_name, root)
    except FileNotFoundError:
        return None
    if not (weights.parent / CONFIG_NAME).is_file():
        logger.debug("%s has no %s beside it: not a loadable checkpoint folder", weights, CONFIG_NAME)
        return None
    return weights


def _pickled_path(model_name: str | Path, root: Path) -> Path | None:
    """The one pickled checkpoint ``model_name`` names, or None.

    In order: a file (absolute, or relative to ``root``), ``<root>/<name>_object.ckpt``, or a
    folder holding exactly one ``*_object.ckpt`` (several: an error asking which). Nothing is
    searched below that, and no "newest file" is guessed.
    """
    path = Path(model_name).expanduser()
    path = path if path.is_absolute() else root / path
    if path.is_file():
        return path
    if Path(f"{path}{SUFFIX}").is_file():
        return Path(f"{path}{SUFFIX}")
    if path.is_dir():
        found = _pickles_in(path)
        if len(found) > 1:
            raise ConfigError(
                f"AutoCostModel requires one checkpoint, got {len(found)} *{SUFFIX} files in {path}: "
                f"{', '.join(p.name for p in found)}; pass the file you mean"
            )
        return found[0] if found else None
    return None


def _load_pickle(path: Path, caller: str, allow_pickle: bool | None) -> Any:
    """Unpickle the module in ``path`` (it can run code: warned, or refused by the setting)."""
    import warnings

    import torch

    if allow_pickle is None:
        allow_pickle = not pickles_refused()
    if not allow_pickle:
        raise ConfigError(
            f"{caller} refuses pickled checkpoints ({PICKLE_ENV} is set or allow_pickle=False), got {path}; "
            "save the model with stable_worldmodel.wm.utils.save_pretrained to load it without pickle"
        )
    warnings.warn(
        f"{path} is a pickled checkpoint: loading it runs code stored in the file; load only files you trust "
        f"(set {PICKLE_ENV}=1 to refuse pickles)",
        UserWarning,
        stacklevel=4,
    )
    map_location = None if torch.cuda.is_available() else "cpu"
    try:
        return torch.load(path, map_location=map_location, weights_only=False)
    except (AttributeError, ModuleNotFoundError, ImportError) as exc:
        what = getattr(exc, "name", None)
        raise ConfigError(
            f"{caller} requires the classes pickled in {path} to be importable, got {type(exc).__name__}: {exc}"
            + (f" (module {what!r})" if what else "")
            + "; install or import the package that defines them"
        ) from exc


def _unknown(caller: str, model_name: str | Path, root: Path) -> UnknownNameError:
    from ..wm.utils import CONFIG_NAME, WEIGHTS_NAME, checkpoint_root, hf_hub_cache

    ckpts = checkpoint_root(root)
    available = list_model_checkpoints(root)
    name = str(model_name)
    orphan = ""
    weights = Path(model_name).expanduser()
    weights = weights if weights.is_absolute() else ckpts / weights
    if weights.is_dir() and (weights / WEIGHTS_NAME).is_file():
        orphan = f" {weights} holds {WEIGHTS_NAME} but no {CONFIG_NAME}: save it with save_pretrained(..., config=...)."
    return UnknownNameError(
        f"{caller} requires a checkpoint folder {ckpts}/<run>/ ({WEIGHTS_NAME} + {CONFIG_NAME}), a .pt file with a "
        f"{CONFIG_NAME} beside it, <user>/<repo>[@<revision>] in {ckpts}/models--<user>--<repo>/ or in the Hugging "
        f"Face cache {hf_hub_cache()}/models--<user>--<repo>/snapshots/ (nothing is downloaded: "
        "stable_worldmodel.wm.utils.from_pretrained downloads), "
        f"or a pickled {root}/<name>{SUFFIX} (or a folder of *{SUFFIX}), got {name!r}.{orphan}"
        f"{did_you_mean(name, available)} Available in {root}: {', '.join(available) or '(none)'}"
    )


def _find_module(obj: Any, method: str, *, need_callable: bool = True) -> Any:
    """``obj`` itself or its first sub-module (depth-first) with ``method``
    (callable, unless ``need_callable=False``)."""

    def has(candidate: Any) -> bool:
        return callable(getattr(candidate, method, None)) if need_callable else hasattr(candidate, method)

    if has(obj):
        return obj
    import torch

    if isinstance(obj, torch.nn.Module):
        for module in obj.modules():
            if has(module):
                return module
    return None


def _load_with(
    caller: str,
    model_name: str | Path,
    method: str,
    cache_dir: str | Path | None,
    allow_pickle: bool | None,
    *,
    need_callable: bool = True,
    trusted_targets: Any = None,
) -> Any:
    import torch

    root = model_cache_dir(cache_dir)
    weights = _new_layout_weights(model_name, root)
    if weights is not None:
        from ..wm.run import Run

        logger.info("loading %s from %s", method, weights)
        obj = Run.open(weights, root).load_model(trusted_targets=trusted_targets)
        path = weights
    else:
        path = _pickled_path(model_name, root)
        if path is None:
            raise _unknown(caller, model_name, root)
        logger.info("loading %s from %s", method, path)
        obj = _load_pickle(path, caller, allow_pickle)
    module = _find_module(obj, method, need_callable=need_callable)
    if module is None:
        hint = " (a state_dict: put the config.json of its model beside it)" if isinstance(obj, dict) else ""
        what = f"{method}()" if need_callable else repr(method)
        raise MissingAttributeError(
            f"{caller} requires a module with {what} in {path}, got {type(obj).__name__}{hint}. "
            f"No module with '{method}' found in the loaded world model."
        )
    if isinstance(module, torch.nn.Module):
        module.eval()
    return module


def AutoCostModel(  # noqa: N802 (seed name)
    model_name: str | Path,
    cache_dir: str | Path | None = None,
    *,
    allow_pickle: bool | None = None,
    trusted_targets: Any = None,
) -> Any:
    """Load model ``model_name`` from the cache and return its module with ``get_cost`` (in eval mode).

    ``model_name`` is tried first as a checkpoint of :mod:`stable_worldmodel.wm.utils` (a run
    folder under ``<cache>/checkpoints/``, a ``.pt`` file with a ``config.json`` beside it, or
    ``<user>/<repo>``): the model is rebuilt from ``config.json`` and its weights loaded on the
    CPU (``weights_only=True``). Otherwise it is an older whole pickled module: a checkpoint
    file, ``<cache>/<model_name>_object.ckpt``, or a folder holding exactly one
    ``*_object.ckpt`` (see :func:`_pickled_path`). Unpickling runs code stored in the file:
    it warns, naming the file, and ``allow_pickle=False`` (or ``STABLEWM_REFUSE_PICKLE=1``)
    refuses it. ``config.json`` may only build trusted ``_target_`` names
    (:mod:`stable_worldmodel.wm.trust`); ``trusted_targets`` adds prefixes. The module returned is
    the object itself or its first sub-module with ``get_cost``; when there is none,
    :class:`MissingAttributeError` (a ``RuntimeError`` and a ``ConfigError``).
    """
    return _load_with("AutoCostModel", model_name, "get_cost", cache_dir, allow_pickle, trusted_targets=trusted_targets)


def AutoActionableModel(  # noqa: N802 (seed name)
    model_name: str | Path,
    cache_dir: str | Path | None = None,
    *,
    allow_pickle: bool | None = None,
    trusted_targets: Any = None,
) -> Any:
    """Like :func:`AutoCostModel`, returning the module with ``get_action`` (for FeedForwardPolicy)."""
    return _load_with(
        "AutoActionableModel", model_name, "get_action", cache_dir, allow_pickle, trusted_targets=trusted_targets
    )


def _load_model_with_attribute(
    run_name: str | Path, attribute_name: str, cache_dir: str | Path | None = None, *, allow_pickle: bool | None = None
) -> Any:
    """Load checkpoint ``run_name`` and return its first module that has ``attribute_name`` (in eval mode).

    The helper behind :func:`AutoCostModel` and :func:`AutoActionableModel` (seed 000's name):
    ``run_name`` is resolved like there, and the checkpoint object itself, then its sub-modules
    depth-first, are searched for the attribute (any attribute, not only methods). Raises
    :class:`MissingAttributeError` (a ``RuntimeError``) when no module has it.
    """
    return _load_with(
        "_load_model_with_attribute", run_name, attribute_name, cache_dir, allow_pickle, need_callable=False
    )

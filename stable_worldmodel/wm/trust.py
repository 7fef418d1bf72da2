"""Which ``_target_`` names a checkpoint's ``config.json`` may call.

A ``_target_`` tree is code: ``{"_target_": "os.system", "_args_": ["..."]}`` would run a
command the moment it is built. Before anything in a tree is called, every ``_target_`` in it
(``_args_``, ``_partial_`` and nested trees included) is checked here, the way transformers
gates ``trust_remote_code``. Without being told otherwise a tree may build:

- ``stable_worldmodel.…``: ``torch.nn.Module`` classes, and the factories marked
  :func:`checkpoint_factory` (``vit_hf``, ``create_backbone``);
- the upstream names mapped to ours (:data:`stable_worldmodel.wm.utils.TARGET_ALIASES`,
  ``stable_pretraining.…``);
- ``torch.nn.…``: ``torch.nn.Module`` classes and the functions of ``torch.nn.functional``;
- ``transformers.…``: model and config classes (``ViTModel``, ``ViTConfig``, ...), never their
  methods (``from_pretrained`` could fetch or run remote code).

More is trusted only when asked: ``trusted_targets=("mylab.models.",)`` on the loading call,
or ``STABLEWM_TRUSTED_TARGETS=mylab.models.,otherlab.`` in the environment. A trusted prefix
admits any callable defined in that package. Anything else is an
:class:`~stable_worldmodel.errors.UntrustedCheckpointError` naming the file, the key path of the
entry and the target, raised before any target is imported or called.
"""

from __future__ import annotations

import importlib
import inspect
import os
from collections.abc import Callable, Iterable, Mapping
from typing import Any

from ..errors import ConfigError, UnknownNameError, UntrustedCheckpointError

__all__ = ["PICKLE_ENV", "TRUSTED_ENV", "checkpoint_factory", "pickles_refused", "resolve_targets", "trusted_prefixes"]

TRUSTED_ENV = "STABLEWM_TRUSTED_TARGETS"
#: set to 1 to refuse every pickle (``*_object.ckpt`` modules, train states written before format 1)
PICKLE_ENV = "STABLEWM_REFUSE_PICKLE"
_OURS, _TORCH_NN, _TRANSFORMERS = "stable_worldmodel.", "torch.nn.", "transformers."
BUILTIN_PREFIXES = (_OURS, _TORCH_NN, _TRANSFORMERS)
_FACTORY_FLAG = "__swm_checkpoint_factory__"


def pickles_refused() -> bool:
    """Whether ``$STABLEWM_REFUSE_PICKLE`` asks to refuse every pickled file."""
    return os.environ.get(PICKLE_ENV, "").strip().lower() in ("1", "true", "yes")


def checkpoint_factory(fn: Callable) -> Callable:
    """Mark a function of ours as callable from a checkpoint's ``_target_`` (it builds a module
    from plain arguments and has no other effect)."""
    setattr(fn, _FACTORY_FLAG, True)
    return fn


def trusted_prefixes(extra: Iterable[str] | str | None = None) -> tuple[str, ...]:
    """The prefixes a caller trusts beyond the built-in ones: ``extra`` plus ``$STABLEWM_TRUSTED_TARGETS``
    (comma-separated). A prefix without a trailing dot trusts that package (``mylab`` -> ``mylab.``)."""
    if isinstance(extra, str):
        extra = [extra]
    items = list(extra or []) + os.environ.get(TRUSTED_ENV, "").split(",")
    out = []
    for item in items:
        if not isinstance(item, str):
            raise ConfigError(f"trusted_targets requires dotted prefixes (str), got {item!r}")
        item = item.strip()
        if item:
            out.append(item if item.endswith(".") else item + ".")
    return tuple(dict.fromkeys(out))


def _key_path(path: tuple) -> str:
    text = ""
    for part in path:
        text += f"[{part}]" if isinstance(part, int) else (f".{part}" if text else str(part))
    return text or "(top level)"


class _Gate:
    def __init__(self, source: str | os.PathLike | None, trusted: tuple[str, ...], aliases: Mapping[str, str]):
        self.source = str(source) if source is not None else "the config"
        self.trusted = trusted
        self.aliases = aliases
        self.resolved: dict[str, Callable] = {}

    def refuse(self, target: str, path: tuple, why: str) -> UntrustedCheckpointError:
        root = target.split(".")[0]
        return UntrustedCheckpointError(
            f"{self.source} asks to call {target!r} at key {_key_path(path)}, which a checkpoint may not call ({why}); "
            f"nothing was imported or called. A checkpoint may build torch.nn modules, stable_worldmodel modules and "
            f"transformers models. If you trust the author of this file, pass trusted_targets=({root + '.'!r},) to "
            f"load_pretrained / AutoCostModel, or set {TRUSTED_ENV}={root}."
        )

    def walk(self, node: Any, path: tuple = ()) -> None:
        if isinstance(node, Mapping):
            if "_target_" in node:
                self.check(node, path)
            for key, value in node.items():
                if key != "_target_":
                    self.walk(value, path + (key,))
        elif isinstance(node, (list, tuple)):
            for i, value in enumerate(node):
                self.walk(value, path + (i,))

    def check(self, node: Mapping, path: tuple) -> None:
        target = node["_target_"]
        if not isinstance(target, str) or not target:
            raise ConfigError(
                f"{self.source} requires _target_ to be a dotted name at key {_key_path(path)}, got {target!r}"
            )
        partial = node.get("_partial_", False)
        if not isinstance(partial, bool):
            raise ConfigError(
                f"{self.source} requires _partial_ to be true or false at key {_key_path(path)}, got {partial!r}"
            )
        if not isinstance(node.get("_args_", []), (list, tuple)):
            raise ConfigError(
                f"{self.source} requires _args_ to be a list at key {_key_path(path)}, got {node['_args_']!r}"
            )
        if target not in self.resolved:
            self.resolved[target] = self.resolve(target, path)

    def resolve(self, target: str, path: tuple) -> Callable:
        name = self.aliases.get(target, target)
        parts = name.split(".")
        if any(not p.isidentifier() or p.startswith("__") for p in parts):
            raise self.refuse(target, path, "not a plain dotted name")
        user = next((p for p in self.trusted if name.startswith(p)), None)
        builtin = next((p for p in BUILTIN_PREFIXES if name.startswith(p)), None)
        if user is None and builtin is None:
            raise self.refuse(
                target, path, "outside the trusted prefixes " + ", ".join(BUILTIN_PREFIXES + self.trusted)
            )
        obj = _locate(name, target)
        if user is not None:
            ok = _defined_under(obj, user.split(".")[0] + ".") and callable(obj)
        else:
            ok = _builtin_allows(builtin, name, obj)
        if not ok:
            raise self.refuse(target, path, f"it resolves to {_describe(obj)}, not a module class or model factory")
        return obj


def _locate(name: str, target: str) -> Any:
    parts = name.split(".")
    for cut in range(len(parts) - 1, 0, -1):
        try:
            obj = importlib.import_module(".".join(parts[:cut]))
        except ImportError:
            continue
        try:
            for attr in parts[cut:]:
                obj = getattr(obj, attr)
        except AttributeError:
            break
        return obj
    raise UnknownNameError(f"instantiate requires an importable _target_, got {target!r}")


def _defined_under(obj: Any, prefix: str) -> bool:
    module = getattr(obj, "__module__", None) or ""
    return (module + ".").startswith(prefix)


def _describe(obj: Any) -> str:
    kind = "class" if inspect.isclass(obj) else type(obj).__name__
    return f"{kind} {getattr(obj, '__module__', '?')}.{getattr(obj, '__qualname__', obj)!s}"


#: the pure-function namespaces of torch.nn whose functions a tree may name (e.g. an activation with ``_partial_``)
_TORCH_FUNCTION_MODULES = ("torch.nn.functional", "torch.nn.init")


def _builtin_allows(prefix: str, name: str, obj: Any) -> bool:
    import torch

    is_module_class = inspect.isclass(obj) and issubclass(obj, torch.nn.Module)
    if prefix == _OURS:
        return _defined_under(obj, _OURS) and (is_module_class or getattr(obj, _FACTORY_FLAG, False) is True)
    if prefix == _TORCH_NN:
        if is_module_class:
            return _defined_under(obj, "torch.")
        where, _, leaf = name.rpartition(".")
        return (
            where in _TORCH_FUNCTION_MODULES
            and inspect.isroutine(obj)
            and _defined_under(obj, "torch")
            and not leaf.startswith("_")
        )
    if prefix == _TRANSFORMERS:
        if not (inspect.isclass(obj) and _defined_under(obj, _TRANSFORMERS)):
            return False
        import transformers

        bases = tuple(
            b
            for b in (getattr(transformers, "PreTrainedModel", None), getattr(transformers, "PretrainedConfig", None))
            if b
        )
        return issubclass(obj, bases)
    return False


def resolve_targets(
    tree: Any,
    *,
    source: str | os.PathLike | None = None,
    trusted_targets: Iterable[str] | str | None = None,
    aliases: Mapping[str, str] | None = None,
) -> dict[str, Callable]:
    """Check every ``_target_`` of ``tree`` against the trusted prefixes and return ``{target: callable}``.

    Raises :class:`~stable_worldmodel.errors.UntrustedCheckpointError` on the first target that may
    not be called (naming ``source``, the key path and the target); nothing of ``tree`` is called.
    """
    gate = _Gate(source, trusted_prefixes(trusted_targets), aliases or {})
    gate.walk(tree)
    return gate.resolved

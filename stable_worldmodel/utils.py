"""Small helpers: nested-dict access, launching a pretraining script, dataset videos.

``pretraining`` is the one place where the library calls ``sys.exit``: seed 000 documents
that it exits with the child's return code when the script fails (kept for compatibility).
"""

from __future__ import annotations

import logging
import os
import shlex
import subprocess
import sys
from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import Any

from . import keys
from .errors import ConfigError, UnknownNameError, did_you_mean

logger = logging.getLogger(__name__)

__all__ = ["flatten_dict", "get_in", "pretraining", "record_video_from_dataset"]


def flatten_dict(d: Mapping, parent_key: str = "", sep: str = ".") -> dict[str, Any]:
    """Flatten a nested mapping into one level, joining keys with ``sep`` (Hydra style).

    Keys that are not strings are formatted with f-strings; an empty nested mapping
    contributes no key. Overlapping flattened keys keep the value seen last.

    >>> info = {"a": {"b": {"c": 42, "d": 43}}, "e": 44}
    >>> flatten_dict(info)
    {'a.b.c': 42, 'a.b.d': 43, 'e': 44}
    >>> flatten_dict({"a": {"b": 2}, "a.b": 3})
    {'a.b': 3}
    """
    out: dict[str, Any] = {}
    for key, value in d.items():
        name = f"{parent_key}{sep}{key}" if parent_key else f"{key}"
        if isinstance(value, Mapping):
            out.update(flatten_dict(value, name, sep))
        else:
            out[name] = value
    return out


def get_in(mapping: Mapping, path: Iterable[Any]) -> Any:
    """The value at ``path`` (a sequence of keys) inside nested ``mapping``; ``get_in(d, [])`` is ``d``.

    Raises KeyError (an :class:`~stable_worldmodel.errors.UnknownNameError`) naming the missing
    key and the path.

    >>> variations = {"a": {"b": {"c": 42}}}
    >>> get_in(variations, ["a", "b", "c"])
    42
    """
    path = list(path)
    node: Any = mapping
    for depth, key in enumerate(path):
        if not isinstance(node, Mapping) or key not in node:
            where = path[:depth]
            have = list(node) if isinstance(node, Mapping) else []
            got = f"keys {have}" if isinstance(node, Mapping) else f"a {type(node).__name__}"
            hint = did_you_mean(str(key), [str(k) for k in have])
            raise UnknownNameError(f"get_in requires key {key!r} at {where} of path {path}, got {got}.{hint}")
        node = node[key]
    return node


def pretraining(
    script_path: str,
    dataset_name: str,
    output_model_name: str,
    dump_object: bool = True,
    args: str = "",
) -> int:
    """Run a (Hydra) pretraining script in a subprocess with the current interpreter.

    The command is ``[python, script_path, *shlex.split(args), "++dump_object=<bool>",
    "dataset_name=<...>", "output_model_name=<...>"]`` (a name with spaces stays one argument,
    where 0.0.3 split it), with ``PYTHONUNBUFFERED=1`` unless set. Returns 0 on success.

    Raises ConfigError (a ValueError) when ``script_path`` is not a file. When the script
    fails, calls ``sys.exit`` with its return code (SystemExit), as seed 000 specifies.
    """
    script = Path(script_path)
    if not script.is_file():
        raise ConfigError(f"pretraining requires an existing script file, got {str(script_path)!r}")
    cmd = [
        sys.executable,
        str(script),
        *shlex.split(args),
        f"++dump_object={bool(dump_object)}",
        f"dataset_name={dataset_name}",
        f"output_model_name={output_model_name}",
    ]
    logger.info("pretraining: %s", shlex.join(cmd))
    env = os.environ.copy()
    env.setdefault("PYTHONUNBUFFERED", "1")  # the script's prints reach a log as they happen (as 0.0.3)
    try:
        subprocess.run(cmd, check=True, env=env)
    except subprocess.CalledProcessError as exc:
        logger.error("pretraining script %s failed with return code %d", script, exc.returncode)
        sys.exit(exc.returncode)
    return 0


def record_video_from_dataset(
    video_path: str | Path,
    dataset: Any,
    episode_idx: int | list[int],
    max_steps: int = 500,
    fps: int = 30,
    viewname: str | list[str] = keys.PIXELS,
) -> Any:
    """Write the frames of stored episode(s) to video; see ``stable_worldmodel.data.video``."""
    from .data.video import record_video_from_dataset as _impl

    return _impl(video_path, dataset, episode_idx, max_steps=max_steps, fps=fps, viewname=viewname)

"""Cache management and metadata: datasets, model checkpoints, worlds."""

from __future__ import annotations

import functools
import logging
import os
import re
import shutil
from pathlib import Path
from typing import Any, TypedDict

import numpy as np

from ..errors import ConfigError, did_you_mean, unknown_name
from .utils import DATASETS_SUBFOLDER, dataset_candidates, get_cache_dir, resolve_dataset

logger = logging.getLogger(__name__)

_MODEL_FILE = re.compile(r"^(?P<name>.+?)(?:_weights.*|_object)\.ckpt$")


class SpaceInfo(TypedDict, total=False):
    """Metadata of a Gymnasium space."""

    shape: tuple[int, ...]
    type: str
    dtype: str
    low: Any
    high: Any
    n: int


class VariationInfo(TypedDict):
    """Factors of variation of a world."""

    has_variation: bool
    type: str | None
    names: list[str] | None


class WorldInfo(TypedDict):
    """Metadata of a world (registered environment)."""

    name: str
    observation_space: SpaceInfo
    action_space: SpaceInfo
    variation: VariationInfo
    config: dict[str, Any]


def is_image(x: Any) -> bool:
    """True for a uint8 numpy array ``(H, W, C)`` with C in 1, 3, 4."""
    from .writer import is_image_column

    return isinstance(x, np.ndarray) and x.ndim == 3 and is_image_column(x.shape, x.dtype)


# -- datasets ----------------------------------------------------------------------------------
def _dataset_dirs(root: Path) -> list[Path]:
    """Folders directly in the cache (and in its ``datasets/``) that a registered format recognises."""
    from .format import detect_format

    found = []
    for base in (root, root / DATASETS_SUBFOLDER):
        if not base.is_dir():
            continue
        for path in sorted(base.iterdir()):
            if (
                path.is_dir()
                and not _hidden(path, root)
                and path != root / DATASETS_SUBFOLDER
                and detect_format(path) is not None
            ):
                found.append(path)
    return found


def list_datasets(cache_dir: str | os.PathLike | None = None) -> list[str]:
    """Names of the datasets in the cache (or ``cache_dir``): ``<name>.h5`` files and dataset
    folders of any registered format."""
    root = Path(cache_dir).expanduser() if cache_dir is not None else get_cache_dir()
    if not root.is_dir():
        return []
    dirs = {p.relative_to(root).as_posix() for p in _dataset_dirs(root)}
    names = {
        p.relative_to(root).with_suffix("").as_posix()
        for p in root.rglob("*.h5")
        if p.is_file() and not _hidden(p, root) and not _is_shard(p, dirs, root)
    }
    return sorted(names | dirs)


def list_dataset_shards() -> list[str]:
    """Names of the shards of the sharded datasets in the cache (``<name>/shard_00000`` ...): each
    can be shown or read on its own; :func:`list_datasets` lists their folder."""
    root = get_cache_dir()
    return sorted(
        p.relative_to(root).with_suffix("").as_posix()
        for d in _dataset_dirs(root)
        for p in d.glob("shard_*.h5")
        if p.is_file()
    )


def _is_shard(path: Path, dirs: set[str], root: Path) -> bool:
    """A ``shard_*.h5`` of a sharded dataset folder (listed as the folder)."""
    return path.name.startswith("shard_") and path.parent.relative_to(root).as_posix() in dirs


def leftover_partials() -> list[Path]:
    """``.<name>.h5.partial`` files of first recordings that were killed (none is being written now).

    They hold no committed episode (a new file is renamed into place once valid); a later
    recording of the same name replaces them, :func:`delete_dataset` removes them.
    """
    from ..errors import DatasetBusyError
    from ._lock import WriterLock

    root = get_cache_dir()
    found = []
    for path in sorted(root.rglob(".*.h5.partial")):
        final = path.with_name(path.name[1 : -len(".partial")])
        try:
            WriterLock(final).acquire().release()
        except DatasetBusyError:
            continue  # a recording is creating it right now
        found.append(path)
    return found


def _hidden(path: Path, root: Path) -> bool:
    """Under a folder or named with a leading dot (partial files, locks), or under checkpoints/."""
    parts = path.relative_to(root).parts
    return any(p.startswith(".") for p in parts) or parts[0] == "checkpoints"


def dataset_info(name: str) -> dict[str, Any]:
    """Metadata of cached dataset ``name``: name, path, format, num_episodes, num_steps,
    columns, obs_shape, action_shape, goal_shape, variation, episode lengths summary
    (the ``summary`` of its :class:`~.format.Format`)."""
    from ..errors import DatasetFormatError
    from .format import detect_format, list_formats

    path = resolve_dataset(name, who="dataset_info")
    fmt = detect_format(path)
    if fmt is None:
        raise DatasetFormatError(
            f"dataset_info requires a dataset in a registered format ({', '.join(list_formats())}), got {str(path)!r}"
        )
    return {"name": name, **fmt.summary(path)}


def delete_dataset(name: str) -> Path:
    """Delete cached dataset ``name`` (its ``.h5`` file or directory); returns the removed path."""
    for path in dataset_candidates(name):  # in the cache only: never a folder that a relative path names
        if path.is_file():
            path.unlink()
            for leftover in ("partial", "redo"):  # a killed writer's unfinished file and redo record
                path.with_name(f".{path.name}.{leftover}").unlink(missing_ok=True)
            logger.info("Deleted dataset %s", path)
            return path
        if path.is_dir():
            shutil.rmtree(path)
            logger.info("Deleted dataset %s", path)
            return path
    raise unknown_name("dataset", name, list_datasets())


# -- models ------------------------------------------------------------------------------------
def _model_files() -> dict[str, list[Path]]:
    out: dict[str, list[Path]] = {}
    for path in get_cache_dir().rglob("*.ckpt"):
        match = _MODEL_FILE.match(path.name)
        if match:
            out.setdefault(match["name"], []).append(path)
    return out


def list_models() -> list[str]:
    """Names of cached checkpoints (``<name>_weights*.ckpt`` or ``<name>_object.ckpt``), sorted."""
    return sorted(_model_files())


def delete_model(name: str) -> list[Path]:
    """Delete every checkpoint file of model ``name``; returns the removed paths."""
    files = _model_files().get(name)
    if not files:
        raise unknown_name("model", name, list_models())
    for path in files:
        path.unlink()
        logger.info("Deleted %s", path)
    return files


# -- worlds ------------------------------------------------------------------------------------
def list_worlds() -> list[str]:
    """Registered ``swm/...`` world ids, sorted."""
    from ..envs._registry import list_envs

    return sorted(list_envs())


def space_info(space: Any) -> SpaceInfo:
    """:class:`SpaceInfo` of a Gymnasium space."""
    info: SpaceInfo = {"type": type(space).__name__, "shape": tuple(getattr(space, "shape", None) or ())}
    dtype = getattr(space, "dtype", None)
    if dtype is not None:
        info["dtype"] = str(dtype)
    for attr in ("low", "high"):
        if hasattr(space, attr):
            info[attr] = np.asarray(getattr(space, attr)).tolist()
    if hasattr(space, "n"):
        info["n"] = np.asarray(space.n).tolist()
    if hasattr(space, "spaces") and isinstance(space.spaces, dict):
        info["spaces"] = {k: space_info(v) for k, v in space.spaces.items()}  # type: ignore[typeddict-unknown-key]
    return info


@functools.lru_cache(maxsize=64)
def _world_info(name: str, image_shape: tuple[int, int], render_mode: str) -> WorldInfo:
    import gymnasium as gym

    if name not in list_worlds():
        raise ConfigError(f"world_info requires a registered world, got {name!r}.{did_you_mean(name, list_worlds())}")
    env = gym.make(name, render_mode=render_mode)
    try:
        base = env.unwrapped
        if hasattr(base, "set_render_size"):
            base.set_render_size(image_shape)
        space = getattr(base, "variation_space", None)
        variation: VariationInfo = {
            "has_variation": space is not None,
            "type": type(space).__name__ if space is not None else None,
            "names": list(space.names()) if space is not None and hasattr(space, "names") else None,
        }
        return {
            "name": name,
            "observation_space": space_info(env.observation_space),
            "action_space": space_info(env.action_space),
            "variation": variation,
            "config": {
                "image_shape": tuple(image_shape),
                "render_mode": render_mode,
                "max_episode_steps": env.spec.max_episode_steps if env.spec else None,
            },
        }
    finally:
        env.close()


def world_info(name: str, *, image_shape: tuple[int, int] = (224, 224), render_mode: str = "rgb_array") -> WorldInfo:
    """Spaces and variation factors of world ``name`` (the env is built once; results are cached)."""
    return _world_info(name, tuple(int(s) for s in image_shape), render_mode)

"""``lerobot``: a LeRobot dataset (v2.x or v3.0), read only, as upstream 0.1.1's ``lerobot`` format
(see :mod:`stable_worldmodel.data.lerobot`). Detected from ``lerobot://<org>/<name>`` (a Hub id,
found on disk, never downloaded) and from a folder holding ``meta/info.json``."""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any, ClassVar

from ..._lazy import lazy_getattr
from ...errors import ConfigError, DatasetNotFoundError
from ..format import Format, register_format

# the reader, where upstream placed it (imported on first use)
__getattr__ = lazy_getattr(__name__, {"LeRobotAdapter": "stable_worldmodel.data.lerobot"})

SCHEME = "lerobot"
PREFIX = SCHEME + ":/"  # lerobot://org/name; a Path keeps one slash
INFO = "meta/info.json"


def parse_url(path: Any) -> str | None:
    """The repo id of ``lerobot://org/name`` (or of ``lerobot:/org/name``, as a Path spells it), else None."""
    text = os.fspath(path) if isinstance(path, (str, os.PathLike)) else None
    if not isinstance(text, str) or not text.startswith(PREFIX):
        return None
    return text[len(PREFIX) :].lstrip("/")


def _hf_home() -> Path:
    home = os.environ.get("HF_HOME")
    if home:
        return Path(home).expanduser()
    return Path(os.environ.get("XDG_CACHE_HOME") or "~/.cache").expanduser() / "huggingface"


def lerobot_home() -> Path:
    """lerobot's dataset folder: ``$HF_LEROBOT_HOME``, else ``$HF_HOME/lerobot``."""
    home = os.environ.get("HF_LEROBOT_HOME")
    return Path(home).expanduser() if home else _hf_home() / "lerobot"


def hub_cache() -> Path:
    """huggingface_hub's cache: ``$HF_HUB_CACHE``, else ``$HF_HOME/hub``."""
    cache = os.environ.get("HF_HUB_CACHE") or os.environ.get("HUGGINGFACE_HUB_CACHE")
    return Path(cache).expanduser() if cache else _hf_home() / "hub"


def _snapshots_dir(repo_id: str) -> Path:
    return hub_cache() / f"datasets--{repo_id.replace('/', '--')}" / "snapshots"


def _snapshots(repo_id: str, revision: str | None) -> list[Path]:
    """The hub-cache snapshots of ``repo_id``: ``revision``'s, else ``main``'s first, newest next."""
    snaps = _snapshots_dir(repo_id)
    if not snaps.is_dir():
        return []

    def commit(ref: str) -> str:
        file = snaps.parent / "refs" / ref
        return file.read_text().strip() if file.is_file() else ref

    if revision is not None:
        ordered = [snaps / commit(revision)]
    else:
        newest = sorted((p for p in snaps.iterdir() if p.is_dir()), key=lambda p: p.stat().st_mtime, reverse=True)
        ordered = [snaps / commit("main"), *newest]
    return [p for p in dict.fromkeys(ordered) if p.is_dir()]


def is_dataset_dir(path: str | os.PathLike) -> bool:
    """``path`` holds ``meta/info.json``."""
    return (Path(path) / INFO).is_file()


def find_dataset(
    repo_id: str | None, root: str | os.PathLike | None = None, revision: str | None = None, owner: str = "lerobot"
) -> Path:
    """The folder of a LeRobot dataset: ``root``; else ``repo_id`` (a dataset folder, or a Hub id
    looked up offline, see the module docstring). :class:`DatasetNotFoundError` says where to put it."""
    if root is not None:
        path = Path(root).expanduser()
        if is_dataset_dir(path):
            return path
        why = "the folder does not exist" if not path.exists() else f"{INFO} is not there"
        raise DatasetNotFoundError(
            f"{owner} requires root to be a LeRobot dataset folder (holding {INFO}), got {str(root)!r}: {why}"
        )
    if not isinstance(repo_id, str) or not repo_id.strip("/ "):
        raise ConfigError(f"{owner} requires a repo_id such as 'lerobot/pusht' (or root=, a folder), got {repo_id!r}")
    if is_dataset_dir(Path(repo_id).expanduser()):  # a dataset folder given as the repo id
        return Path(repo_id).expanduser()
    if Path(repo_id).is_absolute() or ".." in Path(repo_id).parts:
        raise DatasetNotFoundError(
            f"{owner} requires a Hub repo id such as 'lerobot/pusht' or a LeRobot dataset folder, got {repo_id!r}, "
            f"which holds no {INFO}"
        )
    local = lerobot_home() / repo_id
    for folder in (local, *_snapshots(repo_id, revision)):
        if is_dataset_dir(folder):
            return folder
    snaps = _snapshots_dir(repo_id) / (revision or "<revision>")
    raise DatasetNotFoundError(
        f"{owner} found no LeRobot dataset {repo_id!r} on disk (looked in {local} and {snaps}) and does not "
        f"download: put the dataset folder (holding {INFO}) at {local}, e.g. "
        f"`hf download {repo_id} --repo-type dataset --local-dir {local}`, or pass root= (its folder)"
    )


@register_format
class LeRobot(Format):
    name = "lerobot"
    #: URL schemes this format reads (``load_dataset("lerobot://org/name")``)
    schemes: ClassVar[tuple[str, ...]] = (SCHEME,)

    @classmethod
    def detect(cls, path: str | os.PathLike) -> bool:
        text = os.fspath(path)
        return text.startswith(PREFIX) or is_dataset_dir(text)

    @classmethod
    def open_reader(cls, path: str | os.PathLike, **kwargs: Any) -> Any:
        from ..lerobot import LeRobotAdapter

        repo_id = parse_url(path)
        if repo_id is not None:
            return LeRobotAdapter(repo_id, **kwargs)
        return LeRobotAdapter(root=path, **kwargs)

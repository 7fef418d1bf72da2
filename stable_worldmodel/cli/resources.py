"""Cache commands of seed 000: ``swm list``, ``swm show`` and ``swm delete``.

A model name is either a checkpoint folder under ``<cache>/checkpoints/`` (its path relative
to that folder; ``weights.pt`` + ``config.json`` [+ ``protocol.json``], see
:mod:`stable_worldmodel.wm.utils`) or an older pickled checkpoint ``<cache>/<name>_object.ckpt``
(with its ``<name>_weights*.ckpt``). When both exist under one name, the commands act on both.
"""

from __future__ import annotations

import json
import re
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Annotated, Any

import typer

from ..errors import ConfigError, unknown_name
from .errors import check_choice

#: plural spellings accepted for every kind
ALIASES = {"models": "model", "datasets": "dataset", "worlds": "world", "solvers": "solver"}


#: ``protocol.json`` entries shown by ``swm show model``: (label, key)
PROTOCOL_ROWS = (
    ("model", "model"),
    ("preset", "preset"),
    ("dataset", "dataset"),
    ("env", "env"),
    ("action dim", "action_dim"),
    ("steps", "steps"),
    ("steps done", "steps_done"),
    ("history size", "history_size"),
    ("frameskip", "frameskip"),
    ("image size", "image_size"),
)


def _list_models() -> list[str]:
    """Exactly the names ``AutoCostModel`` / ``swm eval --policy wm:NAME`` accept, sorted."""
    from ..planning.auto import list_model_checkpoints

    return list_model_checkpoints()


def _lister(kind: str) -> Callable[[], list[str]]:
    from .. import data

    return {"model": _list_models, "dataset": data.list_datasets, "world": data.list_worlds}[kind]


# -- models ------------------------------------------------------------------------------------
def _checkpoint_folder(name: str) -> Path | None:
    """``checkpoints/<name>`` when it is a checkpoint folder (as listed by ``list_checkpoints``)."""
    from ..wm.utils import checkpoint_root, list_checkpoints

    return checkpoint_root() / name if name in list_checkpoints() else None


def _pickled_files(name: str) -> list[Path]:
    """The pickled checkpoint ``AutoCostModel(name)`` would load (``[]`` when there is none)."""
    from ..data import get_cache_dir
    from ..planning.auto import _pickled_names, _pickled_path

    root = get_cache_dir()
    if name not in _pickled_names(root):
        return []
    path = _pickled_path(name, root)
    return [path] if path is not None else []


def _entry_size(path: Path) -> int:
    if path.is_file():
        return path.stat().st_size
    return sum(p.stat().st_size for p in path.rglob("*") if p.is_file())


def _count_parameters(weights: Path) -> tuple[int, int]:
    """``(elements, tensors)`` of the state_dict in ``weights``, read without building the model."""
    import torch

    try:
        try:
            state = torch.load(weights, map_location="cpu", weights_only=True, mmap=True)
        except RuntimeError:  # a legacy (non-zip) file cannot be memory-mapped: read it whole
            state = torch.load(weights, map_location="cpu", weights_only=True)
    except Exception as exc:  # pickle / zip errors of every kind: name the file
        raise ConfigError(f"swm show model requires a readable state_dict, got {weights} ({exc})") from exc
    if not isinstance(state, dict):
        raise ConfigError(f"swm show model requires a state_dict in {weights}, got {type(state).__name__}")
    tensors = [v for v in state.values() if isinstance(v, torch.Tensor)]
    return sum(int(t.numel()) for t in tensors), len(tensors)


def _protocol_rows(protocol: dict[str, Any]) -> list[tuple[str, Any]]:
    rows = [(label, protocol[key]) for label, key in PROTOCOL_ROWS if protocol.get(key) is not None]
    for split in ("train", "val"):
        episodes = protocol.get(f"{split}_episodes")
        if isinstance(episodes, list):
            rows.append((f"{split} episodes", len(episodes)))
    final = protocol.get("final")
    if isinstance(final, dict):
        rows += [(f"final {k.replace('_', ' ')}", v) for k, v in final.items() if v is not None]
    made = protocol.get("provenance")
    if isinstance(made, dict):
        versions = made.get("versions") or {}
        rows.append(("versions", ", ".join(f"{k} {v}" for k, v in versions.items())))
        git = made.get("git")
        if isinstance(git, dict):
            rows.append(("git commit", f"{git.get('commit')}" + (" (uncommitted changes)" if git.get("dirty") else "")))
        rows += [(key, made[key]) for key in ("command", "host", "started", "ended") if made.get(key)]
    used = protocol.get("train_config")
    if isinstance(used, dict):
        rows.append(("config file", used.get("file")))
        applied = used.get("applied") or {}
        rows.append(("config applied", ", ".join(f"{k}={json.dumps(v)}" for k, v in applied.items()) or "-"))
        if used.get("overridden"):
            rows.append(("config overridden", ", ".join(map(str, used["overridden"])) + " (by flags or --set)"))
    if protocol.get("logger"):
        rows.append(("logger", protocol["logger"]))
    run = protocol.get("wandb")
    if isinstance(run, dict):
        where = run.get("url") or f"{run.get('mode')} (sync with: wandb sync)"
        rows.append(("wandb run", f"{run.get('project')}/{run.get('id')} {where}"))
    return rows


def checkpoint_info(name: str, folder: Path) -> dict[str, Any]:
    """What ``swm show model`` prints for a checkpoint folder: files, ``_target_``, parameters, protocol."""
    from ..wm.run import Run
    from ..wm.utils import CONFIG_NAME, WEIGHTS_NAME

    try:
        config = json.loads((folder / CONFIG_NAME).read_text())
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise ConfigError(
            f"swm show model requires valid JSON in {folder / CONFIG_NAME}, got a corrupt file ({exc})"
        ) from exc
    weights = folder / WEIGHTS_NAME
    if not weights.is_file():
        weights = sorted(folder.glob("*.pt"))[0]
    elements, tensors = _count_parameters(weights)
    return {
        "name": name,
        "format": f"checkpoint folder ({weights.name} + {CONFIG_NAME})",
        "path": str(folder),
        "target": config.get("_target_") if isinstance(config, dict) else None,
        "parameters": elements,
        "tensors": tensors,
        "files": [(p.name + ("/" if p.is_dir() else ""), _entry_size(p)) for p in sorted(folder.iterdir())],
        "protocol": _protocol_rows(Run.open(weights).protocol.to_dict()),
    }


def pickled_info(name: str, files: Sequence[Path]) -> dict[str, Any]:
    """What ``swm show model`` prints for an older pickled checkpoint: its files (never unpickled)."""
    from ..data import get_cache_dir

    root = get_cache_dir()
    return {
        "name": name,
        "format": "pickled module (*_object.ckpt, not loaded)",
        "path": str(root),
        "files": [(p.relative_to(root).as_posix(), p.stat().st_size) for p in files],
    }


def model_type_info(name: str) -> dict[str, Any]:
    """What ``swm show model`` prints for a registered model type (``swm train NAME``): its config
    class, what it is evaluated with, its presets (the fields each sets), every config field with
    its default and meaning, and the training keys (:func:`train_key_info`)."""
    import dataclasses

    from ..wm import get_config_class

    cls = get_config_class(name)
    doc = (cls.__doc__ or "").strip().split("\n\n")[0]
    doc = re.sub(r":\w+:`~?(?:[\w.]*\.)?([^`.]+)`", r"\1", doc).replace("``", "")  # reST roles -> plain names

    def default(f: dataclasses.Field) -> Any:  # read off the class: some configs need a field set to build
        if f.default is not dataclasses.MISSING:
            return f.default
        return f.default_factory() if f.default_factory is not dataclasses.MISSING else "(required)"

    meanings = cls.field_help()
    fields = [(f.name, default(f), meanings.get(f.name, "")) for f in dataclasses.fields(cls) if f.init]
    return {
        "name": name,
        "config": f"{cls.__module__}.{cls.__qualname__}",
        "summary": " ".join(doc.split()),
        "policy": "wm:SOURCE --video DIR --decoder RUN" if name == "frame" else f"{cls.eval_prefix}:RUN",
        "needs_reward": bool(getattr(cls, "needs_reward", False)),
        "presets": {preset: dict(values) for preset, values in cls.presets.items()},
        "fields": fields,
        "train_keys": train_key_info(),
    }


def train_key_info() -> list[tuple[str, Any, str]]:
    """``(key, default, meaning)`` of each training key ``swm train --set`` / ``--config`` takes besides
    the model's config fields (:func:`stable_worldmodel.train.train`'s arguments; a flag's default is
    the flag's)."""
    import inspect

    from ..train import TRAIN_KEY_HELP, train
    from .train import accepted_train_keys

    params = inspect.signature(train).parameters
    rows = []
    for key in accepted_train_keys():
        param = params.get(key)
        default = "(required)" if param is None or param.default is inspect.Parameter.empty else param.default
        rows.append((key, default, TRAIN_KEY_HELP.get(key, "")))
    return rows


def model_infos(name: str) -> list[dict[str, Any]]:
    """One info dict per layout that holds model ``name`` (checkpoint folder first), and the
    model type's when ``name`` is a registered model type (``lewm``, ``tdmpc2`` ...)."""
    from ..wm import list_models

    folder, files = _checkpoint_folder(name), _pickled_files(name)
    infos = ([checkpoint_info(name, folder)] if folder else []) + ([pickled_info(name, files)] if files else [])
    return infos + ([model_type_info(name)] if name in list_models() else [])


def delete_model(name: str) -> list[Path]:
    """Delete the checkpoint folder and/or the pickled files of model ``name``; returns what was removed."""
    import shutil

    from .. import data

    removed = []
    folder = _checkpoint_folder(name)
    if folder is not None:
        shutil.rmtree(folder)
        removed.append(folder)
    for path in _pickled_files(name):
        path.unlink()
        removed.append(path)
    if name in data.list_models():  # the <name>_weights*.ckpt files kept beside an older pickle
        removed += data.delete_model(name)
    return removed


def _check_names(kind: str, names: Sequence[str], known: Sequence[str]) -> None:
    """Raise for the first of ``names`` that is not in ``known`` (before anything happens)."""
    for name in names:
        if name not in known:
            raise unknown_name(kind, name, known)


def _list_solvers() -> None:
    from rich.table import Table

    from ..solver import get_solver_class, list_solvers
    from .display import console

    table = Table(title="Solvers (swm eval --solver NAME)")
    for column in ("name", "class", "what it does"):
        table.add_column(column)
    for name in list_solvers():
        cls = get_solver_class(name)
        table.add_row(name, cls.__name__, cls.knobs.summary)
    console().print(table)


def list_cmd(
    kind: Annotated[
        str, typer.Argument(help="What to list: model, dataset, world or solver.", metavar="KIND", show_default=False)
    ],
) -> None:
    """List cached models or datasets, the registered worlds, or the planning solvers.

    Example: swm list dataset
    """
    from ..data import get_cache_dir
    from .display import names_table, rows_table

    kind = check_choice("kind", kind, ("model", "dataset", "world", "solver"), ALIASES)
    if kind == "solver":
        _list_solvers()
        return
    note = None if kind == "world" else str(get_cache_dir())
    title = {"model": "Cached models", "dataset": "Cached datasets", "world": "Worlds"}[kind]
    names = sorted(_lister(kind)())
    if kind == "dataset":
        rows_table(title, ("name", "format", "episodes", "steps", "size", "modified"), _dataset_rows(names), note)
    elif kind == "model":
        rows_table(title, ("name", "model", "dataset", "steps", "size", "modified"), _model_rows(names), note)
    else:
        names_table(title, names, note)
    if kind == "model":
        from ..wm import list_models
        from .display import console

        console().print(
            f"[bold]Model types[/] (swm train MODEL; swm show model MODEL for presets and fields): "
            f"{', '.join(list_models())}",
            soft_wrap=True,
        )
    if kind == "dataset":
        from ..data.info import leftover_partials
        from .display import console

        for path in leftover_partials():
            console().print(f"Unfinished first recording (no episode committed): {path}", soft_wrap=True)


def _footprint(path: Path) -> tuple[str, str]:
    """Bytes on disk (a file, or a folder's files) and the last modification, as printed."""
    import datetime

    from .display import human_bytes

    files = [path] if path.is_file() else [p for p in path.rglob("*") if p.is_file()]
    size = sum(p.stat().st_size for p in files)
    newest = max((p.stat().st_mtime for p in files), default=path.stat().st_mtime)
    return human_bytes(size), datetime.datetime.fromtimestamp(newest).strftime("%Y-%m-%d %H:%M")


def _dataset_rows(names: list[str]) -> list[tuple[str, ...]]:
    """``swm list dataset``: name, format, episodes, steps, size, modified (a dataset that cannot be read says so)."""
    from ..data import dataset_info

    rows = []
    for name in names:
        try:
            info = dataset_info(name)
            size, when = _footprint(Path(info["path"]))
            rows.append((name, str(info["format"]), str(info["num_episodes"]), str(info["num_steps"]), size, when))
        except Exception as exc:  # noqa: BLE001 - one unreadable dataset must not hide the others
            rows.append((name, f"unreadable: {type(exc).__name__}", "", "", "", ""))
    return rows


def _model_rows(names: list[str]) -> list[tuple[str, ...]]:
    """``swm list model``: name, model type, dataset, steps done (of planned: "partial" when a run
    stopped early, "snapshot" for its ``step_<N>`` checkpoints), size, modified; a checkpoint with no
    protocol (upstream's) shows its files' size."""
    from ..wm.run import Run

    rows = []
    for name in names:
        try:
            run = Run.open(name)
            protocol = run.protocol.to_dict()
            done, planned = protocol.get("steps_done"), protocol.get("steps")
            steps = "" if done is None else str(done)
            if "/step_" in name and done is not None and planned and int(done) < int(planned):
                steps = f"{done} of {planned} (snapshot)"
            elif run.protocol.partial:  # stopped before its last step (killed, or still training)
                steps = f"{done} of {planned} (partial)"
            size, when = _footprint(run.folder)
            rows.append(
                (name, str(protocol.get("model") or "?"), str(protocol.get("dataset") or ""), steps, size, when)
            )
        except Exception:  # noqa: BLE001 - a pickled or foreign checkpoint: its file, no protocol
            folder = _checkpoint_folder(name)
            files = _pickled_files(name)
            where = folder if folder is not None else (files[0] if files else None)
            size, when = _footprint(where) if where is not None else ("", "")
            rows.append((name, "(no protocol)", "", "", size, when))
    return rows


def show(
    kind: Annotated[
        str, typer.Argument(help="What to show: model, dataset or world.", metavar="KIND", show_default=False)
    ],
    names: Annotated[
        list[str] | None,
        typer.Argument(help="Names to show (see `swm list KIND`).", metavar="NAMES...", show_default=False),
    ] = None,
    all: Annotated[
        bool, typer.Option("--all", "-a", help="Show every cached model / dataset / registered world.")
    ] = False,  # noqa: A002 (seed name)
) -> None:
    """Show the files, model class, parameter count and training protocol of models (the presets
    and config fields of a model type), the columns, counts, shapes and factors of datasets, or
    the spaces and factors of worlds.

    Example: swm show model pusht-lewm; swm show model tdmpc2; swm show dataset tworoom-v1-expert;
    swm show world swm/TwoRoom-v2
    """
    from ..data import dataset_info, world_info
    from .display import display_dataset_info, display_model_info, display_model_type_info, display_world_info

    kind = check_choice("kind", kind, ("model", "dataset", "world"), ALIASES)
    known = sorted(_lister(kind)())
    if all:
        names = known
    elif not names:
        raise ConfigError(f"swm show {kind} requires NAMES or --all, got neither (known: {', '.join(known) or 'none'})")
    if kind == "model":  # a model type (swm train MODEL) shows its presets and fields
        from ..wm import list_models

        known = sorted({*known, *list_models()})
    if kind == "dataset":  # one shard of a sharded dataset shows too
        from ..data.info import list_dataset_shards

        known = sorted({*known, *list_dataset_shards()})
    _check_names(kind, names, known)
    if kind == "model":
        for info in [info for name in names for info in model_infos(name)]:  # read all before printing
            (display_model_type_info if "fields" in info else display_model_info)(info)
        return
    info, display = (dataset_info, display_dataset_info) if kind == "dataset" else (world_info, display_world_info)
    for name in names:
        display(info(name))


def delete(
    kind: Annotated[str, typer.Argument(help="What to delete: model or dataset.", metavar="KIND", show_default=False)],
    names: Annotated[
        list[str], typer.Argument(help="Names to delete (all must exist).", metavar="NAMES...", show_default=False)
    ],
    yes: Annotated[bool, typer.Option("--yes", "-y", help="Do not ask for confirmation.")] = False,
) -> None:
    """Delete cached models (checkpoint folders or pickled files) or datasets, after a confirmation
    (this cannot be undone).

    Example: swm delete dataset tworoom-v1-random --yes
    """
    from .. import data
    from .display import console

    kind = check_choice("kind", kind, ("model", "dataset"), ALIASES)
    names = list(dict.fromkeys(names))  # once each, in the given order
    _check_names(kind, names, sorted(_lister(kind)()))
    plural = kind + ("s" if len(names) > 1 else "")
    if not yes and not typer.confirm(f"Delete {len(names)} {plural} ({', '.join(names)})? This cannot be undone."):
        typer.echo("Nothing deleted.", err=True)
        raise typer.Exit(code=1)
    remove = delete_model if kind == "model" else data.delete_dataset
    out = console()
    for name in names:
        remove(name)
        out.print(f"Deleted {kind} [bold]{name}[/]", soft_wrap=True)


# -- upstream 0.1.1's command names ------------------------------------------------------------
def datasets_cmd() -> None:
    """List the datasets in the cache (upstream 0.1.1's name for `swm list dataset`)."""
    list_cmd("dataset")


def inspect_cmd(
    name: Annotated[
        str, typer.Argument(help="Dataset name to inspect (see `swm datasets`).", metavar="NAME", show_default=False)
    ],
) -> None:
    """Show a dataset's columns, counts, shapes and factors (upstream 0.1.1's name for `swm show dataset`)."""
    show("dataset", [name])


def checkpoints_cmd(
    filter: Annotated[
        str | None, typer.Argument(help="Only names containing this text.", metavar="FILTER", show_default=False)
    ] = None,  # noqa: A002
) -> None:
    """List the model checkpoints in the cache, optionally filtered (upstream 0.1.1's `swm checkpoints`)."""
    from ..data import get_cache_dir
    from .display import names_table

    names = [n for n in _list_models() if filter is None or filter in n]
    names_table("Cached models", names, str(get_cache_dir()))

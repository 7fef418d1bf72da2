"""Cache commands of seed 000: ``swm list``, ``swm show`` and ``swm delete``."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Annotated

import typer

from ..errors import ConfigError, unknown_name
from .errors import check_choice

#: plural spellings accepted for every kind
ALIASES = {"models": "model", "datasets": "dataset", "worlds": "world"}


def _lister(kind: str) -> Callable[[], list[str]]:
    from .. import data

    return {"model": data.list_models, "dataset": data.list_datasets, "world": data.list_worlds}[kind]


def _check_names(kind: str, names: Sequence[str], known: Sequence[str]) -> None:
    """Raise for the first of ``names`` that is not in ``known`` (before anything happens)."""
    for name in names:
        if name not in known:
            raise unknown_name(kind, name, known)


def list_cmd(kind: Annotated[str, typer.Argument(help="What to list: model, dataset or world.", metavar="KIND", show_default=False)]) -> None:
    """List cached models or datasets, or the registered worlds.

    Example: swm list dataset
    """
    from ..data import get_cache_dir
    from .display import names_table

    kind = check_choice("kind", kind, ("model", "dataset", "world"), ALIASES)
    note = None if kind == "world" else str(get_cache_dir())
    title = {"model": "Cached models", "dataset": "Cached datasets", "world": "Worlds"}[kind]
    names_table(title, sorted(_lister(kind)()), note)


def show(
    kind: Annotated[str, typer.Argument(help="What to show: dataset or world.", metavar="KIND", show_default=False)],
    names: Annotated[list[str] | None, typer.Argument(help="Names to show (see `swm list KIND`).", metavar="NAMES...", show_default=False)] = None,
    all: Annotated[bool, typer.Option("--all", "-a", help="Show every cached dataset / registered world.")] = False,  # noqa: A002 (seed name)
) -> None:
    """Show the columns, counts, shapes and factors of datasets, or the spaces and factors of worlds.

    Example: swm show dataset tworoom-v1-expert; swm show world swm/TwoRoom-v1
    """
    from ..data import dataset_info, world_info
    from .display import display_dataset_info, display_world_info

    kind = check_choice("kind", kind, ("dataset", "world"), ALIASES)
    known = sorted(_lister(kind)())
    if all:
        names = known
    elif not names:
        raise ConfigError(f"swm show {kind} requires NAMES or --all, got neither (known: {', '.join(known) or 'none'})")
    _check_names(kind, names, known)
    info, display = (dataset_info, display_dataset_info) if kind == "dataset" else (world_info, display_world_info)
    for name in names:
        display(info(name))


def delete(
    kind: Annotated[str, typer.Argument(help="What to delete: model or dataset.", metavar="KIND", show_default=False)],
    names: Annotated[list[str], typer.Argument(help="Names to delete (all must exist).", metavar="NAMES...", show_default=False)],
    yes: Annotated[bool, typer.Option("--yes", "-y", help="Do not ask for confirmation.")] = False,
) -> None:
    """Delete cached models or datasets, after a confirmation (this cannot be undone).

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
    remove = data.delete_model if kind == "model" else data.delete_dataset
    out = console()
    for name in names:
        remove(name)
        out.print(f"Deleted {kind} [bold]{name}[/]", soft_wrap=True)

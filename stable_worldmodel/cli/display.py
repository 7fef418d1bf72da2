"""Rich rendering for the ``swm`` command: panels, tables and factor trees.

Everything here only formats what it is given (info dicts, spaces, numbers); it never
loads data. Output goes to the current ``sys.stdout`` (so Typer's test runner captures it).
"""

from __future__ import annotations

import sys
from collections.abc import Iterable, Mapping, Sequence
from typing import Any

import numpy as np
from rich.console import Console, Group
from rich.panel import Panel
from rich.table import Table
from rich.text import Text
from rich.tree import Tree

#: width used when stdout is not a terminal (pipes, files, tests): wide enough for env ids
PIPE_WIDTH = 120


def console() -> Console:
    """A Console writing to the current ``sys.stdout`` (terminal width, or :data:`PIPE_WIDTH`)."""
    tty = sys.stdout.isatty()
    return Console(file=sys.stdout, width=None if tty else PIPE_WIDTH, highlight=False)


def short(value: Any, max_items: int = 6) -> str:
    """A compact one-line repr of a scalar, a sequence or an array."""
    if value is None:
        return "-"
    if isinstance(value, str):
        return value
    if isinstance(value, (tuple, list)) and all(isinstance(v, (int, np.integer)) for v in value):
        return "(" + ", ".join(str(int(v)) for v in value) + ("," if len(value) == 1 else "") + ")"
    arr = np.asarray(value)
    if arr.ndim == 0:
        item = arr.item()
        return f"{item:.4g}" if isinstance(item, float) else str(item)
    if arr.size > 1 and np.all(arr == arr.flat[0]):
        return short(arr.flat[0])  # a constant array: its value is enough
    if arr.ndim == 1 and arr.size <= max_items:
        return "[" + ", ".join(short(x) for x in arr) + "]"
    return np.array2string(arr, precision=3, threshold=max_items, edgeitems=2, separator=", ").replace("\n", "")


# -- variation trees ---------------------------------------------------------------------
def _nest(names: Iterable[str]) -> dict[str, Any]:
    """``["a.b", "a.c", "d"]`` -> ``{"a": {"b": {}, "c": {}}, "d": {}}``."""
    root: dict[str, Any] = {}
    for name in names:
        node = root
        for part in str(name).split("."):
            node = node.setdefault(part, {})
    return root


def _fill(tree: Tree, node: Mapping[str, Any], describe: Mapping[str, str], prefix: str = "") -> None:
    for key, child in node.items():
        path = f"{prefix}{key}"
        if child:
            _fill(tree.add(f"[bold]{key}[/]"), child, describe, path + ".")
        else:
            extra = describe.get(path)
            tree.add(f"[cyan]{key}[/]" + (f"  [dim]{extra}[/]" if extra else ""))


def names_tree(title: str, names: Sequence[str], describe: Mapping[str, str] | None = None) -> Tree:
    """A tree of dotted factor names (``agent.color`` under ``agent``), leaves annotated by ``describe``."""
    tree = Tree(f"[bold]{title}[/]")
    if not names:
        tree.add("[dim]none[/]")
    _fill(tree, _nest(names), describe or {})
    return tree


def _uniform(values: Any) -> Any:
    """One number for an array whose entries are all equal (``[[7.0]]`` -> ``7.0``), else the array."""
    arr = np.asarray(values)
    return arr.reshape(-1)[0] if arr.size and np.all(arr == arr.reshape(-1)[0]) else values


def describe_factor(space: Any) -> str:
    """``"RGBBox [0, 255] (3,) = [220, 40, 40]"``: type, range or size, shape and current default."""
    kind = type(space).__name__
    parts = [kind]
    if hasattr(space, "n"):
        parts.append(f"n={short(space.n)}")
    elif hasattr(space, "low") and hasattr(space, "high"):
        parts.append(f"[{short(_uniform(space.low))}, {short(_uniform(space.high))}]")
    elif hasattr(space, "nvec"):
        start = np.asarray(getattr(space, "start", 0))
        parts.append(f"[{short(_uniform(start))}, {short(_uniform(start + np.asarray(space.nvec) - 1))}]")
    shape = getattr(space, "shape", None)
    if shape:
        parts.append(short(tuple(shape)))
    init = getattr(space, "init_value", None)
    if init is not None:
        parts.append(f"default {short(init)}")
    return " ".join(parts)


def factor_leaves(space: Any, prefix: str = "") -> dict[str, Any]:
    """``{dotted name: leaf space}`` of a (nested) variation ``Dict`` space."""
    out: dict[str, Any] = {}
    for key, sub in getattr(space, "spaces", {}).items():
        if hasattr(sub, "spaces") and isinstance(sub.spaces, Mapping):
            out.update(factor_leaves(sub, f"{prefix}{key}."))
        else:
            out[f"{prefix}{key}"] = sub
    return out


def factor_tree(title: str, space: Any) -> Tree:
    """The factor-of-variation tree of ``space`` with each leaf's type, range, shape and default."""
    leaves = factor_leaves(space) if space is not None else {}
    return names_tree(title, list(leaves), {k: describe_factor(v) for k, v in leaves.items()})


def variation_names(variation: Any) -> list[str]:
    """Factor names from the ``variation`` entry of an info dict (names list, nested dict or ``names`` key)."""
    if not variation:
        return []
    if isinstance(variation, Mapping):
        if "names" in variation:
            return list(variation.get("names") or [])
        return list(factor_names_of_nested(variation))
    return [str(v) for v in variation]


def factor_names_of_nested(node: Mapping[str, Any], prefix: str = "") -> list[str]:
    out: list[str] = []
    for key, child in node.items():
        if isinstance(child, Mapping) and child:
            out.extend(factor_names_of_nested(child, f"{prefix}{key}."))
        else:
            out.append(f"{prefix}{key}")
    return out


# -- panels ------------------------------------------------------------------------------
def _kv_table(title: str, rows: Iterable[tuple[str, Any]]) -> Table:
    table = Table(title=title, show_header=False, box=None, pad_edge=False, title_justify="left")
    table.add_column(style="bold")
    table.add_column()
    for key, value in rows:
        table.add_row(key, value if isinstance(value, Text) else short(value))
    return table


def display_dataset_info(info: dict[str, Any]) -> None:
    """Print a panel with a dataset's columns, episode and step counts, shapes and variation tree.

    ``info`` has the keys of :func:`stable_worldmodel.data.dataset_info`: ``name``, ``columns``,
    ``num_episodes``, ``num_steps``, ``obs_shape``, ``action_shape``, ``goal_shape`` and
    ``variation`` (missing keys show as ``-``); an optional ``column_shapes`` mapping
    (column -> shape) adds one row per column.
    """
    lengths = info.get("episode_length") or {}
    overview = _kv_table(
        "Overview",
        [
            ("episodes", info.get("num_episodes")),
            ("steps", info.get("num_steps")),
            (
                "episode length",
                Text(f"{lengths['min']}..{lengths['max']} (mean {lengths['mean']:.1f})") if lengths else None,
            ),
        ]
        + [(k, info[k]) for k in ("format", "env_name") if info.get(k) is not None],
    )
    shapes = _kv_table(
        "Shapes", [(k.removesuffix("_shape"), info.get(k)) for k in ("obs_shape", "action_shape", "goal_shape")]
    )
    for column, shape in (info.get("column_shapes") or {}).items():
        shapes.add_row(f"  {column}", short(shape))
    grid = Table.grid(padding=(0, 4))
    grid.add_row(overview, shapes)
    columns = Text.assemble(("columns ", "bold"), ", ".join(map(str, info.get("columns") or [])) or "-")
    parts = [grid, Text(""), columns]
    if info.get("path"):
        parts.append(Text.assemble(("path ", "bold"), str(info["path"])))
    tree = names_tree("variation", variation_names(info.get("variation")))
    console().print(
        Panel(Group(*parts, Text(""), tree), title=f"[bold]dataset[/] {info.get('name', '?')}", expand=False)
    )


def _space_rows(space: Mapping[str, Any] | None) -> list[tuple[str, Any]]:
    if not space:
        return [("", "-")]
    return [(k, v) for k, v in space.items() if v not in (None, ()) and k != "spaces"]


def _space_table(title: str, space: Any) -> Table:
    table = _kv_table(title, _space_rows(space) if isinstance(space, Mapping) else [("", str(space))])
    for key, sub in ((space or {}).get("spaces") or {}).items() if isinstance(space, Mapping) else ():
        table.add_row(f"  {key}", Text(", ".join(f"{k}={short(v)}" for k, v in _space_rows(sub))))
    return table


def display_world_info(info: dict[str, Any]) -> None:
    """Print a panel with a world's observation space, action space and factor-of-variation tree.

    ``info`` has the keys of :func:`stable_worldmodel.data.world_info`: ``name``,
    ``observation_space``, ``action_space`` (SpaceInfo dicts) and ``variation``.
    """
    grid = Table.grid(padding=(0, 4))
    grid.add_row(
        _space_table("Observation space", info.get("observation_space")),
        _space_table("Action space", info.get("action_space")),
    )
    tree = names_tree("factors of variation", variation_names(info.get("variation")))
    console().print(Panel(Group(grid, Text(""), tree), title=f"[bold]world[/] {info.get('name', '?')}", expand=False))


def human_size(size: int) -> str:
    """``1536`` -> ``"1.5 KiB"`` (below 1 KiB: ``"512 B"``)."""
    value, unit = float(size), "B"
    for unit in ("B", "KiB", "MiB", "GiB"):
        if value < 1024 or unit == "GiB":
            break
        value /= 1024
    return f"{int(size)} B" if unit == "B" else f"{value:.1f} {unit}"


def _count(n: int) -> str:
    """``1234567`` -> ``"1,234,567 (1.23M)"``."""
    for scale, suffix in ((1e9, "B"), (1e6, "M"), (1e3, "k")):
        if n >= scale:
            return f"{n:,} ({n / scale:.3g}{suffix})"
    return str(n)


def display_model_info(info: dict[str, Any]) -> None:
    """Print a panel with a cached model's format, path, files and, for checkpoint folders, its
    ``_target_``, parameter count and training protocol.

    ``info`` has the keys of :func:`stable_worldmodel.cli.resources.checkpoint_info` (``name``,
    ``format``, ``path``, ``files`` as ``(name, bytes)`` pairs, ``target``, ``parameters``,
    ``tensors``, ``protocol`` as ``(label, value)`` rows) or of ``pickled_info`` (no model keys).
    """
    rows: list[tuple[str, Any]] = [("format", info.get("format")), ("path", Text(str(info.get("path", "-"))))]
    if "parameters" in info:
        tensors = info.get("tensors")
        rows += [
            ("target", info.get("target")),
            ("parameters", Text(_count(int(info["parameters"])) + (f" in {tensors} tensors" if tensors else ""))),
        ]
    files = Table(title="Files", title_justify="left", box=None, pad_edge=False, show_header=False)
    files.add_column(style="cyan")
    files.add_column(justify="right")
    for name, size in info.get("files") or [("-", None)]:
        files.add_row(name, "-" if size is None else human_size(size))
    parts: list[Any] = [_kv_table("Overview", rows), Text(""), files]
    protocol = info.get("protocol")
    if protocol:
        parts += [Text(""), _kv_table("Protocol", protocol)]
    elif "protocol" in info:
        parts += [Text(""), Text("no protocol.json", style="dim")]
    console().print(Panel(Group(*parts), title=f"[bold]model[/] {info.get('name', '?')}", expand=False))


def _help_table(title: str, rows: Iterable[tuple[str, Any, str]]) -> Table:
    """A table of ``(key, default, meaning)`` rows under a key / default / meaning header."""
    table = Table(title=title, box=None, pad_edge=False, title_justify="left", header_style="dim")
    table.add_column("key", style="bold", no_wrap=True)
    table.add_column("default", overflow="fold")
    table.add_column("meaning")
    for key, default, meaning in rows:
        shown = default if default == "(required)" else repr(default)
        table.add_row(key, Text(shown), Text(meaning or "-"))
    return table


def display_model_type_info(info: dict[str, Any]) -> None:
    """Print a panel with a model type's config class, summary, policy prefix, presets, config
    fields and training keys with their defaults and meanings (``info`` from
    :func:`stable_worldmodel.cli.resources.model_type_info`)."""
    rows: list[tuple[str, Any]] = [
        ("config", info["config"]),
        ("train", f"swm train {info['name']} --dataset NAME [--preset P] [--set KEY=VALUE]"),
        ("evaluate", f"swm eval ENV --policy {info['policy']}"),
        ("needs reward", "yes" if info["needs_reward"] else "no"),
    ]
    presets = Table(
        title="Presets (the fields each sets)", title_justify="left", box=None, pad_edge=False, show_header=False
    )
    presets.add_column(style="bold cyan")
    presets.add_column()
    for name, values in info["presets"].items():
        presets.add_row(name, Text(", ".join(f"{k}={v!r}" for k, v in values.items())))
    fields = _help_table("Config fields (--set KEY=VALUE, --config FILE)", info["fields"])
    parts: list[Any] = [
        Text(info["summary"]),
        Text(""),
        _kv_table("Overview", rows),
        Text(""),
        presets,
        Text(""),
        fields,
    ]
    if info.get("train_keys"):
        keys = _help_table("Training keys (their flags, --set KEY=VALUE, --config FILE)", info["train_keys"])
        parts += [Text(""), keys]
    console().print(Panel(Group(*parts), title=f"[bold]model type[/] {info['name']}", expand=False))


def _heading(title: str, count: int, note: str | None) -> bool:
    """Print ``title (count) in note`` (or that there are none); whether a table follows."""
    where = f" in {note}" if note else ""
    if not count:
        console().print(f"No {title.lower()}{where}.", soft_wrap=True)
        return False
    console().print(f"[bold]{title}[/] ({count}){where}", soft_wrap=True)
    return True


def names_table(title: str, names: Sequence[str], note: str | None = None) -> None:
    """Print ``title (count) in note`` and a one-column table of ``names`` (or a note that there are none)."""
    if not _heading(title, len(names), note):
        return
    out = console()
    table = Table(show_header=False)
    table.add_column("name", style="cyan", no_wrap=True)
    for name in names:
        table.add_row(name)
    out.print(table)


def rows_table(title: str, columns: Sequence[str], rows: Sequence[Sequence[str]], note: str | None = None) -> None:
    """Print ``title (count) in note`` and a table of ``rows`` under ``columns`` (first column: the names)."""
    if not _heading(title, len(rows), note):
        return
    table = Table()
    for i, column in enumerate(columns):
        right = column in ("episodes", "steps", "size")
        table.add_column(column, style="cyan" if i == 0 else None, no_wrap=i == 0, justify="right" if right else "left")
    for row in rows:
        table.add_row(*row)
    console().print(table)


def human_bytes(n: int) -> str:
    """``1536`` -> ``1.5 KiB``."""
    size = float(n)
    for unit in ("B", "KiB", "MiB", "GiB", "TiB"):
        if size < 1024 or unit == "TiB":
            return f"{size:.0f} {unit}" if unit == "B" else f"{size:.1f} {unit}"
        size /= 1024
    return f"{size:.1f} TiB"  # pragma: no cover - the loop returns


def success_table(title: str, summaries: Sequence[Any]) -> Table:
    """A table of :class:`~stable_worldmodel.cli.stats.SuccessSummary` rows: rate with its 95% Wilson interval."""
    table = Table(title=title)
    table.add_column("policy", style="bold")
    table.add_column("episodes", justify="right")
    table.add_column("successes", justify="right")
    table.add_column("success rate", justify="right", style="green")
    table.add_column("95% CI", justify="right")
    table.add_column("mean length", justify="right")
    for s in summaries:
        low, high = s.interval
        table.add_row(
            s.label,
            str(s.episodes),
            str(s.successes),
            f"{100 * s.rate:.1f}%",
            f"[{100 * low:.1f}, {100 * high:.1f}]",
            f"{s.mean_length:.1f}",
        )
    return table

"""The CLI reference in Markdown, generated from the parser itself (the docs site's ``reference/cli.md``).

Every command and option of ``swm`` comes from the click command tree that ``swm`` runs, so the
reference cannot drift from the code: ``python -m stable_worldmodel.cli.reference`` prints it.
"""

from __future__ import annotations

import re
from typing import Any


def _cell(text: str) -> str:
    return " ".join(str(text).split()).replace("|", "\\|")


def _is(param: Any, kind: str) -> bool:  # typer vendors its own click: ask the parameter, not isinstance
    return getattr(param, "param_type_name", None) == kind


def _option_row(param: Any) -> tuple[str, str, str]:
    names = ", ".join(f"`{n}`" for n in [*param.opts, *param.secondary_opts])
    if not param.is_flag and param.metavar:
        names += f" `{param.metavar}`"
    default = ""
    if param.show_default is not False and not param.is_flag and not param.count:
        value = param.default
        if value not in (None, (), [], "") and not callable(value):
            default = f"`{value}`"
    help_text = getattr(param, "help", None) or ""
    return names, default, _cell(help_text)


def _command_markdown(path: str, command: Any, level: int) -> list[str]:
    lines = [f"{'#' * level} `{path}`", ""]
    doc = (command.help or "").strip()
    if doc:
        lines += [re.sub(r"\x1b\[[0-9;]*m", "", doc).replace("\b\n", ""), ""]
    arguments = [p for p in command.params if _is(p, "argument")]
    options = [p for p in command.params if _is(p, "option") and not p.hidden]
    usage = " ".join(
        [
            path,
            "[OPTIONS]",
            *((a.metavar or a.name).upper() if a.required else f"[{(a.metavar or a.name).upper()}]" for a in arguments),
        ]
    )
    lines += ["```text", usage, "```", ""]
    if options:
        lines += ["| option | default | meaning |", "| --- | --- | --- |"]
        lines += [f"| {n} | {d} | {h} |" for n, d, h in map(_option_row, options)]
        lines.append("")
    return lines


def commands(root: Any = None, prefix: str = "swm") -> list[tuple[str, Any]]:
    """``(path, command)`` of every command under ``root`` (default: ``swm``), sorted by name, sub-commands
    after their group."""
    if root is None:
        import typer

        from .root import app

        root = typer.main.get_command(app)
    out: list[tuple[str, Any]] = []
    for name, command in sorted(getattr(root, "commands", {}).items()):
        out.append((f"{prefix} {name}", command))
        out += commands(command, f"{prefix} {name}")
    return out


def markdown_reference() -> str:
    """The whole ``swm`` reference: the common options, then one section per command."""
    import typer

    from .root import app

    root = typer.main.get_command(app)
    lines: list[Any] = [
        "Generated from the parser (`python -m stable_worldmodel.cli.reference`); `swm COMMAND --help` prints it too.",
        "",
    ]
    lines += _command_markdown("swm", root, 2)[2:]
    for path, command in commands(root):
        lines += _command_markdown(path, command, 2)
    return "\n".join(lines).rstrip() + "\n"


if __name__ == "__main__":  # pragma: no cover
    print(markdown_reference())

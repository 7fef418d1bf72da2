"""The CLI reference of the docs site is generated from the parser: every command and option is in it."""

from __future__ import annotations

import typer

from stable_worldmodel.cli.reference import commands, markdown_reference
from stable_worldmodel.cli.root import app


def test_every_command_and_option_is_in_the_reference():
    text = markdown_reference()
    root = typer.main.get_command(app)
    assert {path for path, _ in commands()} == {f"swm {name}" for name in root.commands}
    for path, command in commands():
        assert f"## `{path}`" in text
        for param in command.params:
            if param.param_type_name == "option" and not param.hidden:
                assert f"`{param.opts[0]}`" in text.split(f"## `{path}`")[1].split("\n## ")[0], (path, param.opts)


def test_usage_lines_mark_optional_arguments():
    text = markdown_reference()
    assert "swm collect [OPTIONS] ENV\n" in text  # required
    assert "swm checkpoints [OPTIONS] [FILTER]\n" in text  # optional
    assert "| `--cache-dir` `DIR` |" in text and "\n| --- | --- | --- |\n" in text

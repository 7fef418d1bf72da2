"""The root ``swm`` command (the Typer app): the global callback, error handling, and the command table.

Only Typer and Rich are imported here; every command imports what it needs when it runs,
so ``swm --version`` and ``swm --help`` stay fast.
"""

from __future__ import annotations

import logging
import os
import sys
from collections.abc import Sequence
from typing import Annotated, Any

import typer
from typer.core import TyperGroup

from .errors import USAGE_EXIT, USER_ERROR_EXIT, USER_ERRORS, one_line, report, shows_traceback

_HANDLER_MARK = "_swm_cli_handler"

try:  # Typer >= 0.2x vendors Click; older releases depend on it
    from typer._click.exceptions import ClickException
except ImportError:  # pragma: no cover - depends on the installed Typer
    from click.exceptions import ClickException


class SWMGroup(TyperGroup):
    """The command group; turns user errors into one ``Error: ...`` line on stderr.

    Whatever the caller asks (``standalone_mode``), the group runs the command itself and
    maps the outcome to an exit status: 0, 1 (a rejected value or a declined prompt) or 2
    (a bad command line). Exceptions that are not user errors propagate with their traceback.
    """

    def main(
        self,
        args: Sequence[str] | None = None,
        prog_name: str | None = None,
        complete_var: str | None = None,
        standalone_mode: bool = True,
        **extra: Any,
    ) -> Any:
        try:
            rv = super().main(args=args, prog_name=prog_name, complete_var=complete_var, standalone_mode=False, **extra)
            code = rv if isinstance(rv, int) and not isinstance(rv, bool) else 0
        except ClickException as exc:  # bad command line: missing argument, not an integer, ...
            if type(exc).__name__ == "NoArgsIsHelpError":  # bare `swm`: the help (Rich mode printed it already)
                if not _rich_help(self):
                    sys.stdout.write(exc.format_message() + "\n")
                return _finish(0, standalone_mode)
            hint = f" (see '{exc.ctx.command_path} --help')" if getattr(exc, "ctx", None) is not None else ""
            sys.stderr.write(f"Error: {one_line(exc.format_message())}{hint}\n")
            code = exc.exit_code if exc.exit_code else USAGE_EXIT
        except typer.Abort:
            sys.stderr.write("Aborted.\n")
            code = USER_ERROR_EXIT
        except USER_ERRORS as exc:
            if shows_traceback(exc):
                raise
            code = report(exc, USER_ERROR_EXIT)
        return _finish(code, standalone_mode)


def _rich_help(group: TyperGroup) -> bool:
    from typer import core

    return bool(getattr(core, "HAS_RICH", False)) and getattr(group, "rich_markup_mode", None) is not None


def _finish(code: int, standalone_mode: bool) -> int:
    if standalone_mode:
        sys.exit(code)
    return code


app = typer.Typer(
    name="swm",
    cls=SWMGroup,
    help="stable-worldmodel: collect datasets from worlds with factors of variation, inspect them, evaluate policies.",
    no_args_is_help=True,
    add_completion=True,  # swm --install-completion [bash|zsh|fish]
    pretty_exceptions_show_locals=False,
    context_settings={"help_option_names": ["-h", "--help"]},
)


def setup_logging(verbosity: int = 0) -> logging.Logger:
    """Route ``stable_worldmodel`` logs to a :class:`rich.logging.RichHandler` on stderr (installed once).

    ``verbosity`` 0 shows warnings, 1 info, 2 and more debug messages.
    """
    logger = logging.getLogger("stable_worldmodel")
    logger.setLevel(max(logging.DEBUG, logging.WARNING - 10 * verbosity))
    if not any(getattr(h, _HANDLER_MARK, False) for h in logger.handlers):
        from rich.console import Console
        from rich.logging import RichHandler

        handler = RichHandler(console=Console(stderr=True), show_path=False, show_time=False)
        setattr(handler, _HANDLER_MARK, True)
        logger.addHandler(handler)
    return logger


def _print_version(value: bool) -> None:
    if value:
        from .. import __version__

        typer.echo(f"stable-worldmodel {__version__}")
        raise typer.Exit()


@app.callback()
def common(
    version: Annotated[
        bool | None,
        typer.Option("--version", "-V", callback=_print_version, is_eager=True, help="Print the version and exit."),
    ] = None,
    verbose: Annotated[
        int, typer.Option("--verbose", "-v", count=True, help="More log messages (-v info, -vv debug).")
    ] = 0,
) -> None:
    """Common options for all stable-worldmodel commands."""
    setup_logging(verbose)


def with_cache_dir(command: Any) -> Any:
    """``command`` with a ``--cache-dir DIR`` option: the cache folder of this invocation (datasets,
    checkpoints), as ``STABLEWM_HOME=DIR swm ...`` would set it."""
    import functools
    import inspect
    from pathlib import Path

    option = typer.Option(
        "--cache-dir",
        metavar="DIR",
        help="Cache folder of datasets and checkpoints for this command (default: $STABLEWM_HOME, else "
        "~/.stable_worldmodel).",
        file_okay=False,
        show_default=False,
    )
    annotation = Annotated[Path | None, option]

    @functools.wraps(command)
    def wrapped(*args: Any, cache_dir: Path | None = None, **kwargs: Any) -> Any:
        if cache_dir is None:
            return command(*args, **kwargs)
        before = os.environ.get("STABLEWM_HOME")
        os.environ["STABLEWM_HOME"] = str(Path(cache_dir).expanduser().resolve())
        try:
            return command(*args, **kwargs)
        finally:  # swm.cli.main() called from Python: the next call sees the environment as it was
            if before is None:
                os.environ.pop("STABLEWM_HOME", None)
            else:
                os.environ["STABLEWM_HOME"] = before

    signature = inspect.signature(command, eval_str=True)
    params = [*signature.parameters.values()]
    params.append(inspect.Parameter("cache_dir", inspect.Parameter.KEYWORD_ONLY, default=None, annotation=annotation))
    wrapped.__signature__ = signature.replace(parameters=params)
    wrapped.__annotations__ = {p.name: p.annotation for p in params}
    del wrapped.__wrapped__  # typer reads the signature above, not the command's
    return wrapped


def _register() -> None:
    from .data_cmds import convert_cmd, preview_cmd
    from .demo import demo
    from .hub import push_cmd
    from .pipeline import collect, envs, eval_cmd, fovs, sweep
    from .resources import checkpoints_cmd, datasets_cmd, delete, inspect_cmd, list_cmd, show
    from .train import train_cmd

    app.command("list")(with_cache_dir(list_cmd))
    app.command("show")(with_cache_dir(show))
    app.command("delete")(with_cache_dir(delete))
    app.command("collect")(with_cache_dir(collect))
    app.command("eval")(with_cache_dir(eval_cmd))
    app.command("sweep")(with_cache_dir(sweep))
    app.command("train")(with_cache_dir(train_cmd))
    app.command("envs")(envs)
    app.command("fovs")(fovs)
    app.command("demo")(with_cache_dir(demo))
    app.command("push")(with_cache_dir(push_cmd))
    # the names upstream 0.1.1 documents
    app.command("datasets")(with_cache_dir(datasets_cmd))
    app.command("inspect")(with_cache_dir(inspect_cmd))
    app.command("checkpoints")(with_cache_dir(checkpoints_cmd))
    app.command("convert")(with_cache_dir(convert_cmd))
    # upstream's main
    app.command("preview")(with_cache_dir(preview_cmd))


_register()


def main(argv: Sequence[str] | None = None) -> int:
    """Run ``swm`` on ``argv`` (default: ``sys.argv[1:]``) and return its exit status.

    Sets ``OMP_WAIT_POLICY=PASSIVE`` unless the environment sets it (before torch is imported):
    torch's OpenMP threads otherwise spin while they wait, and when env workers, data loaders
    or other jobs share the cores, a planning step ran 10x slower on a loaded 2-core machine.
    """
    os.environ.setdefault("OMP_WAIT_POLICY", "PASSIVE")
    return typer.main.get_command(app).main(
        args=list(argv) if argv is not None else None, prog_name="swm", standalone_mode=False
    )

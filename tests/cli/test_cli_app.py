"""The ``swm`` app: version, help, logging, and how errors reach the user."""

from __future__ import annotations

import logging
import subprocess
import sys

import pytest
import typer

import stable_worldmodel as swm_pkg
from stable_worldmodel import cli
from stable_worldmodel.cli import root as app_module
from stable_worldmodel.cli.errors import error_line as format_error
from stable_worldmodel.cli.errors import int_in, is_user_error, one_line
from stable_worldmodel.errors import ConfigError, unknown_name


def test_seed_functions_exist():
    for name in ("app", "main", "common", "list_cmd", "show", "delete", "display_dataset_info", "display_world_info"):
        assert callable(getattr(cli, name)), name


def test_version(swm):
    result = swm("--version")
    assert result.exit_code == 0
    assert result.stdout.strip() == f"stable-worldmodel {swm_pkg.__version__}"


def test_version_is_above_upstreams_and_is_the_installed_one():
    """Same distribution name as upstream (0.1.1 on PyPI): a higher version keeps `pip install -U` from
    swapping this package for it; the installed metadata reads the one version string."""
    import importlib.metadata

    assert tuple(int(p) for p in swm_pkg.__version__.split(".")[:3]) > (0, 1, 1)
    assert importlib.metadata.version("stable-worldmodel") == swm_pkg.__version__


def test_version_short_flag_and_main_return_code(capsys):
    assert cli.main(["-V"]) == 0
    assert capsys.readouterr().out.strip() == f"stable-worldmodel {swm_pkg.__version__}"


def test_python_dash_m_version():
    out = subprocess.run(
        [sys.executable, "-m", "stable_worldmodel.cli", "--version"], capture_output=True, text=True, timeout=60
    )
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == f"stable-worldmodel {swm_pkg.__version__}"


def test_cli_import_pulls_in_no_heavy_module():
    probe = (
        "import sys, stable_worldmodel.cli; "
        "print(sorted(m for m in ('torch', 'h5py', 'cv2', 'matplotlib') if m in sys.modules))"
    )
    out = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, check=True, timeout=60)
    assert out.stdout.strip() == "[]"


def test_bare_swm_prints_help_and_succeeds(swm):
    result = swm()
    assert result.exit_code == 0
    for command in ("list", "show", "delete", "collect", "eval", "envs", "fovs", "demo"):
        assert command in result.output


def test_every_command_has_help(swm):
    for command in ("list", "show", "delete", "collect", "eval", "envs", "fovs", "demo"):
        result = swm(command, "--help")
        assert result.exit_code == 0, command
        assert "Example: swm" in result.output, command


def test_unknown_command_is_one_line_with_suggestion(swm, error_line):
    result = swm("colect")
    assert result.exit_code == 2
    line = error_line(result)
    assert "'colect'" in line and "collect" in line


def test_missing_argument_is_one_line(swm, error_line):
    result = swm("fovs")
    assert result.exit_code == 2
    assert "ENV" in error_line(result).upper()


@pytest.mark.parametrize("value", ["abc", "0", "-3"])
def test_bad_number_is_one_line_naming_it(swm, error_line, value):
    result = swm("eval", "swm/Toy-v0", "--episodes", value)
    assert result.exit_code == 2
    line = error_line(result)
    assert "--episodes" in line and value in line and ">= 1" in line


def test_int_in_parser():
    parse = int_in(8, 16)
    assert parse("12") == 12 and parse(8) == 8
    for bad in ("7", "17", "x", "1.5"):
        with pytest.raises(ValueError, match="in \\[8, 16\\]"):
            parse(bad)


def test_one_line_collapses_whitespace_and_pydantic_prefix():
    assert one_line("a\n  b\tc") == "a b c"
    assert one_line("Value error, expected 3") == "expected 3"


def test_user_error_classification():
    def raise_from_numpy():
        import numpy as np

        np.zeros(2).reshape(3)

    with pytest.raises(ValueError) as numpy_error:
        raise_from_numpy()
    assert not is_user_error(numpy_error.value)  # a bug in our code: keep the traceback
    assert is_user_error(ConfigError("x"))  # typed errors always are
    assert is_user_error(unknown_name("thing", "a", ["b"]))
    with pytest.raises(ValueError) as ours:
        int_in(1)("0")  # a plain ValueError raised by stable_worldmodel code itself
    assert is_user_error(ours.value)
    assert not is_user_error(ValueError("never raised"))  # no traceback: origin unknown
    assert not is_user_error(TypeError("t"))
    assert format_error(KeyError("k")) == "Error: unknown key 'k'"


@pytest.fixture
def boom_command():
    """Temporarily add ``swm boom KIND`` raising a user error, a library bug or an outside ValueError."""

    def boom(kind: str) -> None:
        if kind == "user":
            raise ConfigError("Boom requires a valid\nsetting, got 3")
        if kind == "bug":
            raise TypeError("a real bug")
        import numpy as np

        np.zeros(2).reshape(3)  # ValueError raised inside numpy: a bug, not a user error

    app_module.app.command("boom")(boom)
    yield
    app_module.app.registered_commands.pop()
    assert "boom" not in typer.main.get_command(app_module.app).commands


def test_user_error_is_one_line_exit_1(swm, error_line, boom_command):
    result = swm("boom", "user")
    assert result.exit_code == 1
    assert error_line(result) == "Error: Boom requires a valid setting, got 3"


def test_bugs_keep_their_traceback(swm, boom_command):
    result = swm("boom", "bug")
    assert isinstance(result.exception, TypeError)
    result = swm("boom", "numpy")
    assert isinstance(result.exception, ValueError)


def test_swm_debug_shows_user_error_traceback(swm, boom_command, monkeypatch):
    monkeypatch.setenv("SWM_DEBUG", "1")
    result = swm("boom", "user")
    assert isinstance(result.exception, ConfigError)


def test_rich_handler_is_installed_once(swm):
    logger = logging.getLogger("stable_worldmodel")
    before = list(logger.handlers)
    level = logger.level
    try:
        for _ in range(3):
            assert swm("-v", "list", "world").exit_code == 0
        marked = [h for h in logger.handlers if getattr(h, app_module._HANDLER_MARK, False)]
        assert len(marked) == 1
        from rich.logging import RichHandler

        assert isinstance(marked[0], RichHandler)
        assert logger.level == logging.INFO
        swm("-vv", "list", "world")
        assert logger.level == logging.DEBUG
    finally:
        for handler in logger.handlers[:]:
            if handler not in before:
                logger.removeHandler(handler)
        logger.setLevel(level)


@pytest.mark.parametrize("preset, expected", [(None, "PASSIVE"), ("ACTIVE", "ACTIVE")])
def test_main_makes_openmp_threads_wait_passively_unless_told(monkeypatch, capsys, preset, expected):
    if preset is None:
        monkeypatch.delenv("OMP_WAIT_POLICY", raising=False)
    else:
        monkeypatch.setenv("OMP_WAIT_POLICY", preset)
    assert cli.main(["--version"]) == 0
    assert app_module.os.environ["OMP_WAIT_POLICY"] == expected


def test_shell_completion():
    """``swm --install-completion`` / ``--show-completion`` (typer's): the script, and the completions it asks for."""
    import os

    script = subprocess.run(  # typer detects the user's shell; a test process may have none to detect
        [sys.executable, "-m", "stable_worldmodel.cli", "--show-completion", "bash"],
        env={**os.environ, "_TYPER_COMPLETE_TEST_DISABLE_SHELL_DETECTION": "1"},
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert script.returncode == 0 and "_SWM_COMPLETE=complete_bash" in script.stdout, script.stderr

    def complete(words: str) -> list[str]:
        env = {
            **os.environ,
            "_SWM_COMPLETE": "complete_bash",
            "COMP_WORDS": words,
            "COMP_CWORD": str(len(words.split()) - 1),
        }
        out = subprocess.run(
            [sys.executable, "-m", "stable_worldmodel.cli"], env=env, capture_output=True, text=True, timeout=60
        )
        assert out.returncode == 0, out.stderr
        return out.stdout.split()

    assert complete("swm co") == ["collect", "convert"]
    assert "--policy" in complete("swm collect --pol")


def test_every_command_that_reads_the_cache_takes_cache_dir(swm, tmp_path, _stablewm_home):
    """``--cache-dir DIR``: the cache of this invocation (as ``STABLEWM_HOME=DIR``), on every command that
    reads or writes datasets or checkpoints."""
    import os

    import typer.main

    from stable_worldmodel.cli import app

    group = typer.main.get_command(app)
    with_option = {name for name, cmd in group.commands.items() if any(p.name == "cache_dir" for p in cmd.params)}
    assert with_option == set(group.commands) - {"envs", "fovs"}
    other = tmp_path / "other"
    made = swm("collect", "swm/Toy-v0", "-n", "1", "--max-steps", "3", "--image-size", "16", "--cache-dir", str(other))
    assert made.exit_code == 0, made.output
    assert (other / "toy-v0-random.h5").is_file() and not _stablewm_home.exists()
    assert "toy-v0-random" in swm("list", "dataset", "--cache-dir", str(other)).stdout
    assert os.environ["STABLEWM_HOME"] == str(_stablewm_home)  # only for the command

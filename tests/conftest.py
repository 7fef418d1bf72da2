"""Shared fixtures: every test gets its own empty cache directory; the ``swm`` command runner
and its ``error_line`` check; one torch thread for tiny models."""

from __future__ import annotations

import pytest
from typer.testing import CliRunner

from stable_worldmodel.cli import app


@pytest.fixture(autouse=True)
def _stablewm_home(tmp_path, monkeypatch):
    """Point ``STABLEWM_HOME`` at a fresh temp dir so no test touches ``~``."""
    home = tmp_path / "stablewm_home"
    monkeypatch.setenv("STABLEWM_HOME", str(home))
    return home


class Swm:
    """``swm(*args, input=...)`` runs the command in-process and returns Typer's Result."""

    def __init__(self) -> None:
        self.runner = CliRunner()

    def __call__(self, *args: str, input: str | None = None, **kwargs):
        return self.runner.invoke(app, list(args), input=input, prog_name="swm", **kwargs)


@pytest.fixture(autouse=True)
def _start_method():
    """Opening a Lance dataset makes new processes spawn (lance is not fork-safe, see
    stable_worldmodel.data.lance.fork_safe_workers): each test starts with the session's method."""
    import multiprocessing as mp

    before = mp.get_start_method(allow_none=True)
    yield
    if mp.get_start_method(allow_none=True) != before:
        mp.set_start_method(before, force=True)


@pytest.fixture
def swm() -> Swm:
    return Swm()


def _error_line(result) -> str:
    lines = [line for line in result.stderr.splitlines() if line.strip()]
    assert len(lines) == 1, f"expected one error line, got {lines!r}"
    assert lines[0].startswith("Error: "), lines[0]
    assert "Traceback" not in result.output
    assert result.exception is None or isinstance(result.exception, SystemExit), result.exception
    return lines[0]


@pytest.fixture
def error_line():
    """``error_line(result)``: the single ``Error: ...`` line of a failed command (asserted to be one line)."""
    return _error_line


@pytest.fixture
def one_torch_thread():
    """Width-8 models are fastest on one thread; several threads on a busy CPU are 50x slower."""
    import torch

    threads = torch.get_num_threads()
    torch.set_num_threads(1)
    yield
    torch.set_num_threads(threads)


class CompileRecorder:
    """What :func:`compile_recorder` saw: the ``__name__`` of each function given to ``torch.compile``; ``backend``
    runs the captured graphs (``aot_eager``: torch's own kernels, no code generation; ``inductor``: what
    ``torch.compile`` runs by default)."""

    def __init__(self) -> None:
        self.names: list[str] = []
        self.backend = "aot_eager"


@pytest.fixture
def compile_recorder(monkeypatch) -> CompileRecorder:
    """``torch.compile`` patched to record what it compiles and to use the recorder's ``backend``."""
    import torch

    recorder = CompileRecorder()
    real_compile = torch.compile

    def recording_compile(fn, **options):
        recorder.names.append(fn.__name__)
        return real_compile(fn, **{**options, "backend": recorder.backend})

    monkeypatch.setattr(torch, "compile", recording_compile)
    return recorder

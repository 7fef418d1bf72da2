"""Fixtures of the CLI tests: a runner, and small toy datasets recorded by the tests."""

from __future__ import annotations

import pytest
from typer.testing import CliRunner

from stable_worldmodel.cli import app

TOY = "swm/Toy-v0"


class Swm:
    """``swm(*args, input=...)`` runs the command in-process and returns Typer's Result."""

    def __init__(self) -> None:
        self.runner = CliRunner()

    def __call__(self, *args: str, input: str | None = None, **kwargs):
        return self.runner.invoke(app, list(args), input=input, prog_name="swm", **kwargs)


@pytest.fixture
def swm() -> Swm:
    return Swm()


@pytest.fixture
def record_toy():
    """``record_toy(name, episodes=2, variation=None)`` records a 16x16 toy dataset in the cache."""
    from stable_worldmodel import World
    from stable_worldmodel.envs import expert_policy

    def record(name: str, episodes: int = 2, variation: list[str] | None = None):
        with World(TOY, 1, (16, 16), max_episode_steps=20, verbose=0) as world:
            world.set_policy(expert_policy(TOY))
            options = {"variation": variation} if variation else None
            return world.record_dataset(name, episodes=episodes, seed=0, options=options)

    return record


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

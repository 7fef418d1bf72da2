"""Progress of recording and evaluation: a bar in a terminal, plain lines elsewhere (never silent
for long); the evaluation shows its env step while the envs of a batch run together."""

from __future__ import annotations

import re
import sys

import pytest

import stable_worldmodel as swm
from stable_worldmodel.world.progress import progress


def test_a_terminal_gets_a_bar_and_a_log_gets_lines(monkeypatch):
    from tqdm.auto import tqdm

    monkeypatch.setattr(sys.stderr, "isatty", lambda: True, raising=False)
    assert isinstance(progress(3, "x", enabled=True), tqdm)
    monkeypatch.setattr(sys.stderr, "isatty", lambda: False, raising=False)
    assert not isinstance(progress(3, "x", enabled=True), tqdm)
    assert progress(3, "x", enabled=False).disable  # verbose=0: silent either way


def test_no_bar_drawn_imports_no_tqdm():
    """tqdm (and the asyncio it pulls in) costs ~50 ms to import: paid only for a bar drawn."""
    import subprocess

    code = (
        "import sys\n"
        "from stable_worldmodel.world.progress import progress\n"
        "with progress(3, 'x', enabled=False) as bar:\n"
        "    bar.set_postfix_str('y'); bar.update(2)\n"
        "assert bar.n == 2, bar.n\n"
        "progress(3, 'x', enabled=True)  # stderr is a pipe here: lines, not a bar\n"
        "print('tqdm' in sys.modules)\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "False"


@pytest.mark.parametrize("num_envs", [1, 3])
def test_evaluation_and_recording_lines_outside_a_terminal(capsys, monkeypatch, tmp_path, num_envs):
    monkeypatch.setenv("STABLEWM_PROGRESS_SECONDS", "0")  # every update (default: every 30 s)
    monkeypatch.setattr(sys.stderr, "isatty", lambda: False, raising=False)
    world = swm.World("swm/Toy-v0", num_envs, (8, 8), max_episode_steps=4, verbose=1, vectorization_mode="sync")
    world.set_policy(swm.policy.RandomPolicy(seed=0))
    world.evaluate(episodes=3, seed=0)
    lines = capsys.readouterr().err.strip().splitlines()
    pattern = r"evaluate swm/Toy-v0: (\d)/3 ep, \d successes, env step (\d+), \d+ s"
    parsed = [re.fullmatch(pattern, line) for line in lines]
    assert all(parsed), lines
    assert parsed[0][1] == "0" and parsed[0][2] == "1"  # a line before any episode ends
    assert int(parsed[-1][1]) <= 3
    world.record_dataset("p", episodes=2, seed=0, cache_dir=tmp_path)
    recorded = capsys.readouterr().err.strip().splitlines()
    assert re.fullmatch(r"Recording p\.h5: 2/2 ep, \d+ rows/s, \d+ s", recorded[-1]), recorded
    world.close()

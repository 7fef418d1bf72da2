"""Every code block of README.md and of the guides under docs/ runs in the suite, so none can go stale.

Per page, in order, in a fresh working folder and cache (``STABLEWM_HOME``):

- ```python blocks share one namespace; ``print(...)  # -> TEXT`` must print exactly ``TEXT``.
- ```bash blocks run command by command (``\\`` continues a line, ``#`` starts a comment), each one with exit
  status 0 (``swm ...`` in this process, through :func:`stable_worldmodel.cli.main`; anything else through
  ``bash``); counts are made small first (:data:`SMALL`: ``--episodes 50`` runs 2 episodes, ...).
- a block right after ``<!-- docs-test: skip REASON -->`` is not run (a GPU, a cluster, the network);
  ```text / ```console / ```yaml blocks are shown, not run (a ```yaml block after ``<!-- docs-test: file NAME -->``
  is written to NAME for the blocks below it).
"""

from __future__ import annotations

import os
import re
import shlex
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from stable_worldmodel.cli import main

ROOT = Path(__file__).resolve().parents[1]
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").rglob("*.md"))]

#: (pattern, replacement) applied to bash commands: the same command with small counts
SMALL = [
    (r"(?<=\s)(-n|--episodes|--eval-episodes)(\s+|=)\d+", r"\1\g<2>2"),
    (r"(?<=\s)--steps(\s+|=)\d+", r"--steps\g<1>6"),
    (r"(?<=\s)--num-envs(\s+|=)\d+", r"--num-envs\g<1>2"),
    (r"(?<=\s)--samples(\s+|=)\d+", r"--samples\g<1>8"),
    (r"(?<=\s)--iterations(\s+|=)\d+", r"--iterations\g<1>2"),
    (r"(?<=\s)--horizon(\s+|=)\d+", r"--horizon\g<1>2"),
    (r"(?<=\s)--max-steps(\s+|=)\d+", r"--max-steps\g<1>10"),
    (r"(?<=\s)--budget(\s+|=)\d+", r"--budget\g<1>6"),
    (r"(?<=\s)--goal-offset(\s+|=)\d+", r"--goal-offset\g<1>3"),
    (r"(?<=\s)--fov-sweep(\s+)all", r"--fov-sweep\g<1>agent.color"),
]

_BLOCK = re.compile(
    r"(?:<!-- docs-test: (?P<mark>skip|file)\s*(?P<arg>[^>]*?)\s*-->\s*\n)?```(?P<lang>[\w-]*)\n(?P<body>.*?)```", re.S
)
_EXPECT = re.compile(r"^(?P<indent>\s*)print\((?P<args>.*)\)\s+# -> (?P<text>.*?)\s*$")


def blocks(page: Path) -> list[tuple[str, str, str, str]]:
    """``(lang, body, mark, arg)`` of every fenced block of ``page``."""
    return [(m["lang"], m["body"], m["mark"] or "", m["arg"] or "") for m in _BLOCK.finditer(page.read_text())]


def checked_python(body: str) -> str:
    """``body`` with each ``print(ARGS)  # -> TEXT`` turned into a print that must give ``TEXT``."""
    lines = []
    for line in body.splitlines():
        m = _EXPECT.match(line)
        lines.append(f"{m['indent']}__expect__({m['text']!r}, {m['args']})" if m else line)
    return "\n".join(lines)


def _expect(text: str, *args) -> None:
    got = " ".join(str(a) for a in args)
    print(got)
    assert got == text, f"the docs say this prints {text!r}, it printed {got!r}"


def commands(body: str) -> list[str]:
    """The shell commands of a bash block: continuations joined, comments and blank lines dropped."""
    joined = re.sub(r"\s*\\\n\s*", " ", body)
    out = []
    for line in joined.splitlines():
        line = re.sub(r"(^|\s)#.*$", "", line).strip()
        if line:
            out.append(line)
    return out


#: options added to a command that does not give them (its defaults are sized for real runs)
ADDED = {
    "swm eval": ("--samples 8", "--iterations 2", "--max-steps 10"),
    "swm train": ("--steps 6",),
}
#: (pattern, replacement) applied to the files the pages write (sweep files)
SMALL_FILE = [
    (r"(?m)^(episodes|samples|iterations):\s*\d+", r"\1: 2"),
    (r"(?<=samples: )\d+", "8"),
    (r"(?<=iterations: )\d+", "2"),
    (r"(?m)^max_steps:\s*\d+", "max_steps: 10"),
]


def small(command: str) -> str:
    for pattern, replacement in SMALL:
        command = re.sub(pattern, replacement, command)
    for prefix, options in ADDED.items():
        if command.startswith(prefix + " "):
            command += "".join(f" {o}" for o in options if o.split()[0] not in command)
    return command


def small_file(text: str) -> str:
    for pattern, replacement in SMALL_FILE:
        text = re.sub(pattern, replacement, text)
    return text


def _swm_command(command: str) -> tuple[dict[str, str], list[str]] | None:
    """``({VAR: value}, argv)`` of ``[VAR=value ...] swm ARGS`` (run in this process), else None (a shell command)."""
    if any(c in command for c in "|;&<>$`"):
        return None
    parts = shlex.split(command)
    assignments = {}
    while parts and re.fullmatch(r"[A-Za-z_][A-Za-z0-9_]*=.*", parts[0]):
        key, _, value = parts.pop(0).partition("=")
        assignments[key] = value
    return (assignments, parts[1:]) if parts and parts[0] == "swm" else None


def _page_id(page: Path) -> str:
    return page.relative_to(ROOT).as_posix()


RUNNABLE = [p for p in PAGES if any(lang in ("python", "bash") and mark != "skip" for lang, _, mark, _ in blocks(p))]


def test_pages_are_found_and_have_examples():
    names = {_page_id(p) for p in RUNNABLE}
    assert "README.md" in names and len(names) >= 5, names


def test_the_harness_checks_what_it_says():
    assert checked_python("print(1 + 1)  # -> 2") == "__expect__('2', 1 + 1)"
    with pytest.raises(AssertionError, match="prints '3'"):
        _expect("3", 1 + 1)
    assert commands("swm a \\\n   --b 1  # note\n# only a comment\n\nswm c") == ["swm a --b 1", "swm c"]
    assert (
        small("swm eval X -n 50 --samples 300 --max-steps 200")
        == "swm eval X -n 2 --samples 8 --max-steps 10 --iterations 2"
    )
    assert small("swm train lewm --dataset d") == "swm train lewm --dataset d --steps 6"
    assert small("swm collect E --episodes 300 --steps=2000") == "swm collect E --episodes 2 --steps=6"
    assert small_file("episodes: 50\nplan: {solver: cem, samples: 300, iterations: 30}") == (
        "episodes: 2\nplan: {solver: cem, samples: 8, iterations: 2}"
    )
    text = "<!-- docs-test: skip needs a GPU -->\n```bash\nswm x\n```\n```python\nprint(1)\n```\n"
    page = ROOT / "tests" / "_tmp_docs_page.md"
    try:
        page.write_text(text)
        assert blocks(page) == [("bash", "swm x\n", "skip", "needs a GPU"), ("python", "print(1)\n", "", "")]
    finally:
        page.unlink()


@pytest.mark.parametrize("page", RUNNABLE, ids=_page_id)
def test_page_examples_run(page, tmp_path, monkeypatch):
    work = tmp_path / "work"
    work.mkdir()
    home = tmp_path / "home"
    monkeypatch.chdir(work)
    monkeypatch.setenv("STABLEWM_HOME", str(home))
    monkeypatch.setenv("STABLEWM_PROGRESS_SECONDS", "3600")
    env = dict(os.environ)
    env["PATH"] = f"{Path(sys.executable).parent}{os.pathsep}{env.get('PATH', '')}"
    namespace: dict = {"__name__": "__docs__", "__expect__": _expect}
    for lang, body, mark, arg in blocks(page):
        if mark == "skip":
            continue
        if mark == "file":
            (work / arg).write_text(small_file(body))
            continue
        if lang == "python":
            exec(compile(checked_python(body), f"{_page_id(page)} (python block)", "exec"), namespace)  # noqa: S102
        elif lang == "bash":
            for command in commands(body):
                command = small(command)
                swm_args = _swm_command(command)
                if swm_args is not None:  # in this process: no interpreter start-up per command
                    assignments, argv = swm_args
                    with monkeypatch.context() as m:
                        for key, value in assignments.items():
                            m.setenv(key, value)
                        code = main(argv)
                    assert code == 0, f"{_page_id(page)}: `{command}` exited {code} (its output is above)"
                    continue
                done = subprocess.run(
                    ["bash", "-c", command],
                    cwd=work,
                    env=env,
                    capture_output=True,
                    text=True,
                    timeout=300,
                    stdin=subprocess.DEVNULL,
                )
                assert done.returncode == 0, (
                    f"{_page_id(page)}: `{command}` exited {done.returncode}:\n{done.stderr[-3000:]}"
                )
    shutil.rmtree(home, ignore_errors=True)

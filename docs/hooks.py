"""MkDocs hooks: pages generated from the code, so the site cannot drift from it.

- ``reference/cli.md``: ``<!-- swm-cli-reference -->`` becomes the reference of every ``swm`` command and option,
  read from the parser (:func:`stable_worldmodel.cli.reference.markdown_reference`).
- ``envs/<name>.md``: one page per registered environment (its docstring, spaces, factors of variation with their
  ranges and defaults, scripted expert, gallery row when ``docs/images/<name>.png`` exists), and
  ``<!-- env-pages -->`` in ``envs/index.md`` becomes the list of them.
"""

from __future__ import annotations

import inspect
import os
import warnings
from pathlib import Path

from mkdocs.structure.files import File

DOCS = Path(__file__).resolve().parent
_PAGES: dict[str, str] = {}


def _slug(env_id: str) -> str:
    return env_id.split("/", 1)[-1]


def _space_line(space) -> str:
    text = " ".join(repr(space).split())
    return text if len(text) <= 200 else text[:197] + "..."


def _text(doc: str) -> str:
    """A docstring as Markdown: reST literals and roles made code spans, indented blocks kept as code."""
    import re

    doc = re.sub(r":\w+:`~?([^`]+)`", r"`\1`", doc).replace("``", "`")
    return doc + "\n"


def env_page(env_id: str) -> str:
    """The Markdown page of one registered environment."""
    import gymnasium as gym

    from stable_worldmodel.cli.display import describe_factor, factor_leaves
    from stable_worldmodel.envs import get_entry

    entry = get_entry(env_id)
    lines = [f"# `{env_id}`", ""]
    image = DOCS / "images" / f"{_slug(env_id)}.png"
    if image.is_file():
        lines += [f"![{env_id}: default look, then three samples of all its factors](../images/{image.name})", ""]
    module, _, name = entry.entry_point.partition(":")
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            env = gym.make(env_id, disable_env_checker=True)
    except Exception as exc:  # an optional extra that is missing: the page says so
        lines += [f"Not available in the environment that built these docs ({type(exc).__name__}: {exc}).", ""]
        return "\n".join(lines)
    try:
        cls = type(env.unwrapped)
        docs = [inspect.getdoc(inspect.getmodule(cls)) or "", inspect.getdoc(cls) or ""]
        lines += [_text(d) for d in docs if d and "see the module docstring" not in d]
        lines += [
            "| | |",
            "| --- | --- |",
            f"| class | `{module}.{name}` |",
            f"| tags | {', '.join(entry.tags) or '-'} |",
            f"| episode limit | {entry.max_episode_steps or 'none'} |",
            f"| scripted expert | {'`swm.envs.expert_policy(' + repr(env_id) + ')`' if entry.expert else 'none'} |",
            f"| action space | `{_space_line(env.action_space)}` |",
            "",
            "## Observation (infos)",
            "",
            "| key | space |",
            "| --- | --- |",
        ]
        spaces = getattr(env.observation_space, "spaces", {"observation": env.observation_space})
        lines += [f"| `{key}` | `{_space_line(space)}` |" for key, space in spaces.items()]
        leaves = factor_leaves(getattr(env.unwrapped, "variation_space", None))
        lines += ["", f"## Factors of variation ({len(leaves)})", ""]
        if leaves:
            lines += [
                "Resampled per episode with `reset(options={'variation': [NAME, ...]})` or `--variation NAME`.",
                "",
                "| factor | type, range, shape = default |",
                "| --- | --- |",
            ]
            lines += [f"| `{key}` | `{describe_factor(space)}` |" for key, space in leaves.items()]
        else:
            lines.append("None.")
    finally:
        env.close()
    return "\n".join(lines) + "\n"


def on_config(config):
    from stable_worldmodel.envs import list_envs

    for section in config["nav"]:
        if isinstance(section, dict) and "Environments" in section:
            section["Environments"] += [{env_id: f"envs/{_slug(env_id)}.md"} for env_id in list_envs()]
    return config


def on_files(files, config):
    os.environ.setdefault("MUJOCO_GL", "egl")
    from stable_worldmodel.envs import list_envs

    for env_id in list_envs():
        src = f"envs/{_slug(env_id)}.md"
        _PAGES[src] = env_page(env_id)
        files.append(File.generated(config, src, content=_PAGES[src]))
    return files


def on_page_markdown(markdown, page, config, files):
    if "<!-- swm-cli-reference -->" in markdown:
        from stable_worldmodel.cli.reference import markdown_reference

        markdown = markdown.replace("<!-- swm-cli-reference -->", markdown_reference())
    if "<!-- env-pages -->" in markdown:
        rows = ["| environment | page |", "| --- | --- |"]
        rows += [f"| `{p[5:-3]}` | [{p[5:-3]}]({p[5:]}) |" for p in sorted(_PAGES)]
        markdown = markdown.replace("<!-- env-pages -->", "\n".join(rows))
    return markdown

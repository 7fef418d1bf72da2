"""``swm push RUN REPO_ID``: upload a trained run to the Hugging Face Hub
(:func:`~stable_worldmodel.wm.utils.push_to_hub`; needs ``pip install "stable-worldmodel[hub]"``)."""

from __future__ import annotations

from typing import Annotated

import typer


def push_cmd(
    run: Annotated[
        str,
        typer.Argument(
            help="Run to upload: a name in the cache, wm:NAME / gc:NAME, or a path.", metavar="RUN", show_default=False
        ),
    ],
    repo_id: Annotated[
        str,
        typer.Argument(
            help="Hub repo to upload to, USER/REPO (created when missing).", metavar="REPO_ID", show_default=False
        ),
    ],
    private: Annotated[bool, typer.Option("--private", help="Create the repo private (when it is new).")] = False,
    revision: Annotated[
        str | None,
        typer.Option("--revision", metavar="REV", help="Branch to commit to (created when missing). Default: main."),
    ] = None,
    message: Annotated[
        str | None, typer.Option("--message", "-m", metavar="M", help="Commit message.", show_default=False)
    ] = None,
) -> None:
    """Upload a run to the Hugging Face Hub: its weights, config.json, protocol.json and a model card.

    Nothing else of the run folder is uploaded (no train_state.ckpt, step_<N>/ or pickles).

    The token is huggingface_hub's: $HF_TOKEN, or `hf auth login`.

    Load it back with from_pretrained("USER/REPO"), or `swm eval ENV --policy wm:USER/REPO` once downloaded.
    """
    from ..wm.utils import push_to_hub

    info = push_to_hub(run, repo_id, private=private, revision=revision, commit_message=message)
    url = getattr(info, "commit_url", None) or str(info)
    typer.echo(f"Pushed {run} to {repo_id}: {url}")

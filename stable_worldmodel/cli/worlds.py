"""The pipeline commands' view of :mod:`stable_worldmodel.planning.policies` (policies and worlds by
name), plus what only a command does: print the warnings of a run used where it was not trained."""

from __future__ import annotations

from ..planning.policies import (
    checkpoint_run,
    env_action_dim,
)


def check_run_fits(
    policy: str, env_id: str, image_size: int, *, force: bool = False, image_option: str = "--image-size "
) -> None:
    """For a ``wm:`` / ``gc:`` policy: raise :class:`~stable_worldmodel.errors.RunMismatchError`
    when its run cannot act on ``env_id`` at ``image_size`` (another action dimension, or other
    frames unless ``force``), and write one ``Warning:`` line per thing it never saw (another env
    id: silenced by ``force``) and one when the run is partial (the checkpoint of step N of M).
    Done once per command, before any World starts."""
    run = checkpoint_run(policy)
    if run is None:
        return
    from ..planning import run_fit
    from .errors import warn

    facts, protocol = run_fit.run_facts(run)
    lines = run_fit.check_run_fits(
        facts,
        policy,
        env_id=env_id,
        action_dim=env_action_dim(env_id),
        image_size=image_size,
        force=force,
        image_option=image_option,
    )
    note = run_fit.partial_note(policy, protocol)
    for line in [*lines, *([note] if note else [])]:
        warn(line)

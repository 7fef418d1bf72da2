"""Does a trained run fit where it is used? The env, frame size, action dimension and frameskip
a run recorded in its ``protocol.json`` against the ones it is asked to act in.

:func:`check_run_fits` raises :class:`~stable_worldmodel.errors.RunMismatchError` where the run
cannot act (another action dimension or frameskip), or where it would act on frames other than
its own (another image size, unless ``force``), and returns warning lines where planning still
runs but on something the run never saw (another env id with the same actions and frames;
``force`` silences them). :func:`partial_run` tells a run killed before its last step.

Nothing here imports torch; a run is described by its protocol alone.
"""

from __future__ import annotations

import json
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ..errors import RunMismatchError

__all__ = ["RunFacts", "check_run_fits", "partial_note", "partial_run", "run_facts"]

#: what a dataset folder recorded on Ray keeps its env id in (``world.on_ray``)
MANIFEST = "manifest.json"


@dataclass(frozen=True)
class RunFacts:
    """What run ``run`` was trained on, as its ``protocol.json`` records it (None: not recorded).

    ``frame_size`` is ``(H, W)`` of the frames it saw (its dataset's), ``model_size`` the side
    its model resizes them to, ``action_dim`` the env's (one step, not the block), ``frameskip``
    the env steps of one action block."""

    run: str
    env: str | None = None
    dataset: str | None = None
    frame_size: tuple[int, int] | None = None
    model_size: int | None = None
    action_dim: int | None = None
    frameskip: int | None = None

    @classmethod
    def from_protocol(cls, run: str, protocol: Any) -> RunFacts:
        """The facts of ``protocol`` (a :class:`~stable_worldmodel.wm.run.RunProtocol` or its mapping):
        only what it records, so an upstream checkpoint's defaults are not taken for facts."""
        from ..wm.run import RunProtocol

        typed = protocol if isinstance(protocol, RunProtocol) else RunProtocol.from_dict(protocol)
        raw = typed.raw
        recorded_size = "dataset_image_shape" in raw or "image_size" in raw
        no_frames = raw.get("dataset_image_shape") == []  # a state-input model: no image size to match
        return cls(
            run=run,
            env=typed.env or _manifest_env(typed.dataset_path),
            dataset=typed.dataset,
            frame_size=typed.frame_size if recorded_size and not no_frames else None,
            model_size=typed.image_size if "image_size" in raw and not no_frames else None,
            action_dim=typed.action_dim,
            frameskip=typed.frameskip if "frameskip" in raw else None,
        )

    def trained_on(self) -> str:
        """``"dataset 'toy' of swm/Toy-v0"``, as much of it as is recorded."""
        parts = []
        if self.dataset:
            parts.append(f"dataset {self.dataset!r}")
        if self.env:
            parts.append(("of " if parts else "") + self.env)
        return " ".join(parts) or "its training data"


def _manifest_env(path: str | None) -> str | None:
    """The env id in the manifest of a dataset folder recorded on Ray (None: none there)."""
    if path:
        manifest = Path(path) / MANIFEST
        try:
            env = json.loads(manifest.read_text()).get("env") if manifest.is_file() else None
        except (OSError, ValueError, AttributeError):
            env = None
        if env:
            return str(env)
    return None


def run_facts(run: str, cache_dir: str | None = None) -> tuple[RunFacts, dict[str, Any]]:
    """``(facts, protocol)`` of checkpoint ``run`` (an upstream checkpoint without a protocol: nothing recorded)."""
    from ..wm.run import Run

    protocol = Run.open(run, cache_dir).protocol
    return RunFacts.from_protocol(run, protocol), protocol.to_dict()


def partial_run(protocol: dict[str, Any]) -> tuple[int, int] | None:
    """``(steps_done, steps)`` of a run stopped before its last step (its ``final`` absent or null,
    ``steps_done < steps``: :attr:`~stable_worldmodel.wm.run.RunProtocol.partial`), else None."""
    from ..wm.run import RunProtocol

    typed = RunProtocol.from_dict(protocol)
    return (typed.steps_done, typed.steps) if typed.partial else None


def check_run_fits(
    facts: RunFacts,
    who: str,
    *,
    env_id: str | None = None,
    action_dim: int | None = None,
    image_size: int | None = None,
    frameskip: int | None = None,
    force: bool = False,
    image_option: str = "--image-size ",
    frameskip_option: str = "frameskip=",
) -> list[str]:
    """Check that ``facts``' run can act as ``who`` (``"wm:RUN"``...) on ``env_id`` (whose actions
    have ``action_dim`` numbers), with ``image_size`` square frames and action blocks of ``frameskip``
    env steps (None: not checked). Returns the warning lines (empty under ``force``). The messages
    spell values as ``image_option`` / ``frameskip_option`` followed by the value (``"--image-size "``,
    ``"frameskip="``, ``"image_size: "``).

    Raises :class:`~stable_worldmodel.errors.RunMismatchError` naming both values and the fix
    on another action dimension or frameskip, and on another image size unless ``force``.
    """
    run, env_note = facts.run, (f" of {env_id}" if env_id else "")
    if action_dim is not None and facts.action_dim is not None and int(action_dim) != facts.action_dim:
        home = facts.env or "the env its dataset was recorded from"
        raise RunMismatchError(
            f"{who} requires an env with {facts.action_dim}-dim actions "
            f"(run {run!r} was trained on {facts.trained_on()}), "
            f"got {env_id or 'an env'} with {int(action_dim)}-dim actions; evaluate it on {home}, or train a run on a "
            f"dataset{env_note} (swm collect {env_id or 'ENV'} --policy expert, then swm train)"
        )
    if frameskip is not None and facts.frameskip is not None and int(frameskip) != facts.frameskip:
        raise RunMismatchError(
            f"{who} requires {frameskip_option}{facts.frameskip} (run {run!r} was trained on action blocks of "
            f"{facts.frameskip} env steps), got {frameskip_option}{int(frameskip)}; drop {_bare(frameskip_option)} (it "
            f"defaults to the run's), or train a run with --frameskip {int(frameskip)}"
        )
    if (
        image_size is not None
        and facts.frame_size is not None
        and (int(image_size),) * 2 != facts.frame_size
        and not force
    ):
        h, w = facts.frame_size
        resized = (
            f" (frames are then resized to the model's {facts.model_size}x{facts.model_size})"
            if facts.model_size
            else ""
        )
        raise RunMismatchError(
            f"{who} requires {image_option}{h} (run {run!r} was trained on {h}x{w} frames of {facts.trained_on()}), "
            f"got {image_option}{int(image_size)}; drop {_bare(image_option)} (it defaults to the run's) "
            f"or set it to {h}, "
            f"or pass --force to evaluate at {int(image_size)}x{int(image_size)} anyway{resized}"
        )
    warnings = []
    if env_id is not None and facts.env is not None and env_id != facts.env and not force:
        same = []
        if facts.action_dim is not None:
            same.append(f"{facts.action_dim}-dim actions")
        if facts.frame_size is not None and image_size is not None:
            same.append("{}x{} frames".format(*facts.frame_size))
        why = f"the same {' and '.join(same)}, so it plans" if same else "it plans"
        warnings.append(
            f"{who} was trained on {facts.env} (dataset {facts.dataset!r}), got {env_id}: {why}, "
            f"but on an env it never saw; pass --force to silence this warning"
        )
    return warnings


def _bare(option: str) -> str:
    """``"--image-size "`` -> ``"--image-size"``, ``"frameskip="`` -> ``"frameskip"``."""
    return option.rstrip(" =:")


def partial_note(who: str, protocol: dict[str, Any]) -> str | None:
    """The line that says a partial run acts with the checkpoint of its last saved step (None: a finished run)."""
    partial = partial_run(protocol)
    if partial is None:
        return None
    done, steps = partial
    name = who.split(":", 1)[-1]
    run, _, leaf = name.rpartition("/")
    if run and (leaf == "best" or re.fullmatch(r"step_\d+", leaf)):  # a snapshot the Trainer keeps in RUN/
        return f"{who} is a checkpoint kept while {run} trained: step {done} of {steps}"
    return (
        f"{who} uses the checkpoint of step {done} of {steps} (partial run: training stopped before its last step; "
        f"continue it with swm train ... --name {name} --resume)"
    )

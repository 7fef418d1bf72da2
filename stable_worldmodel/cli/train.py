"""``swm train``: train a world model on a recorded dataset (see :func:`stable_worldmodel.train.train`)."""

from __future__ import annotations

from typing import Annotated

import typer

from .errors import int_in


def _float_pos(value: str) -> float:
    try:
        number = float(value)
    except ValueError as exc:
        raise typer.BadParameter(f"requires a number, got {value!r}") from exc
    if not number > 0:
        raise typer.BadParameter(f"requires a number > 0, got {value!r}")
    return number


def _config_override(value: str) -> tuple[str, object]:
    from ..errors import ConfigError
    from ..wm.config import parse_override

    try:
        return parse_override(value)
    except ConfigError as exc:
        raise typer.BadParameter(str(exc)) from None


#: the train() arguments that are also flags of swm train (``--set KEY=VALUE`` routes there): key -> flag
FLAGS = {
    "model": "MODEL",
    "dataset": "--dataset",
    "preset": "--preset",
    "steps": "--steps",
    "epochs": "--epochs",
    "batch_size": "--batch-size",
    "lr": "--lr",
    "device": "--device",
    "precision": "--precision",
    "name": "--name",
    "seed": "--seed",
    "resume": "--resume",
    "init_from": "--init-from",
    "eval_every": "--eval-every",
    "eval_episodes": "--eval-episodes",
    "eval_env": "--eval-env",
    "frameskip": "--frameskip",
    "source": "--from",
}
#: how a ``--set`` value of a flag is checked: what the flag's own parser accepts
_FLAG_PARSERS = {
    "steps": int_in(1),
    "batch_size": int_in(1),
    "seed": int_in(0),
    "frameskip": int_in(1),
    "lr": _float_pos,
    "epochs": _float_pos,
    "eval_every": int_in(1),
    "eval_episodes": int_in(1),
}


def _resume_command(model: str, run: str) -> str:
    """This command line with ``--resume`` (when it ran as ``swm`` / ``python -m stable_worldmodel.cli``),
    else the shortest one that resumes run ``run``."""
    import shlex
    import sys
    from pathlib import Path

    argv = list(sys.argv)
    if argv and (Path(argv[0]).name == "swm" or argv[0].endswith(("stable_worldmodel/cli/__main__.py", "-m"))):
        args = [a for a in argv[1:] if a != "--resume"]
        return shlex.join(["swm", *args, "--resume"])
    return shlex.join(["swm", "train", model, "--name", run, "--resume"]) + "  (with the options of the first run)"


def _set_value(key: str, value: object) -> object:
    """A ``--set`` value of flag ``key`` checked and converted as the flag would be."""
    from ..errors import ConfigError

    parse = _FLAG_PARSERS.get(key)
    if parse is None:
        if key in (
            "model",
            "dataset",
            "preset",
            "device",
            "precision",
            "name",
            "source",
            "init_from",
        ) and not isinstance(value, str):
            raise ConfigError(f"swm train --set {key} requires a name, got {value!r}; or use {FLAGS[key]}")
        if key == "resume" and not isinstance(value, bool):
            raise ConfigError(f"swm train --set resume requires true or false, got {value!r}; or use --resume")
        return value
    if isinstance(value, bool) or not isinstance(value, (int, float, str)):
        raise ConfigError(f"swm train --set {key} requires a number, got {value!r}")
    try:
        return parse(str(value))
    except (ValueError, typer.BadParameter) as exc:
        text = (exc.message if isinstance(exc, typer.BadParameter) else str(exc)).replace("expected ", "requires ", 1)
        raise ConfigError(f"swm train --set {key} {text}") from None


def merge_settings(
    flags: dict[str, object], given: set[str], settings: dict[str, object]
) -> tuple[dict[str, object], dict[str, object]]:
    """``(flags, overrides)``: ``--set`` items of :data:`FLAGS` keys moved into ``flags`` (the same
    place as the flag), the others left as config overrides. A key set by both its flag (in
    ``given``) and ``--set`` must have one value, else :class:`~stable_worldmodel.errors.ConfigError`
    naming both."""
    from ..errors import ConfigError

    flags, overrides = dict(flags), {}
    for key, value in settings.items():
        if key not in FLAGS:
            overrides[key] = value
            continue
        value = _set_value(key, value)
        if key in given and flags[key] != value:
            raise ConfigError(
                f"swm train requires one value for {key}, got {FLAGS[key]} {flags[key]!r} and --set {key}={value!r}; "
                f"drop one of them"
            )
        flags[key] = value
    return flags, overrides


def _given(ctx: typer.Context, param: str) -> bool:
    """Whether option ``param`` came from the command line (or an env var), not its default."""
    source = ctx.get_parameter_source(param)
    return source is not None and source.name not in ("DEFAULT", "DEFAULT_MAP")


def train_cmd(
    ctx: typer.Context,
    model: Annotated[
        str,
        typer.Argument(
            help=(
                "Model to train: lewm, pldm, prejepa, tdmpc2, dreamer, dummy (world models), gcbc, gcivl, gciql "
                "(goal-conditioned policies) or frame (a decoder of another run's latents, with --from RUN)."
            ),
            metavar="MODEL",
            show_default=False,
        ),
    ],
    dataset: Annotated[
        str | None,
        typer.Option(
            "--dataset",
            "-d",
            metavar="NAME",
            help="Dataset in the cache (see `swm list dataset`); a frame decoder defaults to its source run's.",
            show_default=False,
        ),
    ] = None,
    preset: Annotated[
        str,
        typer.Option(
            "--preset", metavar="PRESET", help="Sizes and recipe: tiny (CPU, minutes), small (GPU), paper (upstream's)."
        ),
    ] = "tiny",
    steps: Annotated[
        int | None,
        typer.Option(
            "--steps",
            parser=int_in(1),
            metavar="N",
            help="Optimizer steps (default: the preset's).",
            show_default=False,
        ),
    ] = None,
    epochs: Annotated[
        float | None,
        typer.Option(
            "--epochs",
            parser=_float_pos,
            metavar="E",
            help="Passes over the train samples (instead of --steps).",
            show_default=False,
        ),
    ] = None,
    batch_size: Annotated[
        int | None,
        typer.Option(
            "--batch-size",
            parser=int_in(1),
            metavar="B",
            help="Samples per step (default: the preset's).",
            show_default=False,
        ),
    ] = None,
    lr: Annotated[
        float | None,
        typer.Option(
            "--lr",
            parser=_float_pos,
            metavar="LR",
            help="Peak learning rate (default: the preset's).",
            show_default=False,
        ),
    ] = None,
    device: Annotated[str, typer.Option("--device", metavar="DEV", help="auto, cpu, cuda, cuda:N or mps.")] = "auto",
    precision: Annotated[str, typer.Option("--precision", metavar="P", help="32, bf16 or 16 (16 needs CUDA).")] = "32",
    name: Annotated[
        str | None,
        typer.Option(
            "--name", "--run", metavar="RUN", help="Run name (default: <dataset>-<model>).", show_default=False
        ),
    ] = None,
    seed: Annotated[
        int,
        typer.Option(
            "--seed",
            parser=int_in(0),
            metavar="SEED",
            help="Seed of the initial weights, the train/validation split of the episodes and the batches.",
        ),
    ] = 0,
    resume: Annotated[
        bool,
        typer.Option(
            "--resume",
            help=(
                "Continue the run RUN from its last checkpoint (to its planned steps; with a larger --steps, extend "
                "it: the learning-rate schedule becomes the new total's)."
            ),
        ),
    ] = False,
    eval_every: Annotated[
        int | None,
        typer.Option(
            "--eval-every",
            parser=int_in(1),
            metavar="K",
            help=(
                "Evaluate the checkpoint every K steps and at the end (success rate with its 95% CI in the metrics; "
                "the best kept as RUN/best, for swm eval --policy wm:RUN/best)."
            ),
            show_default=False,
        ),
    ] = None,
    eval_episodes: Annotated[
        int,
        typer.Option(
            "--eval-episodes", parser=int_in(1), metavar="N", help="With --eval-every: episodes per evaluation."
        ),
    ] = 10,
    eval_env: Annotated[
        str | None,
        typer.Option(
            "--eval-env",
            metavar="ENV",
            help="With --eval-every: the env to evaluate in (default: the dataset's).",
            show_default=False,
        ),
    ] = None,
    init_from: Annotated[
        str | None,
        typer.Option(
            "--init-from",
            metavar="RUN",
            help="Start from run RUN's weights (fine-tune; same model and sizes) instead of a fresh initialisation.",
            show_default=False,
        ),
    ] = None,
    frameskip: Annotated[
        int | None,
        typer.Option(
            "--frameskip",
            parser=int_in(1),
            metavar="K",
            help="Env steps per model step (the action block).",
            show_default=False,
        ),
    ] = None,
    source: Annotated[
        str | None,
        typer.Option(
            "--from",
            metavar="RUN",
            help=(
                "frame only: the run whose latents the decoder learns to turn into frames "
                "(run name default: RUN-frame)."
            ),
            show_default=False,
        ),
    ] = None,
    online: Annotated[
        str | None,
        typer.Option(
            "--online",
            metavar="ENV",
            help=(
                "Train online in ENV instead of on a dataset: collect with the model's actor, train on a replay "
                "buffer, repeat (models with an actor: tdmpc2, gcbc, gcivl, gciql)."
            ),
            show_default=False,
        ),
    ] = None,
    seed_episodes: Annotated[
        int, typer.Option("--seed-episodes", parser=int_in(1), metavar="N", help="--online: random episodes first.")
    ] = 8,
    collect_every: Annotated[
        int,
        typer.Option(
            "--collect-every", parser=int_in(1), metavar="N", help="--online: training steps between collections."
        ),
    ] = 100,
    episodes_per_collect: Annotated[
        int,
        typer.Option(
            "--episodes-per-collect", parser=int_in(1), metavar="N", help="--online: episodes per collection."
        ),
    ] = 2,
    num_envs: Annotated[
        int, typer.Option("--num-envs", parser=int_in(1), metavar="N", help="--online: envs collecting together.")
    ] = 1,
    max_steps: Annotated[
        int, typer.Option("--max-steps", parser=int_in(1), metavar="N", help="--online: steps per episode at most.")
    ] = 100,
    settings: Annotated[
        list[str] | None,
        typer.Option(
            "--set",
            metavar="KEY=VALUE",
            help=(
                "A config field of the model (repeatable), e.g. --set proprio_dim=2; VALUE is read as JSON when it "
                "parses (see `swm show model MODEL` for the fields). A key that is also a flag (lr, steps, "
                "batch_size, seed, device, frameskip...) sets that flag: giving both takes one value."
            ),
            show_default=False,
        ),
    ] = None,
) -> None:
    """Train MODEL on a recorded dataset (or online in an env: --online ENV); the checkpoint goes to
    $STABLEWM_HOME/checkpoints/RUN.

    Example: swm train lewm --dataset tworoom --preset tiny --name tr-lewm
    (any config field: --set KEY=VALUE,
    e.g. swm train tdmpc2 --dataset tr2 --set proprio_dim=2 --set goal_proprio_dim=2)
    (then: swm eval swm/TwoRoom-v2 --policy wm:tr-lewm; a gcbc / gcivl / gciql run: --policy gc:RUN;
    swm train frame --from tr-lewm trains the decoder that swm eval --video shows the predictions with).
    Several processes (DDP; --batch-size is the global batch):
    torchrun --nproc-per-node N -m stable_worldmodel.cli train ...
    """
    import os
    import sys

    from ..train import train
    from ..wm import get_config_class
    from .display import console

    flags = {
        "model": model,
        "dataset": dataset,
        "preset": preset,
        "steps": steps,
        "epochs": epochs,
        "batch_size": batch_size,
        "lr": lr,
        "device": device,
        "precision": precision,
        "name": name,
        "seed": seed,
        "resume": resume,
        "init_from": init_from,
        "eval_every": eval_every,
        "eval_episodes": eval_episodes,
        "eval_env": eval_env,
        "frameskip": frameskip,
        "source": source,
    }
    given = {k for k in flags if k != "model" and _given(ctx, k)} | {"model"}
    flags, overrides = merge_settings(flags, given, dict(_config_override(item) for item in settings or []))
    model, dataset, preset, source = flags.pop("model"), flags.pop("dataset"), flags.pop("preset"), flags["source"]
    for key in ("frameskip", "source"):  # config fields
        if flags[key] is not None:
            overrides[key] = flags[key]
        del flags[key]
    if online is not None:
        if dataset is not None or flags["epochs"] is not None:
            raise typer.BadParameter("--online takes no --dataset or --epochs", param_hint="--online")
        from ..train.online import train_online

        if flags.pop("init_from") is not None:
            raise typer.BadParameter("trains online from a fresh model: drop --init-from", param_hint="--online")
        if flags.pop("eval_every") is not None:
            raise typer.BadParameter("logs its own collections' success: drop --eval-every", param_hint="--online")
        flags.pop("eval_episodes"), flags.pop("eval_env")
        overrides.setdefault("progress", sys.stderr.isatty())
        for key in ("epochs", "precision"):
            flags.pop(key)
        result = train_online(
            model,
            online,
            preset,
            seed_episodes=seed_episodes,
            collect_every=collect_every,
            episodes_per_collect=episodes_per_collect,
            num_envs=num_envs,
            max_episode_steps=max_steps,
            **flags,
            **overrides,
        )
        last = next((r for r in reversed(result.history) if "online/return" in r), None)
        stats = (
            f", last collection: return {last['online/return']:.2f}, success {100 * last['online/success']:.0f}%"
            if last
            else ""
        )
        prefix = get_config_class(model).eval_prefix
        console().print(
            f"Trained {model} ({preset}) online in {online}: {result.steps} steps in {result.seconds:.0f} s{stats}. "
            f"Checkpoint: {result.folder} ({'plan' if prefix == 'wm' else 'act'} with: swm eval {online} "
            f"--policy {prefix}:{result.run}); replay buffer: {result.folder / 'replay.h5'}",
            soft_wrap=True,
        )
        return
    if dataset is None and source is None:
        raise typer.BadParameter("requires --dataset NAME (or --from RUN for a frame decoder)", param_hint="--dataset")
    overrides.setdefault("progress", sys.stderr.isatty())
    out = console()
    try:
        result = train(model, dataset, preset, **flags, **overrides)
    except KeyboardInterrupt as exc:
        if not hasattr(exc, "swm_run"):
            raise
        run, folder, step, steps, saved = exc.swm_run
        where = f"checkpoint at step {step} saved in {folder}" if saved else f"the last checkpoint in {folder} stands"
        sys.stderr.write(
            f"Interrupted at step {step} of {steps}: {where}. Resume with:\n  {_resume_command(model, run)}\n"
        )
        raise typer.Exit(130) from None
    if os.environ.get("RANK", "0") != "0":  # torchrun: process 0 reports
        return
    val = f"{result.val_loss:.4f}" if result.val_loss is not None else "n/a"
    out.print(
        f"Trained {model} ({preset}) on {dataset or 'the dataset of ' + str(source)}: "
        f"{result.steps} steps in {result.seconds:.0f} s "
        f"({result.samples_per_second:.0f} samples/s), train loss {result.train_loss:.4f}, val loss {val}",
        soft_wrap=True,
    )
    prefix = get_config_class(model).eval_prefix
    how = f"{'plan' if prefix == 'wm' else 'act'} with: swm eval ENV --policy {prefix}:{result.run}"
    if model == "frame":
        from ..wm.frame.config import decoder_usage

        how = f"shows what {source} predicts: {decoder_usage(result.run, source)}"
    if result.features is not None:
        out.print(f"Frozen encoder: {result.features.describe()}", soft_wrap=True)
    out.print(f"Checkpoint: {result.folder} ({how}); loss curve: {result.folder / 'loss.png'}", soft_wrap=True)
    evals = [r for r in result.history if "eval/success_rate" in r]
    if evals:
        best = max(evals, key=lambda r: r["eval/success_rate"])  # the first of equals: the one kept
        last = evals[-1]
        out.print(
            f"Evaluations: last {last['eval/success_rate']:.1f}% [{last['eval/ci95_low']:.1f}, "
            f"{last['eval/ci95_high']:.1f}] at step {last['step']}; best {best['eval/success_rate']:.1f}% at step "
            f"{best['step']} (swm eval ENV --policy wm:{result.run}/best)",
            soft_wrap=True,
        )

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
    "compile": "--compile",
    "name": "--name",
    "seed": "--seed",
    "resume": "--resume",
    "init_from": "--init-from",
    "eval_every": "--eval-every",
    "eval_episodes": "--eval-episodes",
    "eval_env": "--eval-env",
    "eval_protocol": "--eval-protocol",
    "frameskip": "--frameskip",
    "source": "--from",
    "logger": "--logger",
    "wandb_project": "--wandb-project",
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


#: the flags whose value is a name (a string)
_NAME_KEYS = (
    "model",
    "dataset",
    "preset",
    "device",
    "precision",
    "name",
    "source",
    "init_from",
    "logger",
    "wandb_project",
    "eval_protocol",
)


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


def _set_value(key: str, value: object, origin: str = "--set") -> object:
    """A ``--set`` value (or a ``--config`` file's: ``origin``) of flag ``key`` checked and converted as the
    flag would be."""
    from ..errors import ConfigError

    parse = _FLAG_PARSERS.get(key)
    if parse is None:
        if key in _NAME_KEYS and not isinstance(value, str):
            raise ConfigError(f"swm train {origin} {key} requires a name, got {value!r}; or use {FLAGS[key]}")
        if key == "resume" and not isinstance(value, bool):
            raise ConfigError(f"swm train {origin} resume requires true or false, got {value!r}; or use --resume")
        return value
    if isinstance(value, bool) or not isinstance(value, (int, float, str)):
        raise ConfigError(f"swm train {origin} {key} requires a number, got {value!r}")
    try:
        return parse(str(value))
    except (ValueError, typer.BadParameter) as exc:
        text = (exc.message if isinstance(exc, typer.BadParameter) else str(exc)).replace("expected ", "requires ", 1)
        raise ConfigError(f"swm train {origin} {key} {text}") from None


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


#: a number PyYAML leaves as a string (YAML 1.1 wants a dot in ``1.0e-3``; ``1e-3`` is read as text)
_YAML_FLOAT = r"[-+]?(\d+\.?\d*|\.\d+)[eE][-+]?\d+"


def accepted_train_keys() -> list[str]:
    """The keys of ``swm train --set`` / ``--config`` besides the model's config fields (``frameskip``
    and ``source``, flags too, are fields): :func:`~stable_worldmodel.train.train`'s arguments, the
    flags' (``steps``, ``lr``...) and the trainer's without a flag (``ckpt_every``, ``log_every``...)."""
    from ..train import PYTHON_ONLY_KEYS, TRAIN_KEY_HELP

    return [k for k in TRAIN_KEY_HELP if k not in PYTHON_ONLY_KEYS]


def load_config_file(path: str, model: str) -> dict[str, object]:
    """The settings of ``swm train --config FILE`` (YAML, or JSON for a ``.json`` file): a mapping of
    the keys ``--set`` takes, a nested mapping standing for dotted keys (``predictor: {depth: 2}`` is
    ``predictor.depth``) unless its key is a training key or a field of the model (a field that holds
    a mapping, such as ``vit_overrides``, takes it whole). Flattened, in the file's order; an unknown key
    is a :class:`~stable_worldmodel.errors.ConfigError` naming the file, the key and a "did you mean"."""
    import json
    import re
    from pathlib import Path

    from ..errors import ConfigError, did_you_mean
    from ..wm import get_config_class

    file = Path(path).expanduser()
    if not file.is_file():
        why = "is a folder" if file.is_dir() else "does not exist"
        raise ConfigError(f"swm train --config requires a YAML or JSON file, got {str(path)!r}, which {why}")
    try:
        text = file.read_text()
    except (OSError, UnicodeDecodeError) as exc:
        raise ConfigError(f"swm train --config requires a readable text file, got {file} ({exc})") from exc
    yaml_file = file.suffix.lower() != ".json"
    if not yaml_file:
        try:
            data = json.loads(text)
        except json.JSONDecodeError as exc:
            raise ConfigError(f"swm train --config requires valid JSON in {file}, got {exc}") from None
    else:
        import yaml

        try:
            data = yaml.safe_load(text)
        except yaml.YAMLError as exc:
            raise ConfigError(f"swm train --config requires valid YAML in {file}, got {exc}") from None
    data = {} if data is None else data
    if not isinstance(data, dict):
        raise ConfigError(f"swm train --config requires a mapping of KEY: VALUE in {file}, got a {type(data).__name__}")
    cls = get_config_class(model)
    train_keys = set(accepted_train_keys())
    fields = set(cls.field_help())
    flat: dict[str, object] = {}

    def walk(prefix: str, mapping: dict) -> None:
        for name, value in mapping.items():
            if not isinstance(name, str) or not name:
                raise ConfigError(f"swm train --config requires names as the keys of {file}, got {name!r}")
            key = prefix + name
            if isinstance(value, dict) and value and key not in train_keys and key not in fields:
                walk(key + ".", value)
                continue
            if yaml_file and key not in _NAME_KEYS and isinstance(value, str) and re.fullmatch(_YAML_FLOAT, value):
                value = float(value)
            flat[key] = value

    walk("", data)
    accepted = sorted(train_keys | fields)
    for key in flat:
        if key in train_keys or cls.unknown_key(key) is None:
            continue
        leaf = key.rpartition(".")[2]  # predictor.depth: the field is depth
        hint = f" Did you mean {leaf!r}?" if leaf != key and leaf in accepted else did_you_mean(key, accepted)
        raise ConfigError(
            f"swm train --config {file} has an unknown key {key!r}.{hint} Accepted: the flags' keys (dataset, steps, "
            f"lr, batch_size, seed...), the trainer's (ckpt_every, log_every, val_every...) and the fields of "
            f"{cls.__name__} (see swm show model {model})"
        )
    return flat


def apply_config_file(
    flags: dict[str, object], given: set[str], settings: dict[str, object], origin: str
) -> tuple[dict[str, object], dict[str, object], list[str]]:
    """``(flags, overrides, overridden)``: a config file's ``settings`` applied under the flags given on
    the command line (``given``: they win, their keys listed in ``overridden``); flag keys checked as
    ``--set`` checks them, the others left as overrides."""
    flags, overrides, overridden = dict(flags), {}, []
    for key, value in settings.items():
        if key not in FLAGS:
            overrides[key] = value
            continue
        value = _set_value(key, value, origin)
        if key in given:
            overridden.append(key)
        else:
            flags[key] = value
    return flags, overrides, overridden


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
            "--preset",
            metavar="PRESET",
            help="Sizes and recipe: tiny (CPU, minutes), cpu (LeWM, PLDM on a CPU, under an hour), small (GPU), "
            "paper (upstream's).",
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
    compile_loss: Annotated[
        bool,
        typer.Option(
            "--compile",
            help="Run the training step through torch.compile (compiled on the first step: worth it for long runs).",
        ),
    ] = False,
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
        int | None,
        typer.Option(
            "--eval-episodes",
            parser=int_in(1),
            metavar="N",
            help="With --eval-every: episodes per evaluation (default 10; under --eval-protocol, the protocol's).",
            show_default=False,
        ),
    ] = None,
    eval_protocol: Annotated[
        str | None,
        typer.Option(
            "--eval-protocol",
            metavar="NAME",
            help=(
                "With --eval-every: evaluate as swm eval --protocol NAME does (upstream: its planner, goal offset "
                "and budget, from the run's validation episodes); eval/train_seconds gives the success curve "
                "against training time."
            ),
            show_default=False,
        ),
    ] = None,
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
    logger: Annotated[
        str,
        typer.Option(
            "--logger",
            metavar="LOGGER",
            help=(
                "Where the metrics go besides metrics.jsonl/metrics.csv: tensorboard, wandb (TensorBoard and a "
                "Weights & Biases run; WANDB_MODE=offline logs without a network) or none."
            ),
        ),
    ] = "tensorboard",
    wandb_project: Annotated[
        str | None,
        typer.Option(
            "--wandb-project",
            metavar="PROJECT",
            help="--logger wandb: the W&B project (default: $WANDB_PROJECT, else stable-worldmodel).",
            show_default=False,
        ),
    ] = None,
    config_file: Annotated[
        str | None,
        typer.Option(
            "--config",
            metavar="FILE",
            help=(
                "A YAML (or JSON) file of the keys --set takes (flags' keys, trainer keys such as ckpt_every, config "
                "fields; nested mappings are dotted keys); --set and the flags given override it."
            ),
            show_default=False,
        ),
    ] = None,
    settings: Annotated[
        list[str] | None,
        typer.Option(
            "--set",
            metavar="KEY=VALUE",
            help=(
                "A config field of the model or a training key (repeatable), e.g. --set proprio_dim=2 or --set "
                "ckpt_every=500; VALUE is read as JSON when it parses (see `swm show model MODEL` for every key and "
                "its meaning; vit_overrides.hidden_size=96 sets one entry of a mapping field). A key that is also a "
                "flag (lr, steps, batch_size, seed, device, frameskip...) sets that flag: giving both takes one value."
            ),
            show_default=False,
        ),
    ] = None,
) -> None:
    """Train MODEL on a recorded dataset (or online in an env: --online ENV); the checkpoint goes to
    $STABLEWM_HOME/checkpoints/RUN.

    Example: swm train lewm --dataset tworoom --preset tiny --name tr-lewm
    (any config field: --set KEY=VALUE,
    e.g. swm train tdmpc2 --dataset tr2 --set proprio_dim=2 --set goal_proprio_dim=2;
    or a file of them: --config run.yaml, under --set and the flags given; every key with its meaning:
    swm show model MODEL; W&B: --logger wandb, WANDB_MODE=offline without a network)
    (then: swm eval swm/TwoRoom-v2 --policy wm:tr-lewm; a gcbc / gcivl / gciql run: --policy gc:RUN;
    swm train frame --from tr-lewm trains the decoder that swm eval --video shows the predictions with).
    Several processes (DDP; --batch-size is the global batch):
    torchrun --nproc-per-node N -m stable_worldmodel.cli train ...
    """
    import os
    import sys
    from pathlib import Path

    from ..errors import ConfigError
    from ..train import PYTHON_ONLY_KEYS, train
    from ..train.run import check_logger
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
        "compile": compile_loss,
        "name": name,
        "seed": seed,
        "resume": resume,
        "init_from": init_from,
        "eval_every": eval_every,
        "eval_episodes": eval_episodes,
        "eval_env": eval_env,
        "eval_protocol": eval_protocol,
        "frameskip": frameskip,
        "source": source,
        "logger": logger,
        "wandb_project": wandb_project,
    }
    given = {k for k in flags if k != "model" and _given(ctx, k)} | {"model"}
    from_set = dict(_config_override(item) for item in settings or [])
    record: dict[str, object] = {}  # what protocol.json records of the config file
    from_file_overrides: dict[str, object] = {}
    if config_file is not None:  # under --set, under the flags given
        from_file = load_config_file(config_file, model)
        flags, from_file_overrides, overridden = apply_config_file(flags, given, from_file, f"--config {config_file}:")
        overridden += [key for key in from_file if key in from_set and key not in overridden]
        record["train_config"] = {
            "file": str(Path(config_file).expanduser().resolve()),
            "applied": {k: v for k, v in from_file.items() if k not in overridden},
            "overridden": overridden,
        }
    flags, overrides = merge_settings(flags, given, from_set)
    overrides = {**from_file_overrides, **overrides}
    for key in PYTHON_ONLY_KEYS:
        if key in overrides:
            raise ConfigError(f"swm train takes no {key} (an argument of the Python API train() only)")
    check_logger(flags["logger"])  # before anything is loaded (wandb must be installed)
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
        flags.pop("eval_episodes"), flags.pop("eval_env"), flags.pop("eval_protocol")
        overrides.setdefault("progress", sys.stderr.isatty())
        precision, compile_loss = flags.pop("precision"), flags.pop("compile")
        if precision != "32" or compile_loss:
            raise typer.BadParameter(
                "trains online in eager fp32: drop --precision and --compile", param_hint="--online"
            )
        flags.pop("epochs")
        result = train_online(
            model,
            online,
            preset,
            protocol_extra=record or None,
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
        result = train(model, dataset, preset, **flags, **overrides, protocol_extra=record or None)
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

"""Pipeline commands: ``swm collect``, ``swm eval``, ``swm envs`` and ``swm fovs``."""

from __future__ import annotations

import contextlib
from pathlib import Path
from typing import Annotated, Any

import typer

from ..solver import list_solvers
from .errors import int_in, output_dir, output_file, require

EnvArg = Annotated[
    str, typer.Argument(help="Environment id, e.g. swm/TwoRoom-v2 (see `swm envs`).", metavar="ENV", show_default=False)
]
PolicyOpt = Annotated[
    str, typer.Option("--policy", "-p", metavar="POLICY", help="Policy that acts: random, expert or weak (PushT).")
]
NumEnvsOpt = Annotated[
    int, typer.Option("--num-envs", parser=int_in(1), metavar="K", help="Environments stepped together.")
]
ImageSizeOpt = Annotated[
    int, typer.Option("--image-size", parser=int_in(8, 1024), metavar="S", help="Side of the square images (pixels).")
]
SeedOpt = Annotated[int, typer.Option("--seed", parser=int_in(0), metavar="SEED", help="Episode k uses seed SEED + k.")]
MaxStepsOpt = Annotated[
    int | None,
    typer.Option(
        "--max-steps",
        parser=int_in(1),
        metavar="M",
        help="Steps before an episode is cut (default: the env's registered limit).",
        show_default=False,
    ),
]
VariationOpt = Annotated[
    list[str] | None,
    typer.Option(
        "--variation",
        metavar="KEY",
        help="Factor of variation to resample every episode (repeatable; 'all' for every factor; see `swm fovs ENV`).",
    ),
]


EvalImageSizeOpt = Annotated[
    int | None,
    typer.Option(
        "--image-size",
        parser=int_in(8, 1024),
        metavar="S",
        help="Side of the square images (pixels; default: what a wm:/gc: run was trained on, else 64).",
        show_default=False,
    ),
]
ForceOpt = Annotated[
    bool,
    typer.Option(
        "--force",
        help="Evaluate a wm:/gc: run on an env or image size other than its own without a word (no warning, no error).",
    ),
]


RayOpt = Annotated[
    bool,
    typer.Option(
        "--ray", help="Spread the episodes over Ray tasks (a private local Ray on this machine unless --ray-address)."
    ),
]
RayAddressOpt = Annotated[
    str | None,
    typer.Option(
        "--ray-address",
        metavar="ADDRESS",
        help="Ray cluster to use (HOST:PORT or 'auto'); implies --ray.",
        show_default=False,
    ),
]


def default_dataset_name(env_id: str, policy: str) -> str:
    """``swm/TwoRoom-v2`` + ``expert`` -> ``tworoom-v1-expert``."""
    return f"{env_id.rsplit('/', 1)[-1].lower()}-{policy}"


def collect(
    env: EnvArg,
    episodes: Annotated[
        int,
        typer.Option(
            "--episodes",
            "-n",
            parser=int_in(1),
            metavar="N",
            help="Episodes the dataset holds when done (an existing one is resumed up to N).",
        ),
    ] = 10,
    policy: PolicyOpt = "random",
    name: Annotated[
        str | None,
        typer.Option("--name", metavar="NAME", help="Dataset name (default: <env>-<policy>).", show_default=False),
    ] = None,
    num_envs: NumEnvsOpt = 1,
    image_size: ImageSizeOpt = 64,
    seed: SeedOpt = 0,
    variation: VariationOpt = None,
    max_steps: MaxStepsOpt = None,
    overwrite: Annotated[
        bool, typer.Option("--overwrite", help="Replace an existing dataset of that name instead of resuming it.")
    ] = False,
    noise: Annotated[
        float | None,
        typer.Option(
            "--noise",
            min=0.0,
            metavar="SIGMA",
            help=(
                "Std of the Gaussian noise on the expert's actions (default: 1.0 times the action bound for experts "
                "that take noise, so the data shows what varied actions do; 0 records clean demonstrations)."
            ),
            show_default=False,
        ),
    ] = None,
    repeat_prob: Annotated[
        float | None,
        typer.Option(
            "--repeat-prob",
            min=0.0,
            max=1.0,
            metavar="P",
            help="Each env repeats its previous action with probability P (sticky actions, as upstream's collectors).",
            show_default=False,
        ),
    ] = None,
    dist_constraint: Annotated[
        float | None,
        typer.Option(
            "--dist-constraint",
            min=0.0,
            metavar="D",
            help="--policy weak: half-side of the square around the block its targets stay in (default 100).",
            show_default=False,
        ),
    ] = None,
    ray: RayOpt = False,
    ray_address: RayAddressOpt = None,
) -> None:
    """Record EPISODES episodes of ENV into an HDF5 dataset in the cache, then show it.

    Example: swm collect swm/TwoRoom-v2 --episodes 20 --policy expert --name tworoom
    (upstream's datasets: swm collect swm/PushT-v1 --policy weak; swm collect swm/TwoRoom-v1 --policy expert
    --noise 2.0 --repeat-prob 0.05)
    (--ray: one Ray task per shard of seeds, into NAME/shard_*.h5, read as one dataset)
    """
    from ..data import dataset_info, delete_dataset
    from ..data._index import not_a_file
    from ..data.utils import dataset_file
    from ..planning.policies import (
        check_factors,
        check_policy,
        checkpoint_run,
        make_policy,
        make_world,
        recording_noise,
        reset_options,
        resolve_env,
    )
    from .display import console, display_dataset_info

    env = resolve_env(env)
    policy = check_policy(policy)
    noise = recording_noise(policy, env, noise)
    policy_options = {k: v for k, v in (("repeat_prob", repeat_prob), ("dist_constraint", dist_constraint)) if v}
    if checkpoint_run(policy) is None:  # bad combinations fail before any work (a checkpoint's, before it loads)
        make_policy(policy, env, seed=seed, noise=noise, **policy_options)
    name = name or default_dataset_name(env, policy)
    path = dataset_file(name)  # a name under the cache folder (sub-folders allowed), checked
    what = not_a_file(path)
    require(what is None, f"swm collect requires {str(path)!r} to be a dataset file, got {what}; pick another --name")
    out = console()
    if ray or ray_address:
        _collect_on_ray(
            env,
            name,
            episodes,
            policy,
            noise,
            seed,
            image_size,
            max_steps,
            variation or [],
            overwrite,
            num_envs,
            ray_address,
            policy_options,
        )
        return
    have = 0
    if path.exists():
        if overwrite:
            delete_dataset(name)
        else:
            have = dataset_info(name)["num_episodes"]
            todo = f"recording {episodes - have} more to reach {episodes}" if have < episodes else "nothing to record"
            out.print(
                f"Dataset [bold]{name}[/] holds {have} episodes: {todo} (--overwrite replaces it).", soft_wrap=True
            )
    with make_world(env, num_envs=num_envs, image_size=image_size, max_steps=max_steps, seed=seed) as world:
        options = reset_options(check_factors(world, variation or []))
        world.set_policy(make_policy(policy, env, seed=seed, noise=noise, **policy_options))
        path = world.record_dataset(name, episodes=episodes, seed=seed, options=options)
    display_dataset_info(dataset_info(name))
    how = ", ".join(
        f"{what} {value:g}"
        for what, value in (("action noise", noise), ("repeat prob", repeat_prob), ("dist constraint", dist_constraint))
        if value
    )
    how = f" ({how})" if how else ""
    out.print(f"Recorded {max(episodes - have, 0)} {policy} episodes{how} of {env} to {path}", soft_wrap=True)


def _collect_on_ray(
    env: str,
    name: str,
    episodes: int,
    policy: str,
    noise: float | None,
    seed: int,
    image_size: int,
    max_steps: int | None,
    variation: list[str],
    overwrite: bool,
    num_envs: int,
    address: str | None,
    policy_options: dict | None = None,
) -> None:
    """``swm collect --ray``: a sharded dataset recorded by Ray tasks (:mod:`stable_worldmodel.world.on_ray`)."""
    import sys

    from ..data import dataset_info, delete_dataset, list_datasets
    from ..planning.policies import check_factors, episode_limit, make_world, reset_options
    from ..world.on_ray import record_dataset_on_ray
    from .display import console, display_dataset_info

    if num_envs != 1:
        raise typer.BadParameter(
            "each Ray task runs one env: drop --num-envs (--ray spreads the episodes over tasks)",
            param_hint="--num-envs",
        )
    if overwrite and name in list_datasets():
        delete_dataset(name)
    with make_world(env, num_envs=1, image_size=16, max_steps=1, verbose=0) as world:  # checks the factor names
        options = reset_options(check_factors(world, variation))
    folder = record_dataset_on_ray(
        env,
        name,
        episodes,
        seed=seed,
        policy=policy,
        noise=noise,
        policy_options=policy_options,
        image_size=image_size,
        max_steps=episode_limit(env, max_steps),
        options=options,
        address=address,
        progress=sys.stderr.isatty(),
    )
    display_dataset_info(dataset_info(name))
    console().print(
        f"Recorded {episodes} {policy} episodes of {env} on Ray to {folder}/ (shards read as one dataset)",
        soft_wrap=True,
    )


def eval_cmd(
    ctx: typer.Context,
    env: EnvArg,
    policy: Annotated[
        str,
        typer.Option(
            "--policy",
            "-p",
            metavar="POLICY",
            help=(
                "random, expert, wm:RUN (plan with checkpoint RUN, see `swm list model`) or gc:RUN (act with the "
                "goal-conditioned policy RUN: gcbc, gcivl, gciql). With --fov-sweep, several: P1,P2."
            ),
        ),
    ] = "random",
    episodes: Annotated[
        int, typer.Option("--episodes", "-n", parser=int_in(1), metavar="N", help="Episodes to evaluate.")
    ] = 20,
    seed: SeedOpt = 0,
    variation: VariationOpt = None,
    video: Annotated[
        Path | None,
        typer.Option(
            "--video", metavar="DIR", help="Also write one MP4 per env of a rollout into this folder.", file_okay=False
        ),
    ] = None,
    num_envs: NumEnvsOpt = 1,
    max_steps: MaxStepsOpt = None,
    image_size: EvalImageSizeOpt = None,
    solver: Annotated[
        str,
        typer.Option(
            "--solver", metavar="NAME", help=f"Planner of wm: policies: {', '.join(list_solvers())} (swm list solver)."
        ),
    ] = "cem",
    horizon: Annotated[
        int, typer.Option("--horizon", parser=int_in(1), metavar="H", help="Planned action blocks (wm: policies).")
    ] = 5,
    receding_horizon: Annotated[
        int,
        typer.Option(
            "--receding-horizon",
            parser=int_in(1),
            metavar="R",
            help="Blocks executed before replanning (MPC; at most H).",
        ),
    ] = 1,
    samples: Annotated[
        int, typer.Option("--samples", parser=int_in(1), metavar="S", help="Candidates per solver iteration.")
    ] = 300,
    iterations: Annotated[
        int, typer.Option("--iterations", parser=int_in(1), metavar="K", help="Solver iterations per plan.")
    ] = 30,
    cost: Annotated[
        str,
        typer.Option(
            "--cost",
            metavar="C",
            help=(
                "auto: min for goal-distance models, the model's own cost for the others (TD-MPC2); min: the "
                "predicted step closest to the goal counts (reach it at any step); final: the last one (upstream's)."
            ),
        ),
    ] = "auto",
    subgoals: Annotated[
        str | None,
        typer.Option(
            "--subgoals",
            metavar="METHOD",
            help=(
                "wm: policies: graph = plan towards waypoints on a latent graph of the run's training episodes "
                "(search on the replay buffer; takes detours the goal distance alone misses); none = plan on the "
                "goal alone (plain MPC, as papers report); auto = on the goal alone, and on the graph's waypoints "
                "once an episode stops getting closer (LeWM / PLDM / PreJEPA / Dreamer runs whose training dataset "
                "is on disk; else none)."
            ),
        ),
    ] = "auto",
    lookahead: Annotated[
        int | None,
        typer.Option(
            "--lookahead",
            parser=int_in(1),
            metavar="L",
            help="With --subgoals graph or auto: blocks along the graph path to the waypoint (default: H // 2).",
            show_default=False,
        ),
    ] = None,
    patience: Annotated[
        int | None,
        typer.Option(
            "--patience",
            parser=int_in(1),
            metavar="STEPS",
            help=(
                "With --subgoals auto: env steps without progress towards the goal before an episode aims at "
                "waypoints (default: H x the action block // 2, at least 10)."
            ),
            show_default=False,
        ),
    ] = None,
    device: Annotated[
        str, typer.Option("--device", metavar="DEV", help="Where wm: policies plan: auto, cpu, cuda, mps.")
    ] = "auto",
    compile_cost: Annotated[
        bool,
        typer.Option(
            "--compile",
            help=(
                "wm: policies score candidates through torch.compile of the model's cost: the first plan compiles "
                "(tens of seconds on a CPU), later plans run faster (a LeWM on a 2-core CPU: 1.2-1.5x per plan)."
            ),
        ),
    ] = False,
    json_path: Annotated[
        Path | None,
        typer.Option(
            "--json",
            metavar="FILE",
            help="Write success rate, 95% CI, episodes, seeds and the protocol as JSON.",
            dir_okay=False,
        ),
    ] = None,
    from_dataset: Annotated[
        str | None,
        typer.Option(
            "--from-dataset",
            metavar="NAME",
            help="Start from held-out episodes of this dataset (upstream's protocol).",
            show_default=False,
        ),
    ] = None,
    goal_offset: Annotated[
        int,
        typer.Option(
            "--goal-offset",
            parser=int_in(1),
            metavar="G",
            help="With --from-dataset: the goal is the state G steps later.",
        ),
    ] = 25,
    budget: Annotated[
        int,
        typer.Option(
            "--budget", parser=int_in(1), metavar="N", help="With --from-dataset: steps allowed to reach the goal."
        ),
    ] = 50,
    min_goal_distance: Annotated[
        float | None,
        typer.Option(
            "--min-goal-distance",
            metavar="D",
            min=0.0,
            help=(
                "With --from-dataset: only starts whose goal is at least D from them (distance of the dataset's "
                "state rows, the one the env's eval_state reports): a harder variant where random rarely succeeds."
            ),
            show_default=False,
        ),
    ] = None,
    decoder: Annotated[
        str | None,
        typer.Option(
            "--decoder",
            metavar="RUN",
            help=(
                "With --video and wm:RUN: the frame decoder that shows what the model predicts "
                "(default: RUN-frame when it exists)."
            ),
            show_default=False,
        ),
    ] = None,
    fov_sweep: Annotated[
        str | None,
        typer.Option(
            "--fov-sweep",
            metavar="FACTORS",
            help=(
                "Generalization report: evaluate in distribution, with each factor (all: every factor group; or "
                "F1,F2) resampled, and with all resampled, on the same seeds; a table, a heatmap PNG (beside --json, "
                "or --plot) and the JSON."
            ),
            show_default=False,
        ),
    ] = None,
    plot: Annotated[
        Path | None,
        typer.Option(
            "--plot",
            metavar="FILE",
            help="With --fov-sweep: where the heatmap PNG goes (default: beside --json, else fov-sweep-ENV.png).",
            dir_okay=False,
            show_default=False,
        ),
    ] = None,
    protocol: Annotated[
        str | None,
        typer.Option(
            "--protocol",
            metavar="NAME",
            help=(
                "upstream: with --from-dataset, every knob of upstream's evaluation (50 starts, goal +25 steps, "
                "budget 50, CEM 300 x 30, horizon 5, receding horizon 5, cost final, no subgoals, seed 42; OGBCube: "
                "goal +200, budget 400); options you give win; starts from held-out episodes for every policy."
            ),
            show_default=False,
        ),
    ] = None,
    held_out_of: Annotated[
        str | None,
        typer.Option(
            "--held-out-of",
            metavar="RUN",
            help="With --from-dataset: start from the validation episodes of run RUN (wm:RUN / gc:RUN), any policy.",
            show_default=False,
        ),
    ] = None,
    ray: RayOpt = False,
    ray_address: RayAddressOpt = None,
    force: ForceOpt = False,
) -> None:
    """Evaluate a policy on ENV and print its success rate with a 95% confidence interval.

    Example: swm eval swm/TwoRoom-v2 --policy wm:tr-lewm --solver cem --episodes 50 --num-envs 10 --json out.json
    (or --policy gc:tr-gcbc for a policy trained with `swm train gcbc`;
    swm eval swm/TwoRoom-v2 --policy expert,wm:tr-lewm --fov-sweep all --json sweep.json: the generalization report)
    """
    from ..planning.policies import check_policy, episode_limit, resolve_env, run_image_size
    from .display import console, success_table
    from .evaluation import evaluate_cli
    from .worlds import check_run_fits

    env = resolve_env(env)
    if protocol is not None:
        from .evaluation import protocol_knobs

        if from_dataset is None:
            raise typer.BadParameter(
                "requires --from-dataset NAME (upstream's protocol starts from dataset episodes)",
                param_hint="--protocol",
            )
        knobs = protocol_knobs(protocol, env)
        # an option left at its default takes the protocol's value (by name: typer may bring its own click)
        chosen = {
            k: v for k, v in knobs.items() if getattr(ctx.get_parameter_source(k), "name", "DEFAULT") == "DEFAULT"
        }
        if not policy.startswith("wm:"):
            chosen.pop("subgoals", None)  # a planner's knob: the others take none
        episodes, seed = chosen.get("episodes", episodes), chosen.get("seed", seed)
        solver, horizon = chosen.get("solver", solver), chosen.get("horizon", horizon)
        receding_horizon, samples = chosen.get("receding_horizon", receding_horizon), chosen.get("samples", samples)
        iterations, cost = chosen.get("iterations", iterations), chosen.get("cost", cost)
        subgoals, goal_offset = chosen.get("subgoals", subgoals), chosen.get("goal_offset", goal_offset)
        budget = chosen.get("budget", budget)
    if min_goal_distance is not None and from_dataset is None:
        raise typer.BadParameter("requires --from-dataset NAME", param_hint="--min-goal-distance")
    if held_out_of is not None and from_dataset is None:
        raise typer.BadParameter("requires --from-dataset NAME", param_hint="--held-out-of")
    if (ray or ray_address) and (video is not None or from_dataset is not None):
        raise typer.BadParameter(
            "evaluates seeded episodes: it cannot be combined with --video or --from-dataset", param_hint="--ray"
        )
    if fov_sweep is not None:
        if video is not None or from_dataset is not None or variation:
            raise typer.BadParameter(
                "cannot be combined with --video, --from-dataset or --variation (the sweep sets the factors)",
                param_hint="--fov-sweep",
            )
        policies = [check_policy(p.strip()) for p in policy.split(",") if p.strip()]
    else:
        policy = check_policy(policy)
    checked = policies if fov_sweep is not None else [policy]
    if video is not None:
        video = output_dir(video, "swm eval --video")
    if json_path is not None:
        json_path = output_file(json_path, "swm eval --json")
    if decoder is not None and (video is None or not policy.startswith("wm:")):
        raise typer.BadParameter(
            "requires --video DIR and a wm:RUN policy (it decodes what the model predicts)", param_hint="--decoder"
        )
    plan = None
    if any(p.startswith("wm:") for p in checked):
        from ..planning.learned import PlanSettings

        plan = PlanSettings(
            solver=solver,
            horizon=horizon,
            receding_horizon=receding_horizon,
            samples=samples,
            iterations=iterations,
            seed=seed,
            cost=cost,
            subgoals=subgoals,
            lookahead=lookahead,
            patience=patience,
            compile=compile_cost,
        )
    elif subgoals != "auto" or lookahead is not None or patience is not None or compile_cost:
        raise typer.BadParameter(
            "applies to wm:RUN policies only", param_hint="--subgoals/--lookahead/--patience/--compile"
        )
    if image_size is None:
        image_size = run_image_size(checked)
    for name in checked:  # once, before any World starts
        check_run_fits(name, env, image_size, force=force)
    max_steps = episode_limit(env, max_steps)
    out = console()
    if fov_sweep is not None:
        _fov_sweep(
            env,
            policies,
            fov_sweep,
            json_path,
            plot,
            episodes=episodes,
            seed=seed,
            num_envs=num_envs,
            max_steps=max_steps,
            image_size=image_size,
            plan=plan,
            device=device,
            ray=ray,
            ray_address=ray_address,
        )
        return
    summary, title, record = evaluate_cli(
        env,
        policy,
        episodes=episodes,
        seed=seed,
        variation=variation or [],
        num_envs=num_envs,
        max_steps=max_steps,
        image_size=image_size,
        plan=plan,
        device=device,
        from_dataset=from_dataset,
        goal_offset=goal_offset,
        budget=budget,
        video=video,
        decoder=decoder,
        ray=ray,
        ray_address=ray_address,
        held_out_of=held_out_of,
        protocol=protocol,
        min_goal_distance=min_goal_distance,
    )
    out.print(success_table(title, [summary]))
    if record.get("videos"):
        out.print("Videos: " + ", ".join(record["videos"]), soft_wrap=True)
    if json_path is not None:
        import json

        json_path.write_text(json.dumps(record, indent=2) + "\n")
        out.print(f"Results: {json_path}", soft_wrap=True)


def _factor_count(env_id: str, counts: Any) -> str:
    """The factor count column of ``swm envs``: ``counts.get(env_id)`` (``envs.factor_index.FactorCounts``), or why it
    is not available."""
    from .._optional import missing_extra
    from ..envs import get_entry

    extra = missing_extra(get_entry(env_id).tags)
    if extra:
        return f'n/a: pip install "stable-worldmodel[{extra}]"'
    try:
        return str(counts.get(env_id))
    except ImportError as exc:  # an optional extra or an env family that is not installed
        return f"n/a ({type(exc).__name__})"


def envs(
    tag: Annotated[
        str | None, typer.Option("--tag", metavar="TAG", help="Only environments with this tag (e.g. paper, discrete).")
    ] = None,
) -> None:
    """List the registered environments with their number of factors of variation and tags.

    Example: swm envs --tag paper
    """
    from rich.table import Table

    from .._optional import missing_extra
    from ..envs import get_entry, list_envs
    from ..envs.factor_index import FactorCounts
    from .display import console
    from .errors import check_choice

    if tag is not None:
        check_choice("tag", tag, sorted({t for e in list_envs() for t in get_entry(e).tags}))
    table = Table(title="Environments")
    for column, justify in (("id", "left"), ("factors", "right"), ("tags", "left"), ("expert", "left")):
        table.add_column(column, justify=justify, style="cyan" if column == "id" else None, no_wrap=column == "id")
    counts = FactorCounts()
    ids = list_envs(tag)
    # envs whose extra is missing are never built (their row says which extra to install)
    building = sum(env_id not in counts.counts and not missing_extra(get_entry(env_id).tags) for env_id in ids)
    status = f"Counting the factors of {building} env(s): each is built once, then the counts are cached"
    with console().status(status) if building else contextlib.nullcontext():
        for env_id in ids:
            entry = get_entry(env_id)
            factors = _factor_count(env_id, counts)
            table.add_row(env_id, factors, ", ".join(entry.tags), "yes" if entry.expert else "no")
    counts.save()
    console().print(table)


def _fov_sweep(
    env: str, policies: list[str], factors: str, json_path: Path | None, plot: Path | None, *, plan: Any, **kwargs: Any
) -> None:
    """``swm eval --fov-sweep``: the generalization report (:mod:`.sweep`)."""
    import json

    from .display import console
    from .evaluation import evaluate_cli
    from .sweep import run_sweep, sweep_heatmap, sweep_json, sweep_table

    def evaluate(env: str, policy: str, variation: list[str], **kw: Any):
        return evaluate_cli(env, policy, variation=variation, plan=plan if policy.startswith("wm:") else None, **kw)

    report = run_sweep(env, policies, factors, evaluate=evaluate, **kwargs)
    out = console()
    out.print(sweep_table(report))
    png = plot or (
        json_path.with_suffix(".png") if json_path is not None else Path(f"fov-sweep-{env.split('/')[-1]}.png")
    )
    out.print(f"Heatmap: {sweep_heatmap(report, png)}", soft_wrap=True)
    if json_path is not None:
        protocol = {k: v for k, v in kwargs.items()}
        if plan is not None:
            protocol["plan"] = plan.as_dict()
        json_path.write_text(json.dumps(sweep_json(report, protocol), indent=2) + "\n")
        out.print(f"Results: {json_path}", soft_wrap=True)


def sweep(
    file: Annotated[
        Path,
        typer.Argument(
            help=(
                "YAML: envs, policies, factors (none, a factor or group, all, or a list resampled together), "
                "episodes, seed, num_envs, max_steps, image_size, device, plan."
            ),
            metavar="FILE",
            exists=True,
            dir_okay=False,
            show_default=False,
        ),
    ],
    json_path: Annotated[
        Path | None,
        typer.Option("--json", metavar="FILE", help="Write every result and the protocol as JSON.", dir_okay=False),
    ] = None,
    plot: Annotated[
        Path | None,
        typer.Option(
            "--plot",
            metavar="DIR",
            help="Write one heatmap PNG per env into DIR (default: beside --json).",
            file_okay=False,
            show_default=False,
        ),
    ] = None,
    ray: RayOpt = False,
    ray_address: RayAddressOpt = None,
    force: ForceOpt = False,
) -> None:
    """Evaluate every policy on every env in every factor setting of a YAML file, on the same seeds:
    one table per env, heatmaps and one JSON (--ray spreads the episodes over Ray).

    Example: swm sweep sweep.yaml --ray --json results/sweep.json
    """
    import json

    from ..planning.learned import PlanSettings
    from ..planning.policies import check_policy, resolve_env, run_image_size
    from .display import console
    from .evaluation import evaluate_cli
    from .sweep import load_sweep_file, run_sweep_file, sweep_heatmap, sweep_json, sweep_table
    from .worlds import check_run_fits

    spec = load_sweep_file(file)
    spec["policies"] = [check_policy(p) for p in spec["policies"]]
    if spec["image_size"] is None:
        spec["image_size"] = run_image_size(spec["policies"])
    for env in spec["envs"]:  # once per env and run, before any World starts
        for policy in spec["policies"]:
            check_run_fits(policy, resolve_env(env), spec["image_size"], force=force, image_option="image_size: ")
    plan = (
        PlanSettings(**{"seed": spec["seed"], **spec["plan"]})
        if any(p.startswith("wm:") for p in spec["policies"])
        else None
    )
    if json_path is not None:
        json_path = output_file(json_path, "swm sweep --json")
    reports = run_sweep_file(spec, evaluate=evaluate_cli, plan=plan, ray=ray, ray_address=ray_address)
    out = console()
    where = plot or (json_path.parent if json_path is not None else None)
    for report in reports:
        out.print(sweep_table(report))
        if where is not None:
            png = sweep_heatmap(report, Path(where) / f"sweep-{report['env'].split('/')[-1]}.png")
            out.print(f"Heatmap: {png}", soft_wrap=True)
    if json_path is not None:
        protocol = {k: v for k, v in spec.items() if k not in ("envs", "policies")}
        protocol["ray"] = ray_address or ("local" if ray else None)
        data = {"sweep": str(file), "protocol": protocol, "envs": [sweep_json(r, protocol) for r in reports]}
        json_path.write_text(json.dumps(data, indent=2) + "\n")
        out.print(f"Results: {json_path}", soft_wrap=True)


def fovs(env: EnvArg) -> None:
    """Show the factors of variation of ENV: type, range, shape and default of each.

    Example: swm fovs swm/TwoRoom-v2
    """
    from ..planning.policies import resolve_env, variation_space_of
    from .display import console, factor_tree

    env = resolve_env(env)
    space = variation_space_of(env)
    count = len(space.names()) if space is not None else 0
    out = console()
    out.print(factor_tree(f"{env}: {count} factors of variation", space))
    if count:
        out.print("Resample some every episode with --variation NAME (a factor, a group, or 'all').")

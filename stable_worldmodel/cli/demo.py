"""``swm demo`` (what ``make demo`` runs): the whole collect -> train -> plan loop on one env.

1. record expert episodes into a dataset (in the cache) and show it;
2. train a world model on it (tiny LeWM by default: a few minutes on a laptop CPU);
3. evaluate the random policy, the expert and the learned model planning with CEM on the
   same seeds (a JEPA model also with ``--subgoals graph``: waypoints from its training data);
4. write one MP4 rollout of each policy, a PNG bar plot of the success rates with 95%
   Wilson intervals and a ``results.json``;
5. end with one line naming where the outputs are.
"""

from __future__ import annotations

import contextlib
import itertools
import json
import shutil
import sys
import tempfile
from collections.abc import Sequence
from pathlib import Path
from typing import Annotated, Any

import typer

from .errors import int_in, output_dir
from .pipeline import ImageSizeOpt, MaxStepsOpt, SeedOpt, default_dataset_name
from .stats import SuccessSummary

DEFAULT_ENV = "swm/TwoRoom-v2"
DEFAULT_OUT = Path("demo_outputs")
POLICY_ORDER = ("random", "expert")
PLOT_NAME = "success_rates.png"
RESULTS_NAME = "results.json"
#: the evaluation seeds start here, away from the seeds of the recorded episodes
EVAL_SEED_OFFSET = 10_000


def plot_success_rates(summaries: Sequence[SuccessSummary], path: Path, title: str) -> Path:
    """Bar plot of success rates (percent) with asymmetric 95% Wilson error bars, saved as PNG."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    rates = [100 * s.rate for s in summaries]
    lows = [max(0.0, 100 * (s.rate - s.interval[0])) for s in summaries]  # rounding can make 0 a tiny negative
    highs = [max(0.0, 100 * (s.interval[1] - s.rate)) for s in summaries]
    fig, ax = plt.subplots(figsize=(max(4.5, 1.3 * len(summaries)), 3.6), dpi=120)
    try:
        palette = ["#9aa5b1", "#2f7ebc", "#3a9d5d", "#c4703a", "#8a5fb0", "#c9a227"]
        colors = [palette[i % len(palette)] for i in range(len(summaries))]
        labels = [s.label.replace("+", "\n+") for s in summaries]  # lewm+cem+graph on three short lines
        bars = ax.bar(labels, rates, yerr=[lows, highs], capsize=8, color=colors, edgecolor="black", linewidth=0.6)
        for bar, s, top in zip(bars, summaries, highs, strict=False):
            label = f"{100 * s.rate:.0f}% ({s.successes}/{s.episodes})"
            ax.annotate(
                label, (bar.get_x() + bar.get_width() / 2, 100 * s.rate + top + 2), ha="center", va="bottom", fontsize=8
            )
        ax.set_ylim(0, 112)
        ax.set_ylabel("success rate (%)")
        ax.set_title(title, fontsize=9)
        ax.grid(axis="y", alpha=0.3)
        fig.tight_layout()
        fig.savefig(path)
    finally:
        plt.close(fig)
    return path


VIDEO_MIN_SIZE = 224


def _record_rollout(env: str, policy: str, path: Path, seed: int, image_size: int, max_steps: int, plan=None) -> Path:
    """One MP4 of ``policy`` on the episode of seed ``seed`` (the first evaluation episode).

    A learned model resizes the frames to its own image size; the video keeps ``image_size``."""
    from ..planning.policies import make_policy, make_world

    with (
        tempfile.TemporaryDirectory(dir=path.parent) as tmp,
        make_world(env, 1, image_size, max_steps, seed=seed, verbose=0) as world,
    ):
        world.set_policy(make_policy(policy, env, seed=seed, plan=plan))
        (video,) = world.record_video(tmp, max_steps=max_steps, fps=10, seed=seed)
        shutil.move(str(video), path)
    return path


def _write_results(
    path: Path, env: str, seed: int, summaries: Sequence[SuccessSummary], dataset: Path, model: dict | None
) -> None:
    record = {
        "env": env,
        "dataset": str(dataset),
        "eval_seeds": [seed, seed + summaries[0].episodes - 1],
        "policies": {
            s.label: {
                "episodes": s.episodes,
                "successes": s.successes,
                "success_rate": round(100 * s.rate, 2),  # percent, as swm eval --json and World.evaluate
                "ci95": [round(100 * v, 2) for v in s.interval],
                "mean_length": round(s.mean_length, 2),
            }
            for s in summaries
        },
    }
    if model is not None:
        record["model"] = model
    path.write_text(json.dumps(record, indent=2) + "\n")


def claim_run_name(root: Path, base: str) -> str:
    """The first of ``base``, ``base-2``, ``base-3``, ... that no run uses, claimed by creating its empty folder
    (atomic: two demos started together get two names; ``swm train`` accepts an empty run folder)."""
    root.mkdir(parents=True, exist_ok=True)
    for k in itertools.count(1):
        name = base if k == 1 else f"{base}-{k}"
        try:
            (root / name).mkdir()
        except FileExistsError:
            continue
        return name
    raise AssertionError("unreachable")  # pragma: no cover


@contextlib.contextmanager
def _demo_lock(dataset: Path, con: Any):
    """Held while this demo records ``dataset``: a second demo with the same settings waits here, then finds
    the dataset complete (recording resumes to the episodes asked, so it adds none)."""
    from ..data._lock import WriterLock
    from ..errors import DatasetBusyError

    dataset.parent.mkdir(parents=True, exist_ok=True)
    marker = dataset.with_name(dataset.name + ".demo")
    try:
        lock = WriterLock(marker, busy=DatasetBusyError).acquire()  # the error's text: the holder
    except DatasetBusyError as holder:
        con.print(f"Waiting for another swm demo recording {dataset.name} ({holder})", soft_wrap=True)
        lock = WriterLock(marker, wait=True).acquire()
    try:
        yield
    finally:
        lock.release()


def demo(
    env: Annotated[
        str, typer.Option("--env", metavar="ENV", help="Environment id (it needs an expert; see `swm envs`).")
    ] = DEFAULT_ENV,
    episodes: Annotated[
        int, typer.Option("--episodes", "-n", parser=int_in(1), metavar="N", help="Expert episodes to record.")
    ] = 300,
    eval_episodes: Annotated[
        int, typer.Option("--eval-episodes", parser=int_in(1), metavar="N", help="Evaluation episodes per policy.")
    ] = 50,
    out: Annotated[
        Path,
        typer.Option("--out", metavar="DIR", help="Folder for the videos, the plot and results.json.", file_okay=False),
    ] = DEFAULT_OUT,
    seed: SeedOpt = 0,
    image_size: ImageSizeOpt = 64,
    max_steps: MaxStepsOpt = None,
    model: Annotated[
        str,
        typer.Option(
            "--model",
            metavar="MODEL",
            help="World model to train (lewm, pldm, dummy); 'none' skips training and planning.",
        ),
    ] = "lewm",
    train_steps: Annotated[
        int | None,
        typer.Option(
            "--train-steps",
            parser=int_in(1),
            metavar="N",
            help="Training steps (default: the tiny preset's).",
            show_default=False,
        ),
    ] = None,
    samples: Annotated[
        int, typer.Option("--samples", parser=int_in(1), metavar="S", help="CEM candidates per iteration.")
    ] = 300,
    iterations: Annotated[
        int, typer.Option("--iterations", parser=int_in(1), metavar="K", help="CEM iterations per plan.")
    ] = 30,
    num_envs: Annotated[
        int, typer.Option("--num-envs", parser=int_in(1), metavar="K", help="Environments stepped together.")
    ] = 10,
) -> None:
    """Collect expert data, train a world model on it, evaluate random vs expert vs the model
    planning with CEM (LeWM / PLDM also with --subgoals graph), and write videos, a plot and results.json.

    Example: swm demo --env swm/TwoRoom-v2 --episodes 300 --out demo_outputs
    """
    from ..data import dataset_info
    from ..data.utils import resolve_dataset_path
    from ..planning.policies import (
        episode_limit,
        evaluate_policy,
        make_policy,
        make_world,
        recording_noise,
        resolve_env,
    )
    from .display import console, display_dataset_info, success_table

    env = resolve_env(env)
    max_steps = episode_limit(env, max_steps)
    make_policy("expert", env)  # fail now (one line) when the env has no expert
    learn = model != "none"
    if learn:
        from ..wm import get_config_class, list_models
        from .errors import check_choice

        check_choice(
            "world model", model, [m for m in list_models() if m != "frame"]
        )  # a frame decoder needs a source run
    out = output_dir(out, "swm demo --out")
    con = console()
    # its own names: the dataset is named by everything that decides its content (a rerun reuses it, a recording
    # killed midway is completed), the run is a fresh name claimed for this invocation (nothing is deleted)
    name = f"demo-{default_dataset_name(env, 'expert')}-{episodes}x{max_steps}-seed{seed}-{image_size}px"
    total = 5 if learn else 4
    step = iter(range(1, total + 1))

    con.rule(f"[{next(step)}/{total}] Recording {episodes} expert episodes of {env}")
    with _demo_lock(resolve_dataset_path(name), con):
        with make_world(env, min(4, episodes), image_size, max_steps, seed=seed) as world:
            world.set_policy(
                make_policy("expert", env, seed=seed, noise=recording_noise("expert", env, None))
            )  # as swm collect
            dataset = world.record_dataset(name, episodes=episodes, seed=seed)
    display_dataset_info(dataset_info(name))

    policies: list[tuple[str, str, object]] = [(p, p, None) for p in POLICY_ORDER]  # (label, policy, plan)
    model_record = None
    if learn:
        from ..planning.learned import PlanSettings
        from ..train import train
        from ..wm.utils import checkpoint_root

        run = claim_run_name(checkpoint_root(), f"demo-{model}")
        con.rule(f"[{next(step)}/{total}] Training a tiny {model} on {name} (run {run})")
        result = train(model, name, "tiny", steps=train_steps, name=run, seed=seed, progress=sys.stderr.isatty())
        con.print(
            f"{result.steps} steps in {result.seconds:.0f} s ({result.samples_per_second:.0f} samples/s), "
            f"train loss {result.train_loss:.4f}; checkpoint {result.folder}",
            soft_wrap=True,
        )
        plan = PlanSettings(solver="cem", samples=samples, iterations=iterations, seed=seed, subgoals="none")
        policies.append((f"{model}+cem", f"wm:{run}", plan))
        model_record = {
            "run": run,
            "checkpoint": str(result.folder),
            "steps": result.steps,
            "train_seconds": round(result.seconds, 1),
            "plan": plan.as_dict(),
        }
        if get_config_class(model).subgoal_graph:  # the same model and CEM, aiming at waypoints of the training data
            graph = PlanSettings(solver="cem", samples=samples, iterations=iterations, seed=seed, subgoals="graph")
            policies.append((f"{model}+cem+graph", f"wm:{run}", graph))
            model_record["plan_graph"] = graph.as_dict()

    eval_seed = seed + EVAL_SEED_OFFSET
    con.rule(
        f"[{next(step)}/{total}] Evaluating {', '.join(label for label, *_ in policies)} "
        f"on the same {eval_episodes} seeds"
    )
    summaries = []
    with make_world(env, min(num_envs, eval_episodes), image_size, max_steps, seed=eval_seed) as world:
        for label, policy, plan in policies:
            results = evaluate_policy(world, policy, eval_episodes, eval_seed, plan=plan)
            summaries.append(SuccessSummary.from_results(label, results))
    con.print(
        success_table(
            f"{env}: seeds {eval_seed}..{eval_seed + eval_episodes - 1}, at most {max_steps} steps", summaries
        )
    )

    con.rule(f"[{next(step)}/{total}] Recording one rollout video per policy")
    video_size = max(image_size, VIDEO_MIN_SIZE)  # the envs draw at any size: make the videos legible
    videos = [
        _record_rollout(env, p, out / f"{label}.mp4", eval_seed, video_size, max_steps, plan=plan)
        for label, p, plan in policies
    ]
    con.print("Videos: " + ", ".join(str(v) for v in videos), soft_wrap=True)

    con.rule(f"[{next(step)}/{total}] Plotting success rates with 95% confidence intervals")
    plot = plot_success_rates(summaries, out / PLOT_NAME, f"{env}, {eval_episodes} episodes per policy (95% Wilson CI)")
    _write_results(out / RESULTS_NAME, env, eval_seed, summaries, dataset, model_record)
    con.print(f"Plot: {plot}", soft_wrap=True)
    files = ", ".join(p.name for p in (*videos, plot)) + f", {RESULTS_NAME}"
    where = f"; checkpoint {model_record['checkpoint']}" if model_record else ""
    typer.echo(f"Demo outputs in {out.resolve()} ({files}); dataset '{name}' at {dataset}{where}")

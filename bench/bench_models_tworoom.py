"""Every model's tiny preset on one env, with the world-model issues' protocol: collect expert episodes, train,
evaluate on the same seeds; prints a markdown table (training time, plan time, success and its 95% interval).

Usage: python bench/bench_models_tworoom.py [--env swm/TwoRoom-v1] [--models lewm pldm prejepa gcbc dreamer]
       [--episodes 300] [--eval-episodes 50] [--num-envs 10] [--seed 5000] [--steps N] [--set KEY=VALUE ...]
Runs in a scratch $STABLEWM_HOME unless --keep; never asserts. On a 2-core CPU each model takes 3-8 minutes.
"""

from __future__ import annotations

import argparse
import json
import os
import tempfile
import time


def run(args: argparse.Namespace) -> list[dict]:
    from stable_worldmodel.cli.stats import SuccessSummary
    from stable_worldmodel.planning.learned import PlanSettings
    from stable_worldmodel.planning.policies import (
        episode_limit,
        evaluate_policy,
        make_policy,
        make_world,
        policy_history,
        recording_noise,
    )
    from stable_worldmodel.train import train
    from stable_worldmodel.wm import get_config_class

    limit = episode_limit(args.env, None)
    start = time.perf_counter()
    with make_world(args.env, 4, 64, limit, seed=0) as world:
        world.set_policy(make_policy("expert", args.env, seed=0, noise=recording_noise("expert", args.env, None)))
        world.record_dataset("bench", episodes=args.episodes, seed=0)
    collect = time.perf_counter() - start
    rows = []
    for model in args.models:
        start = time.perf_counter()
        result = train(
            model, "bench", "tiny", steps=args.steps, name=f"bench-{model}", seed=0, progress=False, **args.set
        )
        trained = time.perf_counter() - start
        prefix = get_config_class(model).eval_prefix
        # TD-MPC2 plans with MPPI, its own planner (and on its own reward and value)
        plan = (
            PlanSettings(seed=args.seed, **({"solver": "mppi"} if model == "tdmpc2" else {}))
            if prefix == "wm"
            else None
        )
        policy = f"{prefix}:bench-{model}"
        # the frames of history `swm eval` gives the policy: 1 for a planner (it encodes the current frame)
        with make_world(
            args.env, args.num_envs, 64, limit, seed=args.seed, history_size=policy_history(policy)
        ) as world:
            start = time.perf_counter()
            results = evaluate_policy(world, policy, args.eval_episodes, args.seed, plan=plan)
            evaluated = time.perf_counter() - start
        steps = int(sum(results["episode_lengths"]))
        summary = SuccessSummary.from_results(model, results)
        metrics = (result.folder / "metrics.jsonl").read_text().splitlines()
        val = [r["val/loss"] for r in map(json.loads, metrics) if "val/loss" in r]
        rows.append(
            {
                "model": model,
                "collect_s": collect,
                "train_s": trained,
                "eval_s": evaluated,
                "val_loss": val,
                "ms_per_step": 1000 * evaluated * args.num_envs / max(1, steps),
                "summary": summary,
            }
        )
        print_row(rows[-1], flush=True)
    return rows


def print_row(row: dict, flush: bool = False) -> None:
    s = row["summary"]
    lo, hi = (100 * v for v in s.interval)
    print(
        f"| {row['model']} | {row['train_s']:.0f} s | {row['ms_per_step']:.0f} ms "
        f"| {100 * s.rate:.0f}% [{lo:.1f}, {hi:.1f}] "
        f"| {row['collect_s']:.0f} + {row['train_s']:.0f} + {row['eval_s']:.0f} s |",
        flush=flush,
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--env", default="swm/TwoRoom-v1")
    parser.add_argument("--models", nargs="+", default=["lewm", "pldm", "prejepa", "gcbc", "dreamer"])
    parser.add_argument("--episodes", type=int, default=300)
    parser.add_argument("--eval-episodes", type=int, default=50)
    parser.add_argument("--num-envs", type=int, default=10)
    parser.add_argument("--seed", type=int, default=5000)
    parser.add_argument("--steps", type=int, default=None, help="training steps (default: each preset's)")
    parser.add_argument("--keep", action="store_true", help="use $STABLEWM_HOME instead of a scratch folder")
    parser.add_argument(
        "--set",
        nargs="*",
        default=[],
        metavar="KEY=VALUE",
        help="config overrides for every model trained, VALUE read as JSON when it parses (e.g. embed_dim=64)",
    )
    args = parser.parse_args()
    from stable_worldmodel.errors import ConfigError
    from stable_worldmodel.wm.config import parse_override

    try:
        args.set = dict(parse_override(item) for item in args.set)
    except ConfigError as exc:
        parser.error(str(exc))
    print(
        f"{args.env}: {args.episodes} expert episodes, tiny presets, {args.eval_episodes} evaluation episodes "
        f"(seeds {args.seed}..), {args.num_envs} envs, this machine; world models plan with PlanSettings() "
        f"(CEM 300 x 30, horizon 5, subgoals 'auto': the training data's waypoints once an episode stalls; "
        f"TD-MPC2: MPPI on its own reward and value){'; config overrides ' + json.dumps(args.set) if args.set else ''}"
    )
    print("| model | training | plan time per env step | success (95% CI) | collect + train + eval |")
    print("| --- | ---: | ---: | ---: | ---: |")
    if args.keep:
        rows = run(args)
    else:
        with tempfile.TemporaryDirectory() as home:
            os.environ["STABLEWM_HOME"] = home
            rows = run(args)
    for row in rows:
        val = row["val_loss"]
        print(
            f"{row['model']}: validation loss {val[0]:.4g} -> {val[-1]:.4g}"
            if val
            else f"{row['model']}: no validation loss"
        )


if __name__ == "__main__":
    main()

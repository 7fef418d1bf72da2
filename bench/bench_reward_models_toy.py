"""Do the reward-learning world models learn? TD-MPC2 (and Dreamer, LeWM for reference) on swm/Toy-v0
with a fixed goal, so that the env's reward (minus the distance to the goal) says where to go.

TD-MPC2 is not goal-conditioned: it plans on its learned reward and value, which only mean
something when the reward does not depend on a goal that changes per episode. Toy's goal is
pinned at (0.5, 0.5) for recording and evaluation (``options={"goal_state": ...}``); starts are
drawn from the seeds. Protocol: record ``--episodes`` random-policy episodes (64x64: they cover the
square, and the dense reward labels every step), train each
model's tiny preset, evaluate its MPPI / CEM plans and the random policy on the same
``--eval-episodes`` seeds. Prints a markdown table (validation loss first -> last, success with
its 95% interval, times). Runs in a scratch ``$STABLEWM_HOME``; never asserts.

A model name may end in ``+proprio`` (``tdmpc2+proprio``): it then also encodes the ``proprio`` column (the
agent's position; TD-MPC2's usual state input, ``proprio_dim=2``).

Usage: python bench/bench_reward_models_toy.py [--models tdmpc2 tdmpc2+proprio dreamer lewm] [--episodes 200]
       [--eval-episodes 50] [--max-steps 40] [--steps N]
"""

from __future__ import annotations

import argparse
import json
import os
import tempfile
import time

ENV = "swm/Toy-v0"
GOAL = (0.5, 0.5)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--models", nargs="+", default=["tdmpc2", "tdmpc2+proprio", "dreamer", "lewm"])
    parser.add_argument("--episodes", type=int, default=200)
    parser.add_argument("--eval-episodes", type=int, default=50)
    parser.add_argument("--max-steps", type=int, default=40)
    parser.add_argument("--num-envs", type=int, default=10)
    parser.add_argument("--steps", type=int, default=None, help="training steps (default: each tiny preset's)")
    parser.add_argument("--seed", type=int, default=5000)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as home:
        os.environ["STABLEWM_HOME"] = home
        run(args)


def run(args: argparse.Namespace) -> None:
    import numpy as np

    from stable_worldmodel import keys
    from stable_worldmodel.cli.stats import SuccessSummary
    from stable_worldmodel.planning.learned import PlanSettings
    from stable_worldmodel.planning.policies import make_policy, make_world
    from stable_worldmodel.train import train

    options = {keys.GOAL_STATE: np.asarray(GOAL, np.float32)}
    start = time.perf_counter()
    with make_world(ENV, 4, 64, args.max_steps, seed=0) as world:
        world.set_policy(make_policy("random", ENV, seed=0))
        world.record_dataset("toy-goal", episodes=args.episodes, seed=0, options=options)
    print(
        f"recorded {args.episodes} random-policy episodes of {ENV} (goal fixed at {GOAL}) "
        f"in {time.perf_counter() - start:.0f} s"
    )

    def evaluate(policy: str, plan=None) -> tuple[SuccessSummary, float]:
        with make_world(ENV, args.num_envs, 64, args.max_steps, seed=args.seed) as world:
            world.set_policy(make_policy(policy, ENV, seed=args.seed, plan=plan))
            t = time.perf_counter()
            results = world.evaluate(episodes=args.eval_episodes, seed=args.seed, options=options)
            return SuccessSummary.from_results(policy, results), time.perf_counter() - t

    print("| policy | val loss (first -> last) | success (95% CI) | train + eval |")
    print("| --- | ---: | ---: | ---: |")
    summary, seconds = evaluate("random")
    print(row("random", "", summary, f"{seconds:.0f} s"), flush=True)
    for spec in args.models:
        model, _, extra = spec.partition("+")
        overrides = {"proprio_dim": 2} if extra == "proprio" else {}
        name = f"toy-{model}{'-proprio' if overrides else ''}"
        t = time.perf_counter()
        result = train(model, "toy-goal", "tiny", steps=args.steps, name=name, seed=0, progress=False, **overrides)
        trained = time.perf_counter() - t
        val = [
            r["val/loss"]
            for r in map(json.loads, (result.folder / "metrics.jsonl").read_text().splitlines())
            if "val/loss" in r
        ]
        solver = "mppi" if model == "tdmpc2" else "cem"
        summary, seconds = evaluate(f"wm:{name}", PlanSettings(solver=solver, seed=args.seed))
        losses = f"{val[0]:.4f} -> {val[-1]:.4f}" if val else "n/a"
        print(row(f"{spec} tiny + {solver}", losses, summary, f"{trained:.0f} + {seconds:.0f} s"), flush=True)


def row(label: str, losses: str, s, times: str) -> str:
    lo, hi = (100 * v for v in s.interval)
    return f"| {label} | {losses} | {100 * s.rate:.0f}% [{lo:.1f}, {hi:.1f}] | {times} |"


if __name__ == "__main__":
    main()

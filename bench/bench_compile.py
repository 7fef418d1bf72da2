"""torch.compile against eager, in one process, alternating: CEM plans (``BaseSolver.compile_cost``) and LeWM
training steps (``train(compile=True)``'s ``torch.compile(model.loss)``).

    python bench/bench_compile.py [--model tiny-vit|tiny-vit-h3|paper] [--envs 1,10] [--rounds 7] [--threads 2]
                                  [--train-batch 64] [--train-steps 5] [--precision 32|bf16]

The eager and the compiled solver plan the same infos with the same model and seed, one plan each in turn, so both
see the same machine load; the figures are medians over ``--rounds``. The compile time (the first plan of each,
which also encodes) is printed apart. The costs of one batch of candidates are compared (``max |diff|``). Figures
only; nothing is asserted. ``OMP_WAIT_POLICY`` defaults to PASSIVE, as under ``swm``.
"""

from __future__ import annotations

import os

os.environ.setdefault("OMP_WAIT_POLICY", "PASSIVE")  # before torch starts its threads

import argparse
import statistics
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))
sys.path.insert(0, str(HERE))


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--model", default="tiny-vit")
    parser.add_argument("--envs", default="1,10")
    parser.add_argument("--rounds", type=int, default=7)
    parser.add_argument("--threads", type=int, default=2)
    parser.add_argument("--samples", type=int, default=300)
    parser.add_argument("--iterations", type=int, default=30)
    parser.add_argument("--horizon", type=int, default=5)
    parser.add_argument("--train-batch", type=int, default=64, help="0 skips training")
    parser.add_argument("--train-steps", type=int, default=5, help="timed steps per round")
    parser.add_argument("--precision", choices=("32", "bf16"), default="32", help="training autocast")
    args = parser.parse_args()

    import contextlib

    import gymnasium as gym
    import numpy as np
    import torch
    from bench_wm import MODELS

    from stable_worldmodel import wm
    from stable_worldmodel.policy import PlanConfig
    from stable_worldmodel.solver import make_solver

    torch.set_num_threads(args.threads)
    preset, overrides = MODELS[args.model]
    config = wm.get_config("lewm", preset, **overrides)
    adim, size, hist, block = 2, config.image_size, config.history_size, config.frameskip
    torch.manual_seed(0)
    model = wm.make("lewm", preset, action_dim=adim, **overrides).eval()
    print(
        f"LeWM '{args.model}' ({size}px), CEM {args.samples} x {args.iterations}, horizon {args.horizon} x frameskip "
        f"{block}, {args.threads} threads, OMP_WAIT_POLICY={os.environ['OMP_WAIT_POLICY']}, "
        f"torch {torch.__version__}",
        flush=True,
    )
    g = torch.Generator().manual_seed(0)

    def infos(b: int) -> dict:
        return {
            "pixels": torch.randn(b, hist, 3, size, size, generator=g),
            "goal": torch.randn(b, hist, 3, size, size, generator=g),
        }

    print(f"{'figure':36s} {'eager':>9s} {'compiled':>9s} {'speedup':>8s}")
    for b in [int(e) for e in args.envs.split(",")]:
        solvers = []
        for compiled in (False, True):
            solver = make_solver("cem", model, num_samples=args.samples, n_steps=args.iterations, topk=30, seed=0)
            if compiled:
                solver.compile_cost()
            solver.configure(
                action_space=gym.spaces.Box(-1.0, 1.0, (b, adim), dtype=np.float32),
                n_envs=b,
                config=PlanConfig(
                    horizon=args.horizon,
                    receding_horizon=args.horizon,
                    history_len=hist,
                    action_block=block,
                ),
            )
            solvers.append(solver)
        info = infos(b)
        cand = torch.randn(b, args.samples, args.horizon, adim * block, generator=g)
        with torch.inference_mode():
            costs = [s._cost(s._expand({k: v.clone() for k, v in info.items()}, args.samples), cand) for s in solvers]
        diff = (costs[0] - costs[1]).abs().max().item()
        first = []
        for solver in solvers:  # the compiled one compiles here
            t0 = time.perf_counter()
            solver.solve({k: v.clone() for k, v in info.items()})
            first.append(time.perf_counter() - t0)
        times: list[list[float]] = [[], []]
        for _ in range(args.rounds):
            for i, solver in enumerate(solvers):
                t0 = time.perf_counter()
                solver.solve({k: v.clone() for k, v in info.items()})
                times[i].append(time.perf_counter() - t0)
        eager, comp = (1e3 * statistics.median(t) for t in times)
        print(f"{f'CEM plan ms, {b} env(s)':36s} {eager:9.1f} {comp:9.1f} {eager / comp:7.2f}x")
        print(f"  first plan s (compiles): eager {first[0]:.1f}, compiled {first[1]:.1f}; max |cost diff| {diff:.1e}")

    if args.train_batch:
        model.train()
        bt, t = args.train_batch, hist + 1
        batches = [
            {"pixels": torch.randn(bt, t, 3, size, size, generator=g), "action": torch.randn(bt, t, adim * block)}
            for _ in range(args.train_steps)
        ]
        autocast = (
            (lambda: torch.autocast("cpu", dtype=torch.bfloat16))
            if args.precision == "bf16"
            else contextlib.nullcontext
        )
        opt = torch.optim.AdamW(model.parameters(), lr=1e-5, fused=True)
        losses = [model.loss, torch.compile(model.loss)]

        def steps(loss_of) -> float:
            t0 = time.perf_counter()
            for batch in batches:
                with autocast():
                    loss = loss_of(batch)["loss"]
                opt.zero_grad(set_to_none=True)
                loss.backward()
                opt.step()
            return bt * len(batches) / (time.perf_counter() - t0)

        t0 = time.perf_counter()
        steps(losses[1])
        compile_s = time.perf_counter() - t0
        steps(losses[0])
        rates: list[list[float]] = [[], []]
        for _ in range(max(1, args.rounds // 2)):
            for i, loss_of in enumerate(losses):
                rates[i].append(steps(loss_of))
        eager, comp = (statistics.median(r) for r in rates)
        label = f"train samples/s (batch {bt}, {args.precision})"
        print(f"{label:36s} {eager:9.1f} {comp:9.1f} {comp / eager:7.2f}x")
        print(f"  first compiled steps s (compiles): {compile_s:.1f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

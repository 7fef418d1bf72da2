"""Training samples/s with the next batch read in a background thread during each step, and without.

Usage: python bench/bench_train_prefetch.py --dataset NAME [--model lewm] [--preset cpu] [--steps 300]
                                            [--threads 1] [--repeats 2] [--set KEY=VALUE ...]

Trains ``--steps`` steps of the same run twice per repeat (prefetch on, then off; alternating), each in a fresh
temporary checkpoint folder, and prints the samples/s of each (the Trainer's own ``samples_per_s`` of its last log)
and their ratio. The two runs' weights are equal (tested in tests/train); only the time differs. Worth it where
reading a batch is a real share of a step: image datasets too big to preload (a 64x64 Push-T dataset of 3000
episodes). Never asserts.
"""

from __future__ import annotations

import argparse
import os
import statistics
import tempfile


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--dataset", required=True)
    parser.add_argument("--model", default="lewm")
    parser.add_argument("--preset", default="cpu")
    parser.add_argument("--steps", type=int, default=300)
    parser.add_argument("--threads", type=int, default=1)
    parser.add_argument("--repeats", type=int, default=2)
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE")
    args = parser.parse_args()

    import torch

    torch.set_num_threads(args.threads)
    from stable_worldmodel.data import get_cache_dir
    from stable_worldmodel.train import train
    from stable_worldmodel.train.trainer import Trainer
    from stable_worldmodel.wm.config import parse_override

    overrides = dict(parse_override(item) for item in args.set)
    home = str(get_cache_dir())
    auto = Trainer._prefetching
    rates: dict[str, list[float]] = {"prefetch": [], "inline": []}
    for _ in range(args.repeats):
        for mode in rates:
            Trainer._prefetching = auto if mode == "prefetch" else (lambda self: False)
            with tempfile.TemporaryDirectory() as out:
                os.makedirs(os.path.join(out, "checkpoints"))
                for name in (args.dataset, f"{args.dataset}.h5"):  # the dataset stays where it is
                    src = os.path.join(home, name)
                    if os.path.exists(src):
                        os.symlink(src, os.path.join(out, name))
                result = train(
                    args.model,
                    args.dataset,
                    args.preset,
                    steps=args.steps,
                    cache_dir=out,
                    name="bench",
                    progress=False,
                    val_every=0,
                    ckpt_every=0,
                    logger="none",
                    **overrides,
                )
            rate = next(r["samples_per_s"] for r in reversed(result.history) if "samples_per_s" in r)
            rates[mode].append(rate)
            print(f"{mode:9s} {rate:8.1f} samples/s", flush=True)
    Trainer._prefetching = auto
    on, off = statistics.median(rates["prefetch"]), statistics.median(rates["inline"])
    print(f"{args.model} {args.preset} on {args.dataset}, {args.threads} thread(s), {args.steps} steps: ")
    print(f"median samples/s: prefetch {on:.1f}, inline {off:.1f} ({on / off:.2f}x)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

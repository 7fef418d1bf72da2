"""Training throughput of the LeWM presets: samples/s of one training step (encode, predict, loss,
backward, AdamW as our Trainer builds it) at each preset's image size and batch size, in fp32 and
bf16 autocast, and the hours its ``steps`` would take at that rate (data loading not included).

    python bench/bench_presets.py [--presets tiny,small,paper] [--device cpu|cuda] [--steps 10]
                                  [--precisions 32,bf16] [--threads 2]

Batches are random tensors made on the device once; figures only, nothing is asserted.
"""

from __future__ import annotations

import argparse
import contextlib
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))  # this checkout's package


def measure(preset: str, device, precision: str, steps: int) -> dict:
    import torch

    from stable_worldmodel import wm

    config = wm.get_config("lewm", preset)
    torch.manual_seed(0)
    model = wm.make("lewm", preset, action_dim=2).to(device).train()
    frames = config.history_size + config.num_preds
    b, size = config.batch_size, config.image_size
    g = torch.Generator().manual_seed(0)
    batches = [
        {
            "pixels": torch.randn(b, frames, 3, size, size, generator=g).to(device),
            "action": torch.randn(b, frames, 2 * config.frameskip, generator=g).to(device),
        }
        for _ in range(2)
    ]
    opt = torch.optim.AdamW(model.parameters(), lr=config.lr, fused=device.type == "cuda")
    autocast = torch.autocast(device.type, dtype=torch.bfloat16) if precision == "bf16" else contextlib.nullcontext()

    def step(batch):
        with autocast:
            loss = model.loss(batch)["loss"]
        opt.zero_grad(set_to_none=True)
        loss.backward()
        opt.step()

    def sync():
        if device.type == "cuda":
            torch.cuda.synchronize()

    for i in range(2):  # warm up
        step(batches[i % 2])
    sync()
    start = time.perf_counter()
    for i in range(steps):
        step(batches[i % 2])
    sync()
    rate = b * steps / (time.perf_counter() - start)
    return {
        "batch": b,
        "image": size,
        "samples_per_s": rate,
        "hours": config.steps * b / rate / 3600,
        "steps": config.steps,
    }


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--presets", default="tiny,small,paper")
    parser.add_argument("--device", default="cpu")
    parser.add_argument("--precisions", default="32,bf16")
    parser.add_argument("--steps", type=int, default=10)
    parser.add_argument("--threads", type=int, default=0, help="torch threads (0: torch's default)")
    args = parser.parse_args()
    import torch

    if args.threads:
        torch.set_num_threads(args.threads)
    device = torch.device(args.device)
    name = torch.cuda.get_device_name(device) if device.type == "cuda" else f"CPU, {torch.get_num_threads()} threads"
    print(f"LeWM presets, one training step (model + fused-on-CUDA AdamW), {name}, torch {torch.__version__}")
    head = ("preset", "image", "batch", "precision", "samples/s", "preset steps", "hours")
    print("{:8s} {:>5s} {:>5s} {:>9s} {:>10s} {:>12s} {:>7s}".format(*head))
    for preset in args.presets.split(","):
        for precision in args.precisions.split(","):
            r = measure(preset, device, precision, args.steps)
            print(
                f"{preset:8s} {r['image']:5d} {r['batch']:5d} {precision:>9s} {r['samples_per_s']:10.1f} "
                f"{r['steps']:12d} {r['hours']:7.2f}",
                flush=True,
            )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

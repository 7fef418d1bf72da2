"""Lance reads and ReplayBuffer sampling, ours against upstream 0.1.1 on the same data, side by side.

    python bench/bench_lance_buffer.py [--peer /work/peer011-venv/bin/python] [--episodes 100] [--length 50]

One Lance dataset is written by upstream 0.1.1's LanceWriter (its layout: JPEG frames, float32
lists) and read by both readers: ``__getitems__`` of random batches of 64 windows of 4 frames
(what a DataLoader without workers calls), in samples/s. Then both ReplayBuffers are filled with
the same episodes (64x64 frames, 2-d actions) and ``sample(64)`` is timed, in samples/s. The
upstream side runs in the peer venv (``../shared/bench/setup_peer011_venv.sh``) through this same
file (``--impl upstream``). Prints, never asserts.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

BATCH, STEPS, REPEATS = 64, 4, 5


def episodes(n: int, length: int) -> list[dict[str, np.ndarray]]:
    out = []
    for e in range(n):
        rng = np.random.default_rng(e)
        base = rng.integers(0, 255, (8, 8, 3), dtype=np.uint8)
        frames = np.repeat(np.repeat(base, 8, 0), 8, 1)[None].repeat(length, 0)  # a JPEG-friendly 64x64 texture
        frames = (frames.astype(np.int16) + np.arange(length)[:, None, None, None]).clip(0, 255).astype(np.uint8)
        out.append(
            {
                "pixels": frames,
                "action": rng.standard_normal((length, 2)).astype(np.float32),
                "proprio": rng.standard_normal((length, 4)).astype(np.float32),
            }
        )
    return out


def best_rate(fn, samples: int) -> float:
    fn()  # warm: open files, fill caches of the reader's own making
    times = []
    for _ in range(REPEATS):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return samples / min(times)


def measure(impl: str, lance_path: str, n: int, length: int) -> dict[str, float]:
    from stable_worldmodel.data import ReplayBuffer, load_dataset

    ds = load_dataset(lance_path, num_steps=STEPS)
    rng = np.random.default_rng(0)
    batches = [rng.integers(0, len(ds), BATCH).tolist() for _ in range(10)]
    read = best_rate(lambda: [ds.__getitems__(b) for b in batches], BATCH * len(batches))
    buf = ReplayBuffer(max_steps=n * length, history_len=STEPS)
    for ep in episodes(n, length):
        if impl == "upstream":  # its World.collect hands per-step lists
            ep = {k: list(v) for k, v in ep.items()}
        buf.write_episode(ep)
    sample = best_rate(lambda: [buf.sample(BATCH) for _ in range(20)], BATCH * 20)
    return {"lance_read": read, "buffer_sample": sample}


def write_upstream_lance(path: str, n: int, length: int) -> None:
    from stable_worldmodel.data.formats.lance import LanceWriter

    with LanceWriter(path, mode="overwrite") as w:
        w.write_episodes({k: list(v) for k, v in ep.items()} for ep in episodes(n, length))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--peer", default=str(Path(__file__).resolve().parents[2] / "peer011-venv/bin/python"))
    parser.add_argument("--episodes", type=int, default=100)
    parser.add_argument("--length", type=int, default=50)
    parser.add_argument("--impl", choices=("ours", "upstream"), default=None, help=argparse.SUPPRESS)
    parser.add_argument("--lance", default=None, help=argparse.SUPPRESS)
    parser.add_argument("--write", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.write:
        write_upstream_lance(args.lance, args.episodes, args.length)
        return
    if args.impl is not None:
        print(json.dumps(measure(args.impl, args.lance, args.episodes, args.length)))
        return

    folder = Path(tempfile.mkdtemp())
    lance = str(folder / "bench.lance")
    common = ["--episodes", str(args.episodes), "--length", str(args.length), "--lance", lance]
    me = str(Path(__file__).resolve())

    def run(python: str, *extra: str) -> str:
        cwd = tempfile.mkdtemp()  # not the project: the peer imports its own package
        out = subprocess.run([python, me, *common, *extra], capture_output=True, text=True, cwd=cwd, check=True)
        return out.stdout.strip().splitlines()[-1] if out.stdout.strip() else ""

    run(args.peer, "--write")
    figures = {
        impl: json.loads(run(py, "--impl", impl)) for impl, py in (("upstream", args.peer), ("ours", sys.executable))
    }
    print(
        f"{args.episodes} episodes x {args.length} steps, 64x64 frames; batches of {BATCH} windows of {STEPS} frames; "
        f"best of {REPEATS}; one Lance file written by upstream 0.1.1, read by both"
    )
    for key, label in (("lance_read", "Lance __getitems__"), ("buffer_sample", "ReplayBuffer.sample")):
        up, ours = figures["upstream"][key], figures["ours"][key]
        print(f"{label:22s} upstream {up:10,.0f} samples/s   ours {ours:10,.0f} samples/s   ratio {ours / up:5.2f}x")


if __name__ == "__main__":
    main()

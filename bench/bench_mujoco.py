"""World steps/s of the MuJoCo envs with 64x64 pixels, ours and upstream 0.1.1 side by side.

For each env (default: swm/OGBCube-v0 and swm/CartpoleDMControl-v0) and each env count (1, 4),
a ``World`` with a random policy records about ``--steps`` steps of 50-step episodes with
upstream 0.1.1's ``World.collect(path, episodes, format="hdf5")`` (after a warm-up episode per
env), steps/s = recorded rows / seconds; ours runs in this
interpreter, upstream's in ``../peer011-venv`` (built by ../shared/bench/setup_peer011_venv.sh
plus ``pip install "mujoco>=3.17,<4" dm_control ogbench``) when it exists. Each measurement is a
fresh process. Figures only, no assertions.

Usage: python bench/bench_mujoco.py [--envs swm/OGBCube-v0 ...] [--counts 1 4] [--steps 200]
       [--quality low medium high] [--repeat 3]   (--repeat: interleaved rounds, median shown)
"""

from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys
from pathlib import Path

PEER = Path(__file__).resolve().parents[2] / "peer011-venv" / "bin" / "python"

# One measurement, run by either interpreter (both packages are named stable_worldmodel).
PROBE = r"""
import json, os, sys, tempfile, time
os.environ.setdefault("MUJOCO_GL", "egl"); os.environ.setdefault("PYOPENGL_PLATFORM", "egl")
import stable_worldmodel as swm
env_id, n, steps, quality = sys.argv[1], int(sys.argv[2]), int(sys.argv[3]), sys.argv[4]
kwargs = {"render_quality": quality, "verbose": 0} if quality != "-" else {}  # upstream's World takes neither
length = 50  # random actions: every episode runs to the limit
world = swm.World(env_id, num_envs=n, image_shape=(64, 64), max_episode_steps=length, **kwargs)
world.set_policy(swm.policy.RandomPolicy(seed=0))
episodes = max(n, -(-steps // length) // n * n)
with tempfile.TemporaryDirectory() as tmp:
    world.collect(os.path.join(tmp, "warm.h5"), episodes=n, seed=0, format="hdf5", progress=False)
    t = time.perf_counter()
    world.collect(os.path.join(tmp, "data.h5"), episodes=episodes, seed=1, format="hdf5", progress=False)
    dt = time.perf_counter() - t
print(json.dumps({"steps_per_s": episodes * length / dt}))
"""


def measure(python: str, env_id: str, n: int, steps: int, quality: str) -> dict | None:
    out = subprocess.run([python, "-c", PROBE, env_id, str(n), str(steps), quality], capture_output=True, text=True,
                         cwd="/tmp", timeout=1800)
    if out.returncode != 0:
        print(f"    failed: {out.stderr.strip().splitlines()[-1] if out.stderr.strip() else out.returncode}")
        return None
    return json.loads(out.stdout.strip().splitlines()[-1])


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--envs", nargs="+", default=["swm/OGBCube-v0", "swm/CartpoleDMControl-v0"])
    parser.add_argument("--counts", nargs="+", type=int, default=[1, 4])
    parser.add_argument("--steps", type=int, default=200)
    parser.add_argument("--quality", nargs="+", default=["medium", "high"], choices=["low", "medium", "high"],
                        help="our render_quality levels to measure (upstream has one)")
    parser.add_argument("--repeat", type=int, default=1,
                        help="rounds; each round runs every configuration once, interleaved, and the median is shown")
    args = parser.parse_args()
    peer = str(PEER) if PEER.exists() else None
    print(f"World steps/s, 64x64 pixels, random policy; upstream 0.1.1: {peer or 'not found (ratio not measured)'}")
    runs = [(f"ours {q}", sys.executable, q) for q in args.quality] + ([("upstream", peer, "-")] if peer else [])
    for env_id in args.envs:
        for n in args.counts:
            samples: dict[str, list[float]] = {label: [] for label, _, _ in runs}
            for _ in range(args.repeat):  # interleaved: every configuration sees the same machine load
                for label, python, quality in runs:
                    result = measure(python, env_id, n, args.steps, quality)
                    if result is not None:
                        samples[label].append(result["steps_per_s"])
            row = {k: statistics.median(v) for k, v in samples.items() if v}
            figures = ", ".join(f"{k} {v:.1f}" + (f" ({'/'.join(f'{x:.1f}' for x in samples[k])})" if len(samples[k]) > 1 else "")
                                for k, v in row.items())
            ratios = ", ".join(f"{k[5:]} {v / row['upstream']:.1f}x" for k, v in row.items()
                               if k.startswith("ours") and "upstream" in row)
            print(f"  {env_id:28s} {n} env(s): {figures}" + (f"  ours/upstream: {ratios}" if ratios else ""), flush=True)


if __name__ == "__main__":
    main()

"""World steps/s of the MuJoCo envs with 64x64 pixels, ours and upstream 0.1.1 side by side.

For each env (default: swm/OGBCube-v0 and swm/CartpoleDMControl-v0) and each env count (1, 4),
a ``World`` with a random policy records about ``--steps`` steps of 50-step episodes with
upstream 0.1.1's ``World.collect(path, episodes, format="hdf5")`` (after a warm-up episode per
env), steps/s = recorded rows / seconds; ours runs in this
interpreter, upstream's in ``../peer011-venv`` (built by ../shared/bench/setup_peer011_venv.sh
plus ``pip install "mujoco>=3.17,<4" dm_control ogbench``) when it exists. Each measurement is a
fresh process. Figures only, no assertions.

``--upstream-fixed`` adds a row for upstream with one bug patched in the measuring process:
OGBench recompiles its model and replaces its ``mujoco.Renderer`` at every reset, and
``Renderer.close`` frees the GL objects in whichever context is current, i.e. another env's, so
from 2 envs on most of upstream's frames are wrong (measured at 4 envs: 150 of the 208 frames of
the timed collect differ from a correct render of the same state, median MAD 26/255; the
corrupted renderers return garbage or another env's frame in ~0 ms, which is why upstream's
steps/s rise with the env count). The patch makes each renderer free its objects in its own
context first, so every frame is right.

``--picture``: the image-quality side (ours only): for each env and each ``--quality`` below
``high``, the mean absolute difference (out of 255) of its 64x64 ``render()`` frames to the
``high`` ones (MuJoCo's own settings, upstream's picture) over 12 states: seeds 0-3, frames after
0, 20 and 45 random actions (the same actions for both qualities: rendering never touches the
physics); the worst frame's MAD too.

Usage: python bench/bench_mujoco.py [--envs swm/OGBCube-v0 ...] [--counts 1 4] [--steps 200]
       [--quality low medium high] [--repeat 3]   (--repeat: interleaved rounds, median shown)
       python bench/bench_mujoco.py --picture [--envs ...] [--quality low medium]
"""

from __future__ import annotations

import argparse
import json
import os
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
if quality == "fixed":  # upstream with its renderer-freeing bug patched (module docstring)
    import mujoco
    _close = mujoco.Renderer.close
    def close(self):
        if getattr(self, "_mjr_context", None) is not None and getattr(self, "_gl_context", None) is not None:
            self._gl_context.make_current()  # free the GL objects in this renderer's own context
        _close(self)
    mujoco.Renderer.close = close
# upstream's World takes neither
kwargs = {"render_quality": quality, "verbose": 0} if quality not in ("-", "fixed") else {}
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


# Picture: frames of one quality against "high" on the same states (ours only).
PICTURE = r"""
import json, os, sys
os.environ.setdefault("MUJOCO_GL", "egl"); os.environ.setdefault("PYOPENGL_PLATFORM", "egl")
import gymnasium as gym, numpy as np
import stable_worldmodel  # noqa: F401  (registers the envs)
env_id, quality = sys.argv[1], sys.argv[2]
envs = {q: gym.make(env_id, render_quality=q).unwrapped for q in (quality, "high")}
mads = []
for seed in range(4):
    frames = {q: [] for q in envs}
    for q, env in envs.items():
        env.set_render_size((64, 64))
        env.reset(seed=seed)
        actions = np.random.default_rng(seed).uniform(-1, 1, (46, *env.action_space.shape)).astype(np.float32)
        for t, action in enumerate(actions):
            if t in (0, 20, 45):
                frames[q].append(env.render().astype(np.float64))
            env.step(action)
    mads += [float(np.abs(a - b).mean()) for a, b in zip(frames[quality], frames["high"])]
print(json.dumps({"mad": float(np.mean(mads)), "worst": max(mads)}))
"""


def picture(env_id: str, quality: str) -> dict | None:
    out = subprocess.run(
        [sys.executable, "-c", PICTURE, env_id, quality], capture_output=True, text=True, cwd="/tmp", timeout=1800
    )
    if out.returncode != 0:
        print(f"    failed: {out.stderr.strip().splitlines()[-1] if out.stderr.strip() else out.returncode}")
        return None
    return json.loads(out.stdout.strip().splitlines()[-1])


def measure(python: str, env_id: str, n: int, steps: int, quality: str, path: str | None = None) -> dict | None:
    env = {**os.environ, "PYTHONPATH": path} if path else None  # path: another checkout of ours first
    out = subprocess.run(
        [python, "-c", PROBE, env_id, str(n), str(steps), quality],
        capture_output=True,
        text=True,
        cwd="/tmp",
        timeout=1800,
        env=env,
    )
    if out.returncode != 0:
        print(f"    failed: {out.stderr.strip().splitlines()[-1] if out.stderr.strip() else out.returncode}")
        return None
    return json.loads(out.stdout.strip().splitlines()[-1])


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--envs", nargs="+", default=["swm/OGBCube-v0", "swm/CartpoleDMControl-v0"])
    parser.add_argument("--counts", nargs="+", type=int, default=[1, 4])
    parser.add_argument("--steps", type=int, default=200)
    parser.add_argument(
        "--quality",
        nargs="+",
        default=["medium", "high"],
        choices=["low", "medium", "high"],
        help="our render_quality levels to measure (upstream has one)",
    )
    parser.add_argument(
        "--repeat",
        type=int,
        default=1,
        help="rounds; each round runs every configuration once, interleaved, and the median is shown",
    )
    parser.add_argument(
        "--base",
        default=None,
        metavar="DIR",
        help="also measure the stable_worldmodel package under DIR (e.g. an extracted older commit: "
        "git archive HEAD stable_worldmodel | tar -x -C DIR) with this interpreter, as 'base'",
    )
    parser.add_argument(
        "--upstream-fixed",
        action="store_true",
        help="also measure upstream with its renderer-freeing bug patched (module docstring)",
    )
    parser.add_argument(
        "--picture",
        action="store_true",
        help="measure the picture instead: MAD of each --quality below high to high (module docstring)",
    )
    args = parser.parse_args()
    if args.picture:
        print("Picture, 64x64 render(), 12 states (seeds 0-3, after 0/20/45 random actions): MAD to 'high', out of 255")
        for env_id in args.envs:
            for q in (q for q in args.quality if q != "high"):
                result = picture(env_id, q)
                if result is not None:
                    print(
                        f"  {env_id:28s} {q:6s}: MAD {result['mad']:.3f} (worst frame {result['worst']:.3f})",
                        flush=True,
                    )
        return
    peer = str(PEER) if PEER.exists() else None
    print(f"World steps/s, 64x64 pixels, random policy; upstream 0.1.1: {peer or 'not found (ratio not measured)'}")
    runs = [(f"ours {q}", sys.executable, q, None) for q in args.quality]
    runs += [(f"base {q}", sys.executable, q, args.base) for q in args.quality] if args.base else []
    runs += [("upstream", peer, "-", None)] if peer else []
    runs += [("upstream fixed", peer, "fixed", None)] if peer and args.upstream_fixed else []
    for env_id in args.envs:
        for n in args.counts:
            samples: dict[str, list[float]] = {label: [] for label, *_ in runs}
            for _ in range(args.repeat):  # interleaved: every configuration sees the same machine load
                for label, python, quality, path in runs:
                    result = measure(python, env_id, n, args.steps, quality, path)
                    if result is not None:
                        samples[label].append(result["steps_per_s"])
            row = {k: statistics.median(v) for k, v in samples.items() if v}
            figures = ", ".join(
                f"{k} {v:.1f}" + (f" ({'/'.join(f'{x:.1f}' for x in samples[k])})" if len(samples[k]) > 1 else "")
                for k, v in row.items()
            )
            ratios = ", ".join(
                f"{k} {v / row['upstream']:.1f}x"
                for k, v in row.items()
                if not k.startswith("upstream") and "upstream" in row
            )
            if "upstream fixed" in row:
                ratios += "; vs upstream fixed: " + ", ".join(
                    f"{k} {v / row['upstream fixed']:.1f}x" for k, v in row.items() if not k.startswith("upstream")
                )
            print(
                f"  {env_id:28s} {n} env(s): {figures}"
                + (f"  vs upstream: {ratios}" if ratios else "")
                + f"  [load {os.getloadavg()[0]:.1f}]",
                flush=True,
            )


if __name__ == "__main__":
    main()

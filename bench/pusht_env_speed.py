"""PushT ``env.step()`` + ``env.render()`` per second at a given resolution, through gymnasium only.

Runs under any interpreter that has a ``stable_worldmodel`` (ours or the original release),
so the two can be measured side by side on one machine:

    .venv/bin/python bench/pusht_env_speed.py --size 64
    ../peer-venv/bin/python bench/pusht_env_speed.py --size 64

Prints figures; never asserts.
"""

from __future__ import annotations

import argparse
import time

import gymnasium as gym
import numpy as np

import stable_worldmodel  # noqa: F401  (registers swm/... ids)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--size", type=int, default=64)
    parser.add_argument(
        "--env", default="swm/PushT-v1", help="swm/PushT-v1 (upstream behaviour) or swm/PushT-v2 (ours only)"
    )
    parser.add_argument("--steps", type=int, default=2000)
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    env = gym.make(args.env, resolution=args.size, disable_env_checker=True, max_episode_steps=10**9)
    env.reset(seed=0)
    frame = env.render()
    actions = np.random.default_rng(0).uniform(-1, 1, (args.steps, 2)).astype(np.float32)
    best = 0.0
    for _ in range(args.repeats):
        env.reset(seed=0)
        start = time.perf_counter()
        for a in actions:
            env.step(a)
            env.render()
        best = max(best, args.steps / (time.perf_counter() - start))
    print(
        f"{stable_worldmodel.__name__} {getattr(stable_worldmodel, '__version__', '?')}: PushT step+render at "
        f"{frame.shape[0]}x{frame.shape[1]}: {best:.0f} steps/s (best of {args.repeats} x {args.steps})"
    )


if __name__ == "__main__":
    main()

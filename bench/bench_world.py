"""World env-steps/s for 1, 4 and 16 envs at 64x64 and 224x224, sync vs async, and evaluate episodes/s.

Usage: python bench/bench_world.py [--env swm/PushT-v1] [--steps 200] [--quick]
Prints figures; never asserts on time.
"""

from __future__ import annotations

import argparse
import time

import stable_worldmodel as swm
from stable_worldmodel.policy import RandomPolicy


def steps_per_s(env: str, n: int, size: int, mode: str, steps: int) -> float:
    world = swm.World(
        env, num_envs=n, image_shape=(size, size), verbose=0, vectorization_mode=mode, max_episode_steps=10**6
    )
    world.set_policy(RandomPolicy(seed=0))
    world.reset(seed=0)
    for _ in range(5):  # warm up
        world.step()
    start = time.perf_counter()
    for _ in range(steps):
        world.step()
    elapsed = time.perf_counter() - start
    world.close()
    return steps * n / elapsed


def evaluate_eps_per_s(env: str, n: int, episodes: int, max_steps: int) -> float:
    world = swm.World(env, num_envs=n, image_shape=(64, 64), verbose=0, max_episode_steps=max_steps)
    world.set_policy(RandomPolicy(seed=0))
    start = time.perf_counter()
    world.evaluate(episodes=episodes, seed=0)
    elapsed = time.perf_counter() - start
    world.close()
    return episodes / elapsed


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--env", default="swm/PushT-v1")
    parser.add_argument("--steps", type=int, default=200)
    parser.add_argument("--quick", action="store_true")
    args = parser.parse_args()
    steps = 30 if args.quick else args.steps
    print(f"World env-steps/s on {args.env} ({steps} world steps each)")
    print(f"{'envs':>5} {'size':>5} {'sync':>10} {'async':>10} {'auto':>10}")
    for size in (64, 224):
        for n in (1, 4, 16):
            row = [steps_per_s(args.env, n, size, mode, steps) for mode in ("sync", "async", "auto")]
            print(f"{n:>5} {size:>5} " + " ".join(f"{v:>10.0f}" for v in row))
    eps = 16 if args.quick else 64
    print(
        f"evaluate: {evaluate_eps_per_s(args.env, 8, eps, 50):.2f} episodes/s (8 envs, 50-step episodes, random policy)"
    )


if __name__ == "__main__":
    main()

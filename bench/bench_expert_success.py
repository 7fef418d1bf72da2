"""Expert success rates of every built-in env with World.evaluate on 100 seeded episodes.

Usage: python bench/bench_expert_success.py [--episodes 100] [--num-envs 8] [--variation]
Prints one row per env (success rate, mean episode length, episodes/s); never asserts.
"""

from __future__ import annotations

import argparse
import time

import stable_worldmodel as swm

# the acceptance targets of the env issue (episode limits as registered)
TARGETS = {
    "swm/TwoRoom-v1": None,
    "swm/TwoRoom-v2": 95,
    "swm/SimplePointMaze-v1": 90,
    "swm/VoidRun-v0": 80,
    "swm/PushT-v1": 60,
    "swm/PushT-Discrete-v1": None,
    "swm/ImagePositioning-v1": None,
}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--episodes", type=int, default=100)
    parser.add_argument("--num-envs", type=int, default=8)
    parser.add_argument("--variation", action="store_true", help="resample every factor each episode")
    args = parser.parse_args()
    options = {"variation": ["all"]} if args.variation else None
    print(
        f"expert success, {args.episodes} episodes (seeds 0..{args.episodes - 1}), "
        f"{args.num_envs} envs, 64x64, options={options}"
    )
    print(f"{'env':<26} {'max steps':>9} {'success':>8} {'target':>7} {'mean len':>9} {'eps/s':>7}")
    for env_id, target in TARGETS.items():
        steps = swm.envs.get_entry(env_id).max_episode_steps or 100
        world = swm.World(env_id, num_envs=args.num_envs, image_shape=(64, 64), max_episode_steps=steps, verbose=0)
        world.set_policy(swm.envs.expert_policy(env_id))
        start = time.perf_counter()
        res = world.evaluate(episodes=args.episodes, seed=0, options=options)
        elapsed = time.perf_counter() - start
        world.close()
        tgt = f">={target}%" if target else "-"
        print(
            f"{env_id:<26} {steps:>9} {res['success_rate']:>7.0f}% {tgt:>7} "
            f"{res['episode_lengths'].mean():>9.1f} {args.episodes / elapsed:>7.1f}"
        )


if __name__ == "__main__":
    main()

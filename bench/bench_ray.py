"""Collection on Ray versus the in-process World (figures only, no assertions).

Records the same seeds of one env with its expert three ways and prints episodes/s:
``World(env, 1)`` and ``World(env, K)`` in this process, and ``record_dataset_on_ray`` with
K shards on a private local Ray (startup timed apart). The overhead per task is the Ray run's
time minus the work spread over the CPUs, per task, measured with near-empty shards.

Usage: python bench/bench_ray.py [--env swm/TwoRoom-v2] [--episodes 64] [--cpus 2]
"""

from __future__ import annotations

import argparse
import tempfile
import time


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--env", default="swm/TwoRoom-v2")
    parser.add_argument("--episodes", type=int, default=64)
    parser.add_argument("--cpus", type=int, default=2)
    parser.add_argument("--image-size", type=int, default=64)
    args = parser.parse_args()

    import stable_worldmodel as swm
    from stable_worldmodel.planning.policies import episode_limit
    from stable_worldmodel.world import on_ray

    limit = episode_limit(args.env)
    with tempfile.TemporaryDirectory(dir="/tmp", prefix="swmb") as cache:
        rates = {}
        for k in (1, args.cpus):
            with swm.World(args.env, k, (args.image_size,) * 2, max_episode_steps=limit, verbose=0) as world:
                world.set_policy(swm.envs.expert_policy(args.env))
                t = time.perf_counter()
                world.record_dataset(f"w{k}", episodes=args.episodes, seed=0, cache_dir=cache)
                rates[f"World, {k} env(s), in process"] = args.episodes / (time.perf_counter() - t)

        t = time.perf_counter()
        on_ray.init_ray(num_cpus=args.cpus, cache_dir=cache)
        startup = time.perf_counter() - t
        t = time.perf_counter()
        on_ray.record_dataset_on_ray(
            args.env,
            "ray",
            args.episodes,
            seed=0,
            shards=args.cpus,
            image_size=args.image_size,
            max_steps=limit,
            cache_dir=cache,
            progress=False,
        )
        ray_s = time.perf_counter() - t
        rates[f"Ray, {args.cpus} shards of 1 env"] = args.episodes / ray_s

        tasks = 4 * args.cpus  # near-empty shards: what a task costs beyond its episodes
        t = time.perf_counter()
        on_ray.record_dataset_on_ray(
            args.env,
            "tiny",
            tasks,
            seed=0,
            shards=tasks,
            image_size=args.image_size,
            max_steps=limit,
            cache_dir=cache,
            progress=False,
        )
        tiny_s = time.perf_counter() - t
        one_episode = 1.0 / rates["World, 1 env(s), in process"]
        overhead = (tiny_s - tasks * one_episode / args.cpus) * args.cpus / tasks

        import ray

        ray.shutdown()
    print(f"{args.env}, {args.episodes} expert episodes at {args.image_size}x{args.image_size}, {args.cpus} CPUs")
    for label, rate in rates.items():
        print(f"  {label:34s} {rate:7.1f} episodes/s")
    print(f"  Ray startup (local, {args.cpus} CPUs)      {startup:7.2f} s (once per process)")
    print(
        f"  overhead per Ray task                {overhead:7.2f} s (warm workers: World and policy built, shard opened)"
    )


if __name__ == "__main__":
    main()

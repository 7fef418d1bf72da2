"""Expert success rates and env speed for ``swm/TwoRoom-v2`` and ``swm/SimplePointMaze-v1``.

For each env, with the default factors and with ``{"variation": ["all"]}``:

- ``loop``: success rate of the expert over seeds ``0 .. episodes - 1`` in one env, stepped
  by hand, with the mean / longest number of steps to success;
- ``World``: ``World(env_id, num_envs=8, image_shape=(64, 64), max_episode_steps=...)
  .evaluate(episodes, seed=0)`` success rate;
- ``step+render/s``: ``env.step()`` + ``env.render()`` at 64x64 with random actions (one env).

Run: ``.venv/bin/python bench/bench_experts.py [--episodes 100] [--steps 3000]``. Prints, never asserts.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

import stable_worldmodel as swm
from stable_worldmodel import keys

ENVS = {"swm/TwoRoom-v2": 100, "swm/SimplePointMaze-v1": 150}  # env id -> max_episode_steps
OPTIONS = (("default", None), ("variation=all", {"variation": ["all"]}))


def make(env_id: str):
    import gymnasium as gym

    env = gym.make(env_id).unwrapped
    env.set_render_size((64, 64))
    return env


def loop_success(env_id: str, episodes: int, options: dict | None) -> tuple[float, float, int]:
    """(success %, mean steps of successful episodes, longest successful episode)."""
    env, policy = make(env_id), swm.envs.expert_policy(env_id)
    steps = []
    for seed in range(episodes):
        obs, info = env.reset(seed=seed, options=options)
        for t in range(1, ENVS[env_id] + 1):
            infos = {keys.STATE: obs[keys.STATE][None, None], keys.GOAL_STATE: info[keys.GOAL_STATE][None, None]}
            obs, _, terminated, _, info = env.step(policy.get_action(infos)[0])
            if terminated:
                steps.append(t)
                break
    return 100.0 * len(steps) / episodes, float(np.mean(steps)) if steps else float("nan"), max(steps, default=0)


def world_success(env_id: str, episodes: int, options: dict | None) -> float:
    world = swm.World(env_id, num_envs=8, image_shape=(64, 64), max_episode_steps=ENVS[env_id], verbose=0)
    world.set_policy(swm.envs.expert_policy(env_id))
    return float(world.evaluate(episodes=episodes, seed=0, options=options)["success_rate"])


def steps_per_second(env_id: str, steps: int) -> float:
    env = make(env_id)
    env.reset(seed=0)
    actions = np.random.default_rng(0).uniform(-1, 1, (steps, 2)).astype(np.float32)
    start = time.perf_counter()
    for a in actions:
        _, _, terminated, _, _ = env.step(a)
        env.render()
        if terminated:
            env.reset()
    return steps / (time.perf_counter() - start)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--episodes", type=int, default=100)
    parser.add_argument("--steps", type=int, default=3000)
    args = parser.parse_args()
    print(f"{'env':<24}{'options':<15}{'loop %':>8}{'mean/max steps':>16}{'World %':>9}")
    for env_id in ENVS:
        for label, options in OPTIONS:
            rate, mean_steps, longest = loop_success(env_id, args.episodes, options)
            world_rate = world_success(env_id, args.episodes, options)
            print(f"{env_id:<24}{label:<15}{rate:>8.1f}{mean_steps:>10.1f} /{longest:>4}{world_rate:>9.1f}")
    for env_id in ENVS:
        print(f"{env_id:<24}step+render/s at 64x64: {steps_per_second(env_id, args.steps):,.0f}")


if __name__ == "__main__":
    main()

"""Expert success rates and env speed for ``swm/VoidRun-v0`` and ``swm/ImagePositioning-v1``.

Prints, per env and per reset options (defaults, then ``{"variation": ["all"]}``):

- the expert's success rate over 100 seeded episodes, in a plain single-env loop and with
  ``World(env_id, num_envs=8, image_shape=(64, 64), max_episode_steps=...).evaluate(episodes=100,
  seed=0)`` (skipped, with the reason, when ``World`` cannot be built);
- ``env.step()`` + ``env.render()`` calls per second at 64x64 (random actions, single env, the
  resets after falls or successes not timed).

Run: ``.venv/bin/python bench/bench_experts_grid.py [--episodes 100]``. Figures, not asserts.
"""

from __future__ import annotations

import argparse
import time

import gymnasium as gym
import numpy as np

import stable_worldmodel as swm
from stable_worldmodel.envs import expert_policy

MAX_EPISODE_STEPS = {"swm/VoidRun-v0": 100, "swm/ImagePositioning-v1": 100}
OPTIONS = {"default": None, "variation=all": {"variation": ["all"]}}


def single_env_success(env_id: str, episodes: int, options: dict | None) -> tuple[float, float, int]:
    """Success rate (%), mean and longest episode length of the expert over seeds ``0 .. episodes - 1``."""
    env = gym.make(env_id, render_size=(64, 64)).unwrapped
    policy = expert_policy(env_id)
    wins, lengths = 0, []
    for seed in range(episodes):
        obs, info = env.reset(seed=seed, options=options)
        for t in range(1, MAX_EPISODE_STEPS[env_id] + 1):  # noqa: B007 (t, the episode length, is read after the loop)
            batch = {k: np.asarray(v)[None, None] for k, v in {**obs, **info}.items()}
            obs, _, terminated, truncated, info = env.step(policy.get_action(batch)[0])
            if terminated or truncated:
                break
        wins += bool(terminated)
        lengths.append(t)
    return 100.0 * wins / episodes, float(np.mean(lengths)), int(np.max(lengths))


def world_success(env_id: str, episodes: int, options: dict | None) -> str:
    try:
        world = swm.World(
            env_id, num_envs=8, image_shape=(64, 64), max_episode_steps=MAX_EPISODE_STEPS[env_id], verbose=0
        )
        world.set_policy(expert_policy(env_id))
        result = world.evaluate(episodes=episodes, seed=0, options=options)
    except Exception as exc:  # a benchmark reports, it does not stop  # noqa: BLE001
        return f"skipped ({type(exc).__name__}: {exc})"
    return f"{result['success_rate']:.0f}% (mean length {np.mean(result['episode_lengths']):.1f})"


def steps_per_second(env_id: str, seconds: float = 2.0) -> float:
    """``env.step()`` + ``env.render()`` calls per second at 64x64 with random actions (resets not timed)."""
    env = gym.make(env_id, render_size=(64, 64)).unwrapped
    env.action_space.seed(0)
    env.reset(seed=0)
    n, busy = 0, 0.0
    while busy < seconds:
        action = env.action_space.sample()
        start = time.perf_counter()
        _, _, terminated, truncated, _ = env.step(action)
        frame = env.render()
        busy += time.perf_counter() - start
        n += 1
        if terminated or truncated:
            env.reset(seed=n)
    assert frame.shape == (64, 64, 3)
    return n / busy


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--episodes", type=int, default=100)
    args = parser.parse_args()
    for env_id in MAX_EPISODE_STEPS:
        print(f"{env_id} (max_episode_steps={MAX_EPISODE_STEPS[env_id]})")
        for label, options in OPTIONS.items():
            rate, length, longest = single_env_success(env_id, args.episodes, options)
            print(
                f"  expert, {label:>13}: single env {rate:.0f}% (length mean {length:.1f}, max {longest}); "
                f"World 8 envs {world_success(env_id, args.episodes, options)}"
            )
        print(f"  step + render at 64x64: {steps_per_second(env_id):,.0f} steps/s")


if __name__ == "__main__":
    main()

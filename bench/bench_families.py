"""World env-steps/s of the env families of upstream's main (issue 31), beside the simulator they wrap.

Usage: python bench/bench_families.py [--envs ID ...] [--steps 100] [--sizes 64] [--num-envs 1 4]

For each env: our World (random policy, pixels at SIZE x SIZE, 1 and 4 envs) and, where the family wraps a
third-party env, that env alone (``gym.make(raw)``: ``step()`` + ``render()`` at its own size, or at the first
SIZE where it takes one (OGBench), one env) as the
reference upstream's main builds on: upstream's main is not on PyPI, so the simulator is the original that installs
here. An env whose extra is missing prints ``n/a``. Prints figures; never asserts on time.
"""

from __future__ import annotations

import argparse
import time

import gymnasium as gym
import numpy as np

import stable_worldmodel as swm
from stable_worldmodel.envs import list_envs
from stable_worldmodel.policy import RandomPolicy

#: our id -> (the third-party id it wraps or reimplements, the module that registers that id)
RAW = {
    "swm/CartPoleControl-v1": ("CartPole-v1", None),
    "swm/MountainCarControl-v0": ("MountainCar-v0", None),
    "swm/MountainCarContinuousControl-v0": ("MountainCarContinuous-v0", None),
    "swm/AcrobotControl-v1": ("Acrobot-v1", None),
    "swm/PendulumControl-v1": ("Pendulum-v1", None),
    "swm/OGBMaze-v0": ("pointmaze-medium-v0", "ogbench"),
    "swm/FetchReach-v3": ("FetchReach-v4", "gymnasium_robotics"),
    "swm/FetchPush-v3": ("FetchPush-v4", "gymnasium_robotics"),
    "ALE/Pong-v5": ("ALE/Pong-v5", "ale_py"),
    "swm/PFRocketLanding-v0": ("PyFlyt/Rocket-Landing-v4", "PyFlyt.gym_envs"),
}
#: simulators that take the frame size: rendered at the World's size, so both sides draw the same pixels
SIZED = {"ogbench"}
#: the ids measured by default: one or two per family
DEFAULT = [
    "swm/CartPoleControl-v1",
    "swm/PendulumControl-v1",
    "swm/MountainCarContinuousControl-v0",
    "swm/AcrobotControl-v1",
    "swm/OGBMaze-v0",
    "swm/FetchReach-v3",
    "swm/FetchPush-v3",
    "ALE/Pong-v5",
    "swm/CraftaxClassicPixels-v1",
    "swm/PFRocketLanding-v0",
    "swm/Piecewise-v0",
]


def world_steps_per_s(env_id: str, n: int, size: int, steps: int) -> float:
    world = swm.World(env_id, num_envs=n, image_shape=(size, size), verbose=0, max_episode_steps=10**6)
    try:
        world.set_policy(RandomPolicy(seed=0))
        world.reset(seed=0)
        for _ in range(3):  # warm up (compiles, first renders)
            world.step()
        start = time.perf_counter()
        for _ in range(steps):
            world.step()
        return steps * n / (time.perf_counter() - start)
    finally:
        world.close()


def raw_steps_per_s(env_id: str, module: str | None, steps: int, size: int) -> float:
    if module is not None:
        import importlib

        registered = importlib.import_module(module)
        gym.register_envs(registered)
    kwargs = {"width": size, "height": size} if module in SIZED else {}
    env = gym.make(env_id, render_mode="rgb_array", **kwargs)
    try:
        env.reset(seed=0)
        env.action_space.seed(0)
        for _ in range(3):
            env.step(env.action_space.sample())
            env.render()
        start = time.perf_counter()
        for _ in range(steps):
            _, _, term, trunc, _ = env.step(env.action_space.sample())
            env.render()
            if term or trunc:
                env.reset()
        return steps / (time.perf_counter() - start)
    finally:
        env.close()


def _cell(fn, *args) -> str:
    try:
        return f"{fn(*args):.0f}"
    except Exception as exc:  # a missing extra or simulator: the row says so
        return f"n/a ({type(exc).__name__})"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--envs", nargs="*", default=None, help="env ids (default: one or two per family)")
    parser.add_argument("--steps", type=int, default=100)
    parser.add_argument("--sizes", type=int, nargs="*", default=[64])
    parser.add_argument("--num-envs", type=int, nargs="*", default=[1, 4])
    args = parser.parse_args()
    known = set(list_envs())
    envs = args.envs or [e for e in DEFAULT if e in known or e.startswith("ALE/")]
    heads = [f"World {n} env{'s' if n > 1 else ''} {s}px" for s in args.sizes for n in args.num_envs]
    print("| env | " + " | ".join(heads) + " | simulator alone (1 env, its size) |")
    print("| --- | " + " | ".join("---:" for _ in heads) + " | ---: |")
    for env_id in envs:
        cells = [_cell(world_steps_per_s, env_id, n, s, args.steps) for s in args.sizes for n in args.num_envs]
        raw = RAW.get(env_id)
        reference = f"{_cell(raw_steps_per_s, raw[0], raw[1], args.steps, args.sizes[0])} ({raw[0]})" if raw else "-"
        print(f"| `{env_id}` | " + " | ".join(cells) + f" | {reference} |")
    print(f"\n(env steps/s, random policy, {args.steps} World steps after 3 warm-up steps; numpy {np.__version__})")


if __name__ == "__main__":
    main()

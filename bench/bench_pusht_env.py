"""PushT speed and expert success rate.

Prints:

- ``env.step()`` + ``env.render()`` per second at 64x64 (single env, random actions), and the
  split between physics and drawing; the original release's env (pygame at 512x512, then a
  resize) does a few hundred per second, so the target is >= 5x that;
- the PushTExpert's time per action and success rate within 300 steps over seeds 0..N-1 in a
  plain single-env loop, for defaults and for a few factors of variation;
- the same success rate through ``World("swm/PushT-v2", num_envs=8, image_shape=(64, 64),
  max_episode_steps=300).evaluate(episodes=N, seed=0)`` (skipped, with the reason, when World
  cannot be built), and the discrete expert's in the single-env loop.

Run: ``.venv/bin/python bench/bench_pusht_env.py [--episodes 100] [--steps 5000]``. Figures, not asserts.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from stable_worldmodel import keys
from stable_worldmodel.envs.pusht import PushT, PushTDiscrete, PushTDiscreteExpert, PushTExpert


def step_speed(n_steps: int) -> None:
    env = PushT(render_size=(64, 64))
    env.reset(seed=0)
    actions = np.random.default_rng(0).uniform(-1, 1, (n_steps, 2)).astype(np.float32)
    t_step = t_render = 0.0
    for a in actions:
        t0 = time.perf_counter()
        env.step(a)
        t1 = time.perf_counter()
        env.render()
        t2 = time.perf_counter()
        t_step, t_render = t_step + t1 - t0, t_render + t2 - t1
    total = t_step + t_render
    print(
        f"PushT step+render 64x64: {n_steps / total:,.0f} steps/s "
        f"(step {1e6 * t_step / n_steps:.0f} us, render {1e6 * t_render / n_steps:.0f} us)"
    )


def expert_loop(env, expert, episodes: int, options: dict | None, variation_keys: tuple[str, ...] = ()) -> str:
    successes, lengths, t_act, n_act = 0, [], 0.0, 0
    for seed in range(episodes):
        obs, info = env.reset(seed=seed, options=options)
        extra = {f"{keys.VARIATION}.{k}": np.array([[_factor(env, k)]]) for k in variation_keys}
        for t in range(300):
            infos = {
                keys.STATE: obs[keys.STATE][None, None],
                keys.GOAL_STATE: info[keys.GOAL_STATE][None, None],
                **extra,
            }
            t0 = time.perf_counter()
            action = expert.get_action(infos)[0]
            t_act, n_act = t_act + time.perf_counter() - t0, n_act + 1
            obs, _, terminated, _, info = env.step(action)
            if terminated:
                successes += 1
                lengths.append(t + 1)
                break
    mean_len = np.mean(lengths) if lengths else float("nan")
    return (
        f"success {100 * successes / episodes:.0f}% ({successes}/{episodes}), mean length of successes {mean_len:.0f}, "
        f"{1e3 * t_act / max(n_act, 1):.2f} ms per action"
    )


def _factor(env, name: str) -> float:
    v = env.variation_space.value
    for part in name.split("."):
        v = v[part]
    return float(np.asarray(v))


def world_success(episodes: int) -> None:
    try:
        import stable_worldmodel as swm

        world = swm.World("swm/PushT-v2", num_envs=8, image_shape=(64, 64), max_episode_steps=300, verbose=0)
    except Exception as exc:  # noqa: BLE001 - a benchmark reports why it skipped
        print(f"World evaluate: skipped ({type(exc).__name__}: {exc})")
        return
    world.set_policy(swm.envs.expert_policy("swm/PushT-v2"))
    t0 = time.perf_counter()
    result = world.evaluate(episodes=episodes, seed=0)
    print(
        f"World(num_envs=8).evaluate({episodes}, seed=0): "
        f"success {result['success_rate']:.0f}% in {time.perf_counter() - t0:.1f} s"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--episodes", type=int, default=100)
    parser.add_argument("--steps", type=int, default=5000)
    args = parser.parse_args()
    step_speed(args.steps)
    env = PushT(render_size=(64, 64))
    print("expert, defaults:", expert_loop(env, PushTExpert(), args.episodes, None))
    shape_keys = ("block.shape", "block.scale", "agent.scale")
    for names in (["block.shape"], ["block.scale", "agent.scale"], ["goal.position", "goal.angle"]):
        result = expert_loop(env, PushTExpert(), args.episodes, {keys.VARIATION: names}, shape_keys)
        print(f"expert, variation={names}:", result)
    world_success(args.episodes)
    disc = PushTDiscrete(render_size=(64, 64))
    print("discrete expert, defaults:", expert_loop(disc, PushTDiscreteExpert(), args.episodes, None))


if __name__ == "__main__":
    main()

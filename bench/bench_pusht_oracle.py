"""The ceiling of upstream's Push-T protocol: CEM planning through the true simulator (a perfect world model).

Usage: python bench/bench_pusht_oracle.py [--dataset pusht-weak] [--episodes 50] [--cost zl2|shaped]
       [--samples 300] [--iterations 30] [--topk 30] [--seed 42]

The same starts as ``swm eval swm/PushT-v1 --policy random --protocol upstream --from-dataset DATASET --seed SEED``
(the validation episodes of ``swm train``'s default split; goal 25 steps later, budget 50) and the same planner
settings (CEM ``samples`` x ``iterations``, ``topk`` elites, horizon 5 blocks of 5 actions, receding horizon 5, the
cost of the final state, actions drawn from N(0, 1) in the dataset's normalized action units). The only change: each
candidate is scored by running it in a copy of the env's physics from the current state (agent and block positions,
velocities, block angle) instead of in a learned model. Costs:

- ``zl2``: squared distance to the goal state over its 7 numbers, each divided by its standard deviation in the
  dataset (the distance an isotropic embedding of the normalized state would measure);
- ``shaped``: the success test's own terms, ``|agent, block - goal| / 20 px + |angle - goal| / 20 degrees``.

Prints the success rate with its 95% interval. Single process, ~20 s per episode on this CPU. Never asserts.
"""

from __future__ import annotations

import argparse
import math
import time

import numpy as np

HORIZON, BLOCK, OFFSET, BUDGET = 5, 5, 25, 50


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--dataset", default="pusht-weak")
    parser.add_argument("--episodes", type=int, default=50)
    parser.add_argument("--cost", choices=("zl2", "shaped"), default="zl2")
    parser.add_argument("--samples", type=int, default=300)
    parser.add_argument("--iterations", type=int, default=30)
    parser.add_argument("--topk", type=int, default=30)
    parser.add_argument("--seed", type=int, default=42, help="swm eval's default seed: the same starts")
    args = parser.parse_args()

    from stable_worldmodel.cli.evaluation import DEFAULT_SPLIT, dataset_starts
    from stable_worldmodel.cli.stats import SuccessSummary
    from stable_worldmodel.data import HDF5Dataset
    from stable_worldmodel.envs.pusht.physics import body_state
    from stable_worldmodel.envs.pusht.v1 import PushTV1
    from stable_worldmodel.train.data import split_episodes

    dataset = HDF5Dataset(args.dataset, preload=False)
    state = np.asarray(dataset.get_col_data("state"), np.float64)
    action = np.asarray(dataset.get_col_data("action"), np.float64)
    action = action[np.isfinite(action).all(axis=1)]
    act_mean, act_std = action.mean(0), action.std(0)
    state_std = state.std(0)
    offsets = np.concatenate([[0], np.cumsum(dataset.lengths)[:-1]])
    _, pool = split_episodes(len(dataset.lengths), *DEFAULT_SPLIT)
    eps, starts = dataset_starts(dataset, args.episodes, OFFSET, args.seed, [int(e) for e in pool])

    env = PushTV1(render_mode=None)

    def snapshot():
        a, b = env.agent, env.block
        return tuple(a.position), tuple(a.velocity), tuple(b.position), tuple(b.velocity), b.angle, b.angular_velocity

    def restore(s):
        a, b = env.agent, env.block
        a.position, a.velocity, b.position, b.velocity, b.angle, b.angular_velocity = s

    def simulate(actions: np.ndarray) -> np.ndarray:  # PushTV1.step's physics, without observations
        for ax, ay in actions * env.action_scale:
            px, py = env.agent.position
            env._drive(px + ax, py + ay)
        return body_state(env.agent, env.block)

    def cost(goal: np.ndarray, s: np.ndarray) -> float:
        d = goal - s
        d[4] = (d[4] + math.pi) % (2 * math.pi) - math.pi
        if args.cost == "zl2":
            return float(np.sum((d / state_std) ** 2))
        return float(np.linalg.norm(d[:4]) / 20 + abs(d[4]) / (math.pi / 9))

    def plan(goal: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        start = snapshot()
        mean, std = np.zeros((HORIZON * BLOCK, 2)), np.ones((HORIZON * BLOCK, 2))
        for _ in range(args.iterations):
            cand = mean + std * rng.standard_normal((args.samples, HORIZON * BLOCK, 2))
            costs = np.empty(args.samples)
            for i, normalized in enumerate(cand):
                restore(start)
                costs[i] = cost(goal, simulate(normalized * act_std + act_mean))
            elite = cand[np.argsort(costs)[: args.topk]]
            mean, std = elite.mean(0), elite.std(0)
        restore(start)
        return mean * act_std + act_mean

    successes, steps = [], []
    t0 = time.perf_counter()
    for k, (ep, st) in enumerate(zip(eps, starts, strict=True)):
        row = int(offsets[ep] + st)
        goal = state[row + OFFSET]
        env.reset(seed=k, options={"state": state[row], "goal_state": goal})
        rng = np.random.default_rng(args.seed + k)
        done, t = False, 0
        while t < BUDGET and not done:
            for a in plan(goal, rng):  # receding horizon 5: the whole plan runs
                _, _, done, _, _ = env.step(a.astype(np.float32))
                t += 1
                if done or t >= BUDGET:
                    break
        successes.append(bool(done))
        steps.append(t if done else -1)
        print(f"start {k} (episode {ep}, step {st}): {'success' if done else 'failure'} after {t} steps; "
              f"{sum(successes)}/{len(successes)}, {time.perf_counter() - t0:.0f} s", flush=True)  # fmt: skip
    summary = SuccessSummary.from_results(
        "oracle", {"episode_successes": np.asarray(successes), "episode_lengths": np.asarray(steps)}
    )
    lo, hi = (100 * v for v in summary.interval)
    print(
        f"CEM through the simulator ({args.cost} cost), {args.dataset}, {len(successes)} starts: "
        f"{100 * summary.rate:.0f}% [{lo:.1f}, {hi:.1f}] in {time.perf_counter() - t0:.0f} s"
    )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

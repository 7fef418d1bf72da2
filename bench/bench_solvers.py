"""Solver benchmark: ms per plan (CEM at the original defaults, MPPI, GD) and WorldModelPolicy env-steps/s.

    python bench/bench_solvers.py [--envs 1,4] [--repeats 5] [--device cpu] [--quick] [--act gelu] [--threads 2]

The cost model is a small MLP over (state (8,), flattened plan (H * A,)) -> 256 -> 256 -> 1
(``--act gelu`` is the shared harness's model; it runs with 2 torch threads: ``--threads 2``).
CEM and MPPI lines also give ``model`` (the same number of ``get_cost`` calls on one fixed
batch, outside any solver) and ``overhead`` (plan - model): what the solver itself costs.
``--big`` adds a ~15M-parameter MLP (the GPU latency figure of issue 6; use with --device cuda).
"""

from __future__ import annotations

import argparse
import time


def mlp_cost(in_dim: int, width: int, depth: int, device: str, act: str = "relu"):
    import torch

    activation = {"relu": torch.nn.ReLU, "gelu": torch.nn.GELU}[act]

    class MLPCost(torch.nn.Module):
        def __init__(self):
            super().__init__()
            layers, dim = [], in_dim
            for _ in range(depth):
                layers += [torch.nn.Linear(dim, width), activation()]
                dim = width
            self.net = torch.nn.Sequential(*layers, torch.nn.Linear(dim, 1))

        def get_cost(self, info, candidates):  # (B, S, H, A) -> (B, S)
            state = info["state"][:, :, -1]
            x = torch.cat([state, candidates.flatten(2)], dim=-1)
            return self.net(x).squeeze(-1)

    return MLPCost().to(device).eval()


def time_plan(solver, info, repeats: int, device: str) -> float:
    import torch

    solver.solve(info)  # warm-up
    times = []
    for _ in range(repeats):
        if device.startswith("cuda"):
            torch.cuda.synchronize()
        t0 = time.perf_counter()
        solver.solve(info)  # returns CPU tensors: includes the one device->host copy
        times.append(time.perf_counter() - t0)
    return sorted(times)[len(times) // 2]


def time_model(model, n: int, samples: int, steps: int, shape: tuple[int, int], repeats: int, device: str) -> float:
    """Median time of ``steps`` get_cost calls on one fixed (n, samples, H, A) batch: the model's share of a plan."""
    import torch

    candidates = torch.rand(n, samples, *shape, device=device) * 2 - 1
    info = {"state": torch.randn(n, 1, 1, 8, device=device).expand(n, samples, 1, 8)}

    def run():
        with torch.inference_mode():
            for _ in range(steps):
                model.get_cost(info, candidates)
        if device.startswith("cuda"):
            torch.cuda.synchronize()

    run()
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        run()
        times.append(time.perf_counter() - t0)
    return sorted(times)[len(times) // 2]


def bench_plans(args) -> None:
    import gymnasium as gym
    import numpy as np
    import torch

    from stable_worldmodel.policy import PlanConfig
    from stable_worldmodel.solver import CEMSolver, GradientSolver, MPPISolver

    horizon, block, adim = 5, 5, 2
    config = PlanConfig(horizon=horizon, receding_horizon=1, action_block=block)
    samples, steps = (100, 5) if args.quick else (300, 30)
    sizes = [(f"mlp 58-256-256-1 {args.act}", 256, 2)] + ([("mlp ~15M", 2730, 3)] if args.big else [])
    for label, width, depth in sizes:
        model = mlp_cost(8 + horizon * block * adim, width, depth, args.device, args.act)
        params = sum(p.numel() for p in model.parameters())
        for n in args.envs:
            space = gym.spaces.Box(-1, 1, (n, adim), np.float32)
            info = {"state": torch.randn(n, 1, 8)}
            solvers = {
                "cem": CEMSolver(
                    model, num_samples=samples, n_steps=steps, topk=30 if samples >= 300 else 10, device=args.device
                ),
                "mppi": MPPISolver(
                    model, num_samples=samples, n_steps=steps, topk=30 if samples >= 300 else 10, device=args.device
                ),
                "gd": GradientSolver(model, n_steps=steps, num_samples=32, device=args.device),
            }
            for name, solver in solvers.items():
                solver.configure(action_space=space, n_envs=n, config=config)
                ms = 1000 * time_plan(solver, info, args.repeats, args.device)
                split = ""
                if name != "gd":  # gd also backpropagates: a forward-only model time says little there
                    shape = (horizon, block * adim)
                    model_ms = 1000 * time_model(model, n, samples, steps, shape, args.repeats, args.device)
                    split = f"  (model {model_ms:.2f} ms, overhead {ms - model_ms:.2f} ms)"
                head = f"{name}_plan_ms  {label} ({params / 1e6:.2f}M)  n_envs={n}  samples={samples} iters={steps}"
                print(f"{head}  {ms:9.2f} ms{split}")


def bench_policy(args) -> None:
    from stable_worldmodel import World
    from stable_worldmodel.policy import PlanConfig, WorldModelPolicy
    from stable_worldmodel.solver import CEMSolver

    class PointCost:  # distance to goal of a point model of TwoRoom (speed 2)
        def get_cost(self, info, candidates):
            b, s = candidates.shape[:2]
            pos, goal = info["state"][:, :, -1, :2], info["goal_state"][:, :, -1, :2]
            final = pos + 2.0 * candidates.reshape(b, s, -1, 2).sum(dim=2)
            return (final - goal).norm(dim=-1)

    n, steps = 4, (20 if args.quick else 100)
    config = PlanConfig(horizon=5, receding_horizon=5, action_block=5)
    solver = CEMSolver(PointCost(), num_samples=300, n_steps=30, topk=30)
    with World("swm/TwoRoom-v2", num_envs=n, image_shape=(64, 64), max_episode_steps=1000, verbose=0) as world:
        world.set_policy(WorldModelPolicy(solver, config))
        world.reset(seed=0)
        world.step()
        t0 = time.perf_counter()
        for _ in range(steps):
            world.step()
        elapsed = time.perf_counter() - t0
    print(
        f"wm_policy_steps_per_s  TwoRoom 64x64 n_envs={n} CEM 300x30 H=5 block=5 rh=5  "
        f"{n * steps / elapsed:9.1f} env-steps/s"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--envs", default="1,4")
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--device", default="cpu")
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--big", action="store_true", help="also a ~15M-parameter cost model")
    parser.add_argument("--act", choices=("relu", "gelu"), default="relu", help="MLP activation (gelu: the harness)")
    parser.add_argument("--threads", type=int, default=None, help="torch.set_num_threads (default: torch's choice)")
    parser.add_argument("--no-policy", action="store_true")
    args = parser.parse_args()
    args.envs = [int(x) for x in args.envs.split(",")]
    if args.threads:
        import torch

        torch.set_num_threads(args.threads)
    bench_plans(args)
    if not args.no_policy:
        bench_policy(args)


if __name__ == "__main__":
    main()

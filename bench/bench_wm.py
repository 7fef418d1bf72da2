"""World-model benchmark: LeWM training samples/s and planning time per plan, ours vs upstream 0.1.1,
with the same weights.

    python bench/bench_wm.py [--peer ../peer011-venv/bin/python] [--model tiny-vit|tiny-vit-h3|paper] [--envs 1,10]
                             [--samples 300] [--iterations 30] [--horizon 5] [--repeats 3] [--threads 2]
                             [--device cpu|cuda] [--precision 32|bf16] [--compile]

One LeWM is built and saved by ours (``save_pretrained``: weights.pt + config.json); the peer
interpreter (upstream 0.1.1, built by ``../shared/bench/setup_peer011_venv.sh``) rebuilds the same
model from that config.json with upstream's own classes (``stable_worldmodel.wm.lewm``; the ViT
from ``transformers``, as ``stable_pretraining.backbone.utils.vit_hf`` does) and loads the same
weights with ``strict=True``. Then each side, in its own process, measures:

- ``cost``: ``get_cost`` of one fixed batch of candidates ``(B, S, H, A)``: the two sides must
  agree (``max |diff|`` is printed: "at equal results");
- ``model``: ``iterations`` calls of ``get_cost`` on fresh candidates (the solver's model time);
- ``plan``: one whole CEM plan (``samples`` x ``iterations``, horizon ``H`` blocks of
  ``frameskip`` actions) with each side's own ``CEMSolver``: context and goal encoded per plan;
  ours batches the envs, upstream plans env by env (``batch_size=1``, its default: its
  ``LeWM.get_cost`` cannot score more than one env per call);
- ``train``: samples/s of a LeWM training step (encode, predict, MSE + 0.09 SIGReg, backward,
  AdamW) on batches of ``history + 1`` frames.

Figures only; nothing is asserted. Both sides use ``--threads`` torch threads.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

HERE = Path(__file__).resolve().parent
DEFAULT_PEER = HERE.parent.parent / "peer011-venv" / "bin" / "python"

#: bench models: LeWM presets with a ViT encoder (upstream has no CNN encoder to rebuild ours)
MODELS = {
    "tiny-vit": (
        "tiny",
        {"encoder": "vit", "vit_size": "tiny", "patch_size": 8, "vit_overrides": {"num_hidden_layers": 2}},
    ),
    # the same with a history of 3 frames (the `cpu` and `paper` presets' history)
    "tiny-vit-h3": (
        "tiny",
        {
            "encoder": "vit",
            "vit_size": "tiny",
            "patch_size": 8,
            "vit_overrides": {"num_hidden_layers": 2},
            "history_size": 3,
        },
    ),
    "paper": ("paper", {}),
}

# What each side runs, in its own process: the same code, with the side's own classes.
# ``ours`` builds with stable_worldmodel.wm.utils.load_pretrained; ``peer`` with a small
# ``_target_`` resolver over upstream's modules (upstream needs hydra, not installed there).
CHILD = r"""
import contextlib, functools, importlib, json, statistics, sys, time
import numpy as np
import torch

args = json.loads(sys.argv[1])
torch.set_num_threads(args["threads"])
device = torch.device(args.get("device", "cpu"))
cuda = device.type == "cuda"


def sync():
    if cuda:
        torch.cuda.synchronize()
folder, side = args["folder"], args["side"]
config = json.load(open(folder + "/config.json"))
state = torch.load(folder + "/weights.pt", map_location="cpu", weights_only=True)


def vit_hf(size="tiny", patch_size=16, image_size=224, pretrained=False, use_mask_token=True, **overrides):
    import transformers
    sizes = {"tiny": (192, 12, 3), "small": (384, 12, 6), "base": (768, 12, 12)}
    hidden, layers, heads = sizes[size]
    params = dict(hidden_size=hidden, num_hidden_layers=layers, num_attention_heads=heads, intermediate_size=4 * hidden,
                  image_size=image_size, patch_size=patch_size)
    params.update(overrides)
    return transformers.ViTModel(
        transformers.ViTConfig(**params), add_pooling_layer=False, use_mask_token=use_mask_token
    )


def build(node):
    if isinstance(node, list):
        return [build(v) for v in node]
    if not isinstance(node, dict):
        return node
    kwargs = {k: build(v) for k, v in node.items() if k not in ("_target_", "_partial_")}
    if "_target_" not in node:
        return kwargs
    target = node["_target_"]
    if target.endswith(".vit_hf"):
        fn = vit_hf
    else:
        module, name = target.rsplit(".", 1)
        fn = getattr(importlib.import_module(module), name)
    return functools.partial(fn, **kwargs) if node.get("_partial_") else fn(**kwargs)


if side == "ours":
    from stable_worldmodel.wm.utils import load_pretrained
    model = load_pretrained(folder)
else:
    model = build(config)
    model.load_state_dict(state, strict=True)
model.to(device).eval()
import stable_worldmodel
out = {"side": side, "module": stable_worldmodel.__file__, "torch": torch.__version__,
       "parameters": sum(p.numel() for p in model.parameters())}
size, block, adim, hist = args["image_size"], args["frameskip"], args["action_dim"], args["history"]
h, s, iters = args["horizon"], args["samples"], args["iterations"]


def images(b, t, seed):
    g = torch.Generator().manual_seed(seed)
    return torch.randn(b, t, 3, size, size, generator=g).to(device)


def info_for(b, seed):
    return {"pixels": images(b, hist, seed), "goal": images(b, hist, seed + 1),
            "action": torch.zeros(b, hist, adim * block, device=device)}


def expand(info, s):  # what upstream's CEM hands get_cost: every entry (B, S, ...)
    return {k: v.unsqueeze(1).expand(v.shape[0], s, *v.shape[1:]) for k, v in info.items()}


def model_info(b, seed):
    info = info_for(b, seed)
    return expand(info, s) if side == "peer" else {k: info[k] for k in ("pixels", "goal")}


compiled = side == "ours" and args.get("compile")  # ours through torch.compile (the first call compiles)
get_cost = torch.compile(model.get_cost, dynamic=False) if compiled else model.get_cost

# 1. equal results: the cost of one fixed batch of candidates (one env: upstream's LeWM.get_cost
#    broadcasts its goal embedding wrongly for more than one env, so its CEM plans env by env)
g = torch.Generator().manual_seed(7)
cand = torch.randn(1, s, h, adim * block, generator=g).to(device)
with torch.inference_mode():
    out["cost"] = get_cost(model_info(1, 0), cand.clone()).cpu().tolist()


def median_time(fn, repeats):
    fn()
    sync()
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        sync()
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


# 2. model time: `iterations` get_cost calls on one plan's info (encode once, as a solver does)
out["model_ms"], out["plan_ms"] = {}, {}
for b in args["envs"]:
    cands = [torch.randn(b, s, h, adim * block, generator=g).to(device) for _ in range(iters)]

    def model_only():
        with torch.inference_mode():
            if side == "ours":  # all envs in one batch
                info = model_info(b, 1)
                for c in cands:
                    get_cost(info, c)
            else:  # env by env, as upstream's CEMSolver(batch_size=1) does
                for e in range(b):
                    info = model_info(1, 1 + e)
                    for c in cands:
                        model.get_cost(info, c[e : e + 1])

    out["model_ms"][b] = 1e3 * median_time(model_only, args["repeats"])

    # 3. one whole CEM plan with the side's own solver
    import gymnasium as gym
    box = gym.spaces.Box(-1.0, 1.0, (b, adim), dtype=np.float32)
    if side == "ours":
        from stable_worldmodel.policy import PlanConfig
        from stable_worldmodel.solver import make_solver
        solver = make_solver("cem", model, num_samples=s, n_steps=iters, topk=30, device=str(device), seed=0)
        if compiled:
            solver.compile_cost()
    else:
        from stable_worldmodel.policy import PlanConfig
        from stable_worldmodel.solver.cem import CEMSolver
        solver = CEMSolver(model, batch_size=1, num_samples=s, n_steps=iters, topk=30, device=str(device), seed=0)
    solver.configure(
        action_space=box,
        n_envs=b,
        config=PlanConfig(horizon=h, receding_horizon=h, history_len=hist, action_block=block),
    )
    plan_info = info_for(b, 2)

    def plan():
        return solver.solve({k: v.clone() for k, v in plan_info.items()})

    out["plan_ms"][b] = 1e3 * median_time(plan, args["repeats"])

# 4. training samples/s
if args["train_batch"]:
    from stable_worldmodel.wm.loss import SIGReg
    model.train()
    torch.manual_seed(0)
    bt, t = args["train_batch"], hist + 1
    batches = [(images(bt, t, 100 + i), torch.randn(bt, t, adim * block).to(device))
               for i in range(args["train_steps"] + 1)]
    # ours: the optimizer our Trainer builds (fused AdamW, CPU and CUDA); upstream: torch's default AdamW
    opt = torch.optim.AdamW(model.parameters(), lr=1e-4, fused=side == "ours")
    sigreg = SIGReg(num_proj=args["num_proj"]).to(device)
    autocast = (torch.autocast(device.type, dtype=torch.bfloat16) if args.get("precision") == "bf16"
                else contextlib.nullcontext())

    loss_of = (torch.compile(model.loss) if compiled else model.loss) if side == "ours" else None

    def step(batch):
        px, act = batch
        with autocast:
            if side == "ours":
                loss = loss_of({"pixels": px, "action": act})["loss"]
            else:
                info = model.encode({"pixels": px, "action": act})
                emb, act_emb = info["emb"], info["act_emb"]
                pred = model.predict(emb[:, :hist], act_emb[:, :hist])
                loss = (pred - emb[:, 1:1 + hist]).square().mean() + 0.09 * sigreg(emb.transpose(0, 1))
        opt.zero_grad(set_to_none=True)
        loss.backward()
        opt.step()

    step(batches[0])
    step(batches[0])
    sync()
    t0 = time.perf_counter()
    for batch in batches[1:]:
        step(batch)
    sync()
    out["train_samples_per_s"] = bt * args["train_steps"] / (time.perf_counter() - t0)
print("RESULT " + json.dumps(out))
"""


def run_side(python: str, side: str, params: dict) -> dict:
    env = {**os.environ, "PYTHONWARNINGS": "ignore", "OMP_WAIT_POLICY": os.environ.get("OMP_WAIT_POLICY", "PASSIVE")}
    cwd = HERE.parent if side == "ours" else tempfile.gettempdir()  # the peer must not import our checkout
    proc = subprocess.run(
        [python, "-c", CHILD, json.dumps({**params, "side": side})], cwd=cwd, env=env, capture_output=True, text=True
    )
    line = next((x for x in proc.stdout.splitlines() if x.startswith("RESULT ")), None)
    if proc.returncode != 0 or line is None:
        tail = (proc.stderr or proc.stdout).strip().splitlines()[-6:]
        print(f"{side} FAILED (rc {proc.returncode}):\n  " + "\n  ".join(tail))
        return {}
    return json.loads(line[len("RESULT ") :])


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--peer", default=str(DEFAULT_PEER), help="python of upstream 0.1.1 ('' to skip)")
    parser.add_argument("--model", choices=sorted(MODELS), default="tiny-vit")
    parser.add_argument("--envs", default="1,10", help="comma-separated env counts per plan")
    parser.add_argument("--samples", type=int, default=300)
    parser.add_argument("--iterations", type=int, default=30)
    parser.add_argument("--horizon", type=int, default=5)
    parser.add_argument("--frameskip", type=int, default=5)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--threads", type=int, default=2)
    parser.add_argument("--train-batch", type=int, default=64, help="0 skips the training figure")
    parser.add_argument("--train-steps", type=int, default=10)
    parser.add_argument("--device", default="cpu", help="cpu or cuda (both sides)")
    parser.add_argument("--precision", choices=("32", "bf16"), default="32", help="training autocast (both sides)")
    parser.add_argument(
        "--compile",
        action="store_true",
        help="ours through torch.compile: get_cost, the solver (compile_cost) and the training loss (the warm-up "
        "calls compile, they are not timed)",
    )
    args = parser.parse_args()

    sys.path.insert(0, str(HERE.parent))
    from stable_worldmodel import wm
    from stable_worldmodel.wm.utils import save_pretrained

    preset, overrides = MODELS[args.model]
    config = wm.get_config("lewm", preset, **overrides)
    action_dim = 2
    with tempfile.TemporaryDirectory() as cache:
        import torch

        torch.manual_seed(0)
        model = wm.make("lewm", preset, action_dim=action_dim, **overrides)
        folder = save_pretrained(model, "bench", config=config.target_tree(action_dim), cache_dir=cache).parent
        params = {
            "folder": str(folder),
            "threads": args.threads,
            "envs": [int(e) for e in args.envs.split(",")],
            "samples": args.samples,
            "iterations": args.iterations,
            "horizon": args.horizon,
            "frameskip": args.frameskip,
            "action_dim": action_dim,
            "image_size": config.image_size,
            "history": config.history_size,
            "repeats": args.repeats,
            "train_batch": args.train_batch,
            "train_steps": args.train_steps,
            "num_proj": getattr(config, "sigreg_num_proj", 1024),
            "device": args.device,
            "precision": args.precision,
            "compile": args.compile,
        }
        print(
            f"LeWM '{args.model}' ({config.image_size}px, embed {config.embed_dim}, predictor depth {config.depth}), "
            f"CEM {args.samples} x {args.iterations}, horizon {args.horizon} x frameskip {args.frameskip}, "
            f"{args.threads} threads, {args.device}, training precision {args.precision}"
            + (", ours through torch.compile" if args.compile else ""),
            flush=True,
        )
        ours = run_side(sys.executable, "ours", params)
        peer = run_side(args.peer, "peer", params) if args.peer and Path(args.peer).exists() else {}
        if args.peer and not Path(args.peer).exists():
            print(f"peer MISSING: {args.peer} (build it with bash ../shared/bench/setup_peer011_venv.sh)")
    if not ours:
        return 1
    print(f"ours: {ours['module']}" + (f"; upstream: {peer['module']}" if peer else ""))
    print(f"parameters {ours['parameters']:,}" + (f" (upstream {peer['parameters']:,})" if peer else ""))
    if peer:
        import numpy as np

        diff = np.abs(np.asarray(ours["cost"]) - np.asarray(peer["cost"])).max()
        scale = np.abs(np.asarray(peer["cost"])).max()
        print(f"equal results: max |cost ours - upstream| = {diff:.2e} (costs up to {scale:.2e})")
    print(f"{'figure':28s} {'ours':>10s} {'upstream':>10s} {'speedup':>8s}")

    def row(label: str, a: float | None, b: float | None, higher_better: bool = False) -> None:
        ratio = (a / b if higher_better else b / a) if a and b else None
        fa = f"{a:10.1f}" if a is not None else f"{'-':>10s}"
        fb = f"{b:10.1f}" if b is not None else f"{'-':>10s}"
        print(f"{label:28s} {fa} {fb} {f'{ratio:7.2f}x' if ratio else '':>8s}")

    for b in params["envs"]:
        key = str(b)
        row(f"model ms/plan, {b} env(s)", ours["model_ms"].get(key), peer.get("model_ms", {}).get(key))
        row(f"CEM plan ms, {b} env(s)", ours["plan_ms"].get(key), peer.get("plan_ms", {}).get(key))
    if args.train_batch:
        row(
            f"train samples/s (batch {args.train_batch})",
            ours.get("train_samples_per_s"),
            peer.get("train_samples_per_s"),
            True,
        )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

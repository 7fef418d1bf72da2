"""What a Push-T state-input run's latent distance weighs: the agent, the block, the block's angle, the velocity.

Usage: python bench/pusht_latent_geometry.py RUN [--dataset NAME] [--rows 500]

For ``rows`` states of the dataset, moves one part of the state by about the success tolerance of upstream's Push-T
(agent or block 14 px, the block 20 degrees; the velocity by 50 px/s; the agent by 100 px for scale) and prints the
median squared latent distance each move makes, the distance a planner minimizes. A run whose embedding ignores the
block (a 14-px move of it 100x smaller than the agent's) cannot plan to push it, however well it predicts.
Figures only; never asserts.
"""

from __future__ import annotations

import argparse

import numpy as np

MOVES = {
    "agent 14 px": [10, 10, 0, 0, 0, 0, 0],
    "block 14 px": [0, 0, 10, 10, 0, 0, 0],
    "block angle 20 deg": [0, 0, 0, 0, np.pi / 9, 0, 0],
    "agent velocity 50 px/s": [0, 0, 0, 0, 0, 35, 35],
    "agent 100 px": [70, 70, 0, 0, 0, 0, 0],
}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("run")
    parser.add_argument("--dataset", default=None, help="default: the run's training dataset")
    parser.add_argument("--rows", type=int, default=500)
    args = parser.parse_args()

    import torch

    from stable_worldmodel.data import HDF5Dataset
    from stable_worldmodel.wm.preprocess import Normalizer
    from stable_worldmodel.wm.run import Run

    run = Run.open(args.run)
    model = run.load_model().eval()
    protocol = run.protocol.to_dict()
    if getattr(model, "obs_key", "pixels") != "state":
        raise SystemExit(f"{args.run} does not read the state column (obs_key {model.obs_key!r})")
    normalizer = Normalizer.from_dict(protocol["normalizers"]["state"])
    dataset = HDF5Dataset(args.dataset or protocol["dataset"], preload=False)
    states = np.asarray(dataset.get_col_data("state"), np.float64)
    rows = states[np.random.default_rng(0).integers(0, len(states), args.rows)]

    def embed(x: np.ndarray) -> torch.Tensor:
        with torch.inference_mode():
            return model.encode_obs(torch.tensor(normalizer.transform(x), dtype=torch.float32))

    base = embed(rows)
    print(f"{args.run}: median squared latent distance of a move, over {len(rows)} states of {dataset.name}")
    for label, move in MOVES.items():
        dist = (embed(rows + np.asarray(move)) - base).square().sum(-1).numpy()
        print(f"  {label:24s} {np.median(dist):10.3f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

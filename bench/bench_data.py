"""Dataset benchmark: record_dataset rows/s and bytes/row, HDF5Dataset samples/s (num_steps=4).

python bench/bench_data.py [--env swm/PushT-v1] [--episodes 20] [--num-envs 4] [--size 64]
"""

from __future__ import annotations

import argparse
import os
import tempfile
import time
from pathlib import Path

import numpy as np


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--env", default="swm/PushT-v1")
    parser.add_argument("--episodes", type=int, default=20)
    parser.add_argument("--num-envs", type=int, default=4)
    parser.add_argument("--steps", type=int, default=50, help="max_episode_steps")
    parser.add_argument("--size", type=int, default=64)
    parser.add_argument("--samples", type=int, default=2000)
    args = parser.parse_args()

    import torch

    from stable_worldmodel import World
    from stable_worldmodel.data import HDF5Dataset
    from stable_worldmodel.policy import RandomPolicy

    tmp = Path(tempfile.mkdtemp())
    world = World(
        args.env, num_envs=args.num_envs, image_shape=(args.size, args.size), max_episode_steps=args.steps, verbose=0
    )
    world.set_policy(RandomPolicy(seed=0))
    t0 = time.perf_counter()
    path = world.record_dataset("bench", episodes=args.episodes, seed=0, cache_dir=tmp)
    elapsed = time.perf_counter() - t0
    ds = HDF5Dataset(path, num_steps=4)
    rows = ds.num_rows
    import h5py

    with h5py.File(path, "r") as f:
        payload = sum(f[k].id.get_storage_size() for k in f)
        raw = sum(f[k].size * f[k].dtype.itemsize for k in f)
    print(
        f"record_rows_per_s {rows / elapsed:.0f} rows/s ({rows} rows, {args.env}, {args.num_envs} envs, {args.size}px)"
    )
    print(
        f"file_bytes_per_row {os.path.getsize(path) / rows:.0f} "
        f"(payload {payload / rows:.0f}, uncompressed {raw / rows:.0f})"
    )

    rng = np.random.default_rng(0)
    idx = rng.integers(0, len(ds), args.samples)
    t0 = time.perf_counter()
    for i in idx:
        ds[int(i)]
    print(f"getitem_samples_per_s {args.samples / (time.perf_counter() - t0):.0f} (random order, all columns)")
    for workers in (0, 2):
        # a fresh dataset, 40 batches of 32 over as many epochs as it takes (workers start once per
        # epoch), start-up included: what a training loop sees
        rates = []
        for _ in range(3):
            t0 = time.perf_counter()
            fresh = HDF5Dataset(path, num_steps=4)
            built = time.perf_counter() - t0
            loader = torch.utils.data.DataLoader(fresh, batch_size=32, shuffle=True, num_workers=workers)
            t0 = time.perf_counter()
            n = batches = 0
            while batches < 40:
                for batch in loader:
                    n += len(batch["action"])
                    batches += 1
                    if batches == 40:
                        break
            rates.append(n / (time.perf_counter() - t0))
        print(
            f"dataloader_w{workers}_samples_per_s {np.median(rates):.0f} (batch 32, 40 batches, median of 3; "
            f"dataset construction {built * 1e3:.0f} ms not included)"
        )
    # what training reads from a dataset too big to keep in memory: random windows of 4 frames at
    # frameskip 5 (pixels + actions), read from the file (preload=False), batch 64
    lazy = HDF5Dataset(path, num_steps=4, frameskip=5, preload=False, keys_to_load=["pixels", "action"])
    batches = [rng.integers(0, len(lazy), 64) for _ in range(20)]
    t0 = time.perf_counter()
    for b in batches:
        lazy._batch(b)
    print(
        f"lazy_window_samples_per_s {64 * len(batches) / (time.perf_counter() - t0):.0f} "
        "(frameskip 5, 4 frames, pixels + action, from the file, random batches of 64)"
    )
    world.close()


if __name__ == "__main__":
    main()

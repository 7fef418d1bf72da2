"""Cost of the Fletcher-32 checksum on raw (uncompressed) chunks: HDF5Writer and HDF5Dataset rows/s
with and without it (``stable_worldmodel.data.writer.CHECKSUM_RAW``).

    python bench/bench_checksum.py [--episodes 200] [--length 50] [--per-commit 4] [--repeats 5] [--kinds numeric,pixels]

Two recordings: ``numeric`` (only small raw columns: the worst case for the checksum) and
``pixels`` (the same plus a 64x64 RGB image column, gzip-compressed and not checksummed by
Fletcher-32). Reads: construction with ``preload=True`` (every column decoded), and
``preload=False`` random items (``num_steps=4``) through the block cache, and a whole-column read.
Each figure is the best of ``--repeats`` interleaved runs. Prints, never asserts.
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

import numpy as np


def episode(ep: int, length: int, pixels: bool) -> dict[str, np.ndarray]:
    rng = np.random.default_rng(ep)
    out = {
        "action": rng.standard_normal((length, 2)).astype(np.float32),
        "state": rng.standard_normal((length, 10)),
        "proprio": rng.standard_normal((length, 4)).astype(np.float32),
        "reward": rng.standard_normal(length).astype(np.float32),
        "step_idx": np.arange(length, dtype=np.int64),
        "terminated": np.arange(length) == length - 1,
    }
    if pixels:
        img = np.zeros((length, 64, 64, 3), np.uint8)
        img[:, 16:48, 16:48] = rng.integers(0, 255, (length, 1, 1, 3), dtype=np.uint8)
        out["pixels"] = img
    return out


def write(path: Path, episodes: list[dict], per_commit: int, checksum: bool) -> float:
    from stable_worldmodel.data import writer

    writer.CHECKSUM_RAW = checksum
    t0 = time.perf_counter()
    with writer.HDF5Writer(path) as w:
        for i in range(0, len(episodes), per_commit):
            w.write_episodes(episodes[i : i + per_commit])
    return time.perf_counter() - t0


def read_preload(path: Path) -> float:
    from stable_worldmodel.data import HDF5Dataset

    t0 = time.perf_counter()
    HDF5Dataset(path=path, preload=True).close()
    return time.perf_counter() - t0


def read_items(path: Path, n: int) -> float:
    from stable_worldmodel.data import HDF5Dataset

    ds = HDF5Dataset(path=path, preload=False, num_steps=4)
    idx = np.random.default_rng(0).integers(0, len(ds), n)
    t0 = time.perf_counter()
    for i in idx:
        ds[int(i)]
    elapsed = time.perf_counter() - t0
    ds.close()
    return elapsed


def read_column(path: Path, col: str) -> float:
    from stable_worldmodel.data import HDF5Dataset

    ds = HDF5Dataset(path=path, preload=False)
    t0 = time.perf_counter()
    ds.get_col_data(col)
    elapsed = time.perf_counter() - t0
    ds.close()
    return elapsed


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--episodes", type=int, default=200)
    parser.add_argument("--length", type=int, default=50)
    parser.add_argument("--per-commit", type=int, default=4, help="episodes per write_episodes call (one per env)")
    parser.add_argument("--items", type=int, default=3000)
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--kinds", default="numeric,pixels", help="recordings to run, comma-separated")
    args = parser.parse_args()

    rows = args.episodes * args.length
    tmp = Path(tempfile.mkdtemp())
    print(f"{args.episodes} episodes x {args.length} rows = {rows} rows, {args.per_commit} episodes per commit; best of {args.repeats}")
    for kind in args.kinds.split(","):
        episodes = [episode(e, args.length, kind == "pixels") for e in range(args.episodes)]
        best: dict[tuple[str, bool], float] = {}
        for r in range(args.repeats):
            for checksum in (False, True) if r % 2 == 0 else (True, False):  # interleaved: drift hits both
                path = tmp / f"{kind}_{checksum}_{r}.h5"
                times = {
                    "write": write(path, episodes, args.per_commit, checksum),
                    "read_preload": read_preload(path),
                    "read_column": read_column(path, "state"),
                    "read_items": read_items(path, args.items),
                }
                for what, t in times.items():
                    best[what, checksum] = min(best.get((what, checksum), float("inf")), t)
                path.unlink()
        print(f"\n[{kind}]")
        for what, unit, n in (
            ("write", "rows/s", rows),
            ("read_preload", "rows/s", rows),
            ("read_column", "rows/s", rows),
            ("read_items", "items/s", args.items),
        ):
            off, on = n / best[what, False], n / best[what, True]
            print(f"{what:13s} without {off:12,.0f} {unit:8s} with {on:12,.0f} {unit:8s} cost {100 * (1 - on / off):+5.1f}%")


if __name__ == "__main__":
    main()

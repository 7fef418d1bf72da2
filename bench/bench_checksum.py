"""Cost of the per-row checksums of raw columns (``stable_worldmodel/data/_rowsum.py``): HDF5Writer and
HDF5Dataset speed with ``HDF5Writer(path, checksum=True)`` (the default) and ``checksum=False``.

    python bench/bench_checksum.py [--episodes 1000] [--length 50] [--per-commit 4] [--repeats 7]
                                   [--kinds numeric,pixels]

Two recordings: ``numeric`` (only small raw columns: the worst case, every byte is checksummed)
and ``pixels`` (the same plus a 64x64 RGB image column, gzip-compressed, which has no row checksum).
Figures (each the best of ``--repeats`` interleaved runs, ``--reads`` times more for the short reads):

* ``write``: recording the file (``--per-commit`` episodes per commit);
* ``read_preload``: ``HDF5Dataset(preload=True)``: every column read and checked at construction;
* ``read_column``: one whole raw column (``state``) by a fresh reader: every row checked (a cold read);
* ``read_column_again``: the same column by the same reader (uncached): checked already, free;
* ``read_items``: random items (``num_steps=4``, ``preload=False``) through the block cache, from a
  fresh reader: each block is checked on its first read;
* ``hash_only``: ``row_checksums`` over the raw columns' rows in memory (the checking's own cost).

``--e2e`` adds the work users run, where the cost shows (or not) end to end:

* ``record``: ``World("swm/PushT-v1", num_envs=4, image_shape=(64, 64)).record_dataset`` (the random
  policy, ``--e2e-episodes`` episodes of 50 steps);
* ``train_epoch``: one pass of a ``torch.utils.data.DataLoader`` (batch 32, no workers) over
  ``HDF5Dataset(num_steps=4)`` of that recording, every item read (pixels, action, proprio, state).

``time`` is the extra time the checksums take (+5% = 5% slower). The file size with and without
checksums is printed too. Prints, never asserts.
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
    from stable_worldmodel.data.writer import HDF5Writer

    t0 = time.perf_counter()
    with HDF5Writer(path, checksum=checksum) as w:
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


def read_column(path: Path, col: str) -> tuple[float, float]:
    """A whole column by a fresh reader, then again by the same reader."""
    from stable_worldmodel.data import HDF5Dataset

    ds = HDF5Dataset(path=path, preload=False)
    ds.get_col_data("reward")  # the file handle is open and warm: only the column read is timed
    times = []
    for _ in range(2):
        t0 = time.perf_counter()
        ds.get_col_data(col)
        times.append(time.perf_counter() - t0)
    ds.close()
    return times[0], times[1]


def hash_only(episodes: list[dict]) -> float:
    from stable_worldmodel.data._rowsum import row_checksums
    from stable_worldmodel.data.writer import COMPRESS_ROW_BYTES

    columns = [np.concatenate([ep[c] for ep in episodes]) for c in episodes[0]]
    raw = [c for c in columns if c[0].nbytes < COMPRESS_ROW_BYTES]
    t0 = time.perf_counter()
    for c in raw:
        row_checksums(c, 0)
    return time.perf_counter() - t0


def record_world(path: Path, episodes: int, checksum: bool) -> float:
    """``World.record_dataset`` on PushT-v1 with ``HDF5Writer(checksum=checksum)``."""
    import stable_worldmodel as swm
    from stable_worldmodel.data import writer

    world = swm.World("swm/PushT-v1", num_envs=4, image_shape=(64, 64), max_episode_steps=50, verbose=0)
    world.set_policy(swm.policy.RandomPolicy(seed=0))
    real = writer.HDF5Writer
    writer.HDF5Writer = lambda p, **kw: real(p, checksum=checksum, **kw)  # what record_dataset imports
    try:
        t0 = time.perf_counter()
        world.record_dataset(path.stem, episodes=episodes, seed=0, cache_dir=path.parent)
        return time.perf_counter() - t0
    finally:
        writer.HDF5Writer = real
        world.close()


def train_epoch(path: Path) -> float:
    """One DataLoader pass over every item of the recording (batch 32, no workers)."""
    import torch

    from stable_worldmodel.data import HDF5Dataset

    ds = HDF5Dataset(path=path, preload=False, num_steps=4, keys_to_load=["pixels", "action", "proprio", "state"])
    t0 = time.perf_counter()
    for _ in torch.utils.data.DataLoader(ds, batch_size=32, shuffle=True, generator=torch.Generator().manual_seed(0)):
        pass
    elapsed = time.perf_counter() - t0
    ds.close()
    return elapsed


def end_to_end(tmp: Path, episodes: int, repeats: int) -> None:
    best: dict[tuple[str, bool], float] = {}
    for r in range(repeats):
        order = (False, True) if r % 2 == 0 else (True, False)
        for checksum in order:
            path = tmp / f"e2e_{checksum}_{r}.h5"
            record(best, "record", checksum, record_world(path, episodes, checksum))
        for _ in range(5):  # an epoch is short: several per file, alternating
            for checksum in order:
                record(best, "train_epoch", checksum, train_epoch(tmp / f"e2e_{checksum}_{r}.h5"))
        for checksum in order:
            (tmp / f"e2e_{checksum}_{r}.h5").unlink()
    print(f"\n[end to end]  swm/PushT-v1 64x64, {episodes} episodes of 50 steps, best of {repeats}")
    rec_off, rec_on = episodes / best["record", False], episodes / best["record", True]
    extra = 100 * (best["record", True] / best["record", False] - 1)
    print(f"{'record':18s} without {rec_off:10.1f} ep/s     with {rec_on:10.1f} ep/s     time {extra:+6.1f}%")
    off, on = best["train_epoch", False], best["train_epoch", True]
    print(
        f"{'train_epoch':18s} without {off:10.2f} s        with {on:10.2f} s        time {100 * (on / off - 1):+6.1f}%"
    )


def record(best: dict, what: str, checksum: bool, seconds: float) -> None:
    best[what, checksum] = min(best.get((what, checksum), float("inf")), seconds)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--episodes", type=int, default=1000)
    parser.add_argument("--length", type=int, default=50)
    parser.add_argument("--per-commit", type=int, default=4, help="episodes per write_episodes call (one per env)")
    parser.add_argument("--items", type=int, default=3000)
    parser.add_argument("--repeats", type=int, default=7)
    parser.add_argument("--reads", type=int, default=5, help="of each short read per file and repeat")
    parser.add_argument("--kinds", default="numeric,pixels", help="recordings to run, comma-separated")
    parser.add_argument("--e2e", action="store_true", help="also time recording PushT-v1 and a training epoch")
    parser.add_argument("--e2e-episodes", type=int, default=40)
    args = parser.parse_args()

    rows = args.episodes * args.length
    tmp = Path(tempfile.mkdtemp())
    print(
        f"{args.episodes} episodes x {args.length} rows = {rows} rows, {args.per_commit} episodes per commit; "
        f"best of {args.repeats}"
    )
    for kind in args.kinds.split(","):
        episodes = [episode(e, args.length, kind == "pixels") for e in range(args.episodes)]
        best: dict[tuple[str, bool], float] = {}
        sizes: dict[bool, int] = {}
        for r in range(args.repeats):
            order = (False, True) if r % 2 == 0 else (True, False)  # interleaved: drift hits both
            paths = {checksum: tmp / f"{kind}_{checksum}_{r}.h5" for checksum in order}
            for checksum in order:
                record(best, "write", checksum, write(paths[checksum], episodes, args.per_commit, checksum))
                sizes[checksum] = paths[checksum].stat().st_size
            for _ in range(args.reads):  # the reads are short: several of each per file, alternating
                for checksum in order:
                    record(best, "read_preload", checksum, read_preload(paths[checksum]))
                    cold, again = read_column(paths[checksum], "state")
                    record(best, "read_column", checksum, cold)
                    record(best, "read_column_again", checksum, again)
            for checksum in order:
                record(best, "read_items", checksum, read_items(paths[checksum], args.items))
                paths[checksum].unlink()
        hashed = min(hash_only(episodes) for _ in range(args.repeats))
        grown = 100 * (sizes[True] / sizes[False] - 1)
        mb = {k: v / 1e6 for k, v in sizes.items()}
        print(f"\n[{kind}]  file {mb[False]:.2f} MB without, {mb[True]:.2f} MB with checksums ({grown:+.1f}%)")
        for what, unit, n in (
            ("write", "rows/s", rows),
            ("read_preload", "rows/s", rows),
            ("read_column", "rows/s", rows),
            ("read_column_again", "rows/s", rows),
            ("read_items", "items/s", args.items),
        ):
            off, on = n / best[what, False], n / best[what, True]
            extra = 100 * (off / on - 1)
            print(f"{what:18s} without {off:12,.0f} {unit:8s} with {on:12,.0f} {unit:8s} time {extra:+6.1f}%")
        print(f"{'hash_only':18s} {rows / hashed:12,.0f} rows/s (every raw column of a row)")
    if args.e2e:
        end_to_end(tmp, args.e2e_episodes, max(3, args.repeats // 2))


if __name__ == "__main__":
    main()

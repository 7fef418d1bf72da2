"""Frozen-encoder feature cache: the encoder time of a first PreJEPA run (features computed)
versus a second run with the same encoder (features loaded), on a recorded dataset.

Usage: python bench/bench_feature_cache.py [--dataset NAME] [--backbone cnn|dinov2_small ...] [--image-size S]
Trains 1 step twice (the training itself is not what is measured) in a scratch cache copy; prints, never asserts.
"""

from __future__ import annotations

import argparse
import os
import shutil
import tempfile
import time
from pathlib import Path


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--dataset", default="tr1", help="a dataset of $STABLEWM_HOME (record one with swm collect)")
    parser.add_argument("--backbone", default="cnn")
    parser.add_argument("--image-size", type=int, default=64)
    args = parser.parse_args()

    from stable_worldmodel.data.utils import get_cache_dir, resolve_dataset_path

    source = resolve_dataset_path(args.dataset)
    with tempfile.TemporaryDirectory() as scratch:
        shutil.copy(source, Path(scratch) / source.name)  # the cache goes beside this copy
        os.environ["STABLEWM_HOME"] = scratch
        assert get_cache_dir() == Path(scratch)
        from stable_worldmodel.train import train

        overrides = {
            "backbone": args.backbone,
            "pretrained": False,
            "image_size": args.image_size,
            "progress": False,
            "steps": 1,
            "val_every": 0,
            "device": "cpu",
            "seed": 0,
        }
        runs = []
        for name in ("first", "second"):
            start = time.perf_counter()
            result = train("prejepa", source.stem, "tiny", name=name, **overrides)
            runs.append((result.features, time.perf_counter() - start))
        (first, t1), (second, t2) = runs
        frames = len(first.features)
        print(
            f"PreJEPA tiny, backbone {args.backbone} at {args.image_size}px, dataset {args.dataset} ({frames} frames)"
        )
        print(f"first run : features computed in {first.seconds:8.3f} s (whole run {t1:.1f} s)")
        print(f"second run: features loaded   in {second.seconds:8.3f} s (whole run {t2:.1f} s)")
        print(f"encoder time of the second run: {second.seconds / first.seconds:.4f} of the first's")


if __name__ == "__main__":
    main()

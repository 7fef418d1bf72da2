"""Side-by-side table (markdown) of two reports of the shared harness (../shared/bench/swm_bench.py).

Usage: python bench/compare.py bench/results/peer_full.json bench/results/ours_full.json
Reports made with ``swm_bench.py --aggregate`` (several runs) are read too: their medians are compared.
A ratio > 1 always means "ours is better" (faster, or smaller for sizes and times).
"""

from __future__ import annotations

import argparse
import json

LOWER_IS_BETTER_UNITS = {"s", "bytes/row", "bytes/frame", "MB"}


def load(path: str) -> dict:
    """``{metric: {"status", "value", "unit"}}`` of one report, or of the medians of an aggregate."""
    metrics = json.load(open(path))["metrics"]
    for metric in metrics.values():
        if "median" in metric and "status" not in metric:
            metric.update(status="ok", value=metric["median"])
    return metrics


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("original")
    parser.add_argument("ours")
    parser.add_argument("--all", action="store_true", help="include peak-memory rows")
    args = parser.parse_args()
    a, b = load(args.original), load(args.ours)
    print("| metric | original 0.0.3 | ours | ratio |")
    print("| --- | ---: | ---: | ---: |")
    for name, ours in b.items():
        if name.startswith("peak_rss") and not args.all:
            continue
        orig = a.get(name, {})
        unit = ours.get("unit", "")
        if ours.get("status") != "ok" or orig.get("status") != "ok":
            why = "missing" if orig.get("status") != "ok" else "n/a"
            shown = f"{ours['value']:.4g} {unit}" if ours.get("status") == "ok" else "missing"
            print(f"| `{name}` | {why} | {shown} | |")
            continue
        x, y = orig["value"], ours["value"]
        ratio = x / y if unit in LOWER_IS_BETTER_UNITS else y / x
        print(f"| `{name}` | {x:.4g} {unit} | {y:.4g} {unit} | {ratio:.1f}x |")


if __name__ == "__main__":
    main()

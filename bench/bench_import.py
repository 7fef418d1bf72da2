"""Import-time benchmark for ``import stable_worldmodel`` (prints figures, asserts nothing).

Usage: ``python bench/bench_import.py [--runs N] [--top K] [--module NAME]``

Each run is a fresh interpreter; the figure is ``time.perf_counter()`` around the import
(interpreter start-up excluded). Then ``-X importtime`` lists the slowest modules (cumulative).
"""

from __future__ import annotations

import argparse
import statistics
import subprocess
import sys

PROBE = "import time; t = time.perf_counter(); import {m}; print(time.perf_counter() - t)"


def time_import(module: str, runs: int) -> list[float]:
    """Seconds for ``import module`` in ``runs`` fresh interpreters."""
    code = PROBE.format(m=module)
    return [
        float(subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout)
        for _ in range(runs)
    ]


def top_imports(module: str, k: int) -> list[tuple[int, int, str]]:
    """The ``k`` largest (cumulative us, self us, name) rows of ``-X importtime``."""
    err = subprocess.run(
        [sys.executable, "-X", "importtime", "-c", f"import {module}"], capture_output=True, text=True, check=True
    ).stderr
    rows = []
    for line in err.splitlines():
        if not line.startswith("import time:") or "self [us]" in line:
            continue
        self_us, cum_us, name = (part.strip() for part in line[len("import time:") :].split("|"))
        rows.append((int(cum_us), int(self_us), name))
    return sorted(rows, reverse=True)[:k]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=7)
    parser.add_argument("--top", type=int, default=15)
    parser.add_argument("--module", default="stable_worldmodel")
    ns = parser.parse_args()

    times = time_import(ns.module, ns.runs)
    print(
        f"import {ns.module}: median {statistics.median(times) * 1000:.1f} ms, "
        f"min {min(times) * 1000:.1f} ms, max {max(times) * 1000:.1f} ms over {ns.runs} runs"
    )
    heavy = subprocess.run(
        [
            sys.executable,
            "-c",
            f"import sys, {ns.module}; "
            "print(sorted(m for m in ('torch','h5py','cv2','mujoco','matplotlib','imageio') if m in sys.modules))",
        ],
        capture_output=True,
        text=True,
        check=True,
    ).stdout.strip()
    print(f"heavy modules loaded: {heavy}")
    print(f"\n{'cumulative ms':>14} {'self ms':>8}  module")
    for cum, own, name in top_imports(ns.module, ns.top):
        print(f"{cum / 1000:14.1f} {own / 1000:8.1f}  {name}")


if __name__ == "__main__":
    main()

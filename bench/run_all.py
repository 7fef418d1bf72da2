"""Run every benchmark of bench/ one after another (``make bench``); figures only, no assertions.

Usage: python bench/run_all.py [--quick]
For the side-by-side comparison with the original release, see the README (../shared/bench harness).
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

HERE = Path(__file__).parent
SCRIPTS = [
    ("bench_import.py", []),
    ("bench_world.py", ["--quick"]),
    ("bench_data.py", []),
    ("bench_solvers.py", []),
    ("bench_expert_success.py", []),
    ("bench_wm.py", []),  # ours vs upstream 0.1.1 when ../peer011-venv exists
    ("bench_compile.py", ["--envs", "1", "--rounds", "3"]),  # torch.compile against eager
    ("bench_presets.py", ["--presets", "tiny,small", "--steps", "3"]),
    ("bench_ray.py", []),
    ("bench_mujoco.py", []),  # ours vs upstream 0.1.1 when ../peer011-venv exists
]


def main() -> int:
    failed = []
    for name, args in SCRIPTS:
        path = HERE / name
        if not path.exists():
            continue
        print(f"\n=== {name} {' '.join(args)}", flush=True)
        if subprocess.run([sys.executable, str(path), *args]).returncode != 0:
            failed.append(name)
    if failed:
        print(f"\nfailed: {', '.join(failed)}")
    return 1 if failed else 0


if __name__ == "__main__":
    raise SystemExit(main())

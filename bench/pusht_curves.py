"""Success rate against training time, from ``swm eval --json`` records of runs and of their snapshots.

Usage: python bench/pusht_curves.py [EVAL.json ...] [--run RUN ...] [--out curves.png] [--line LABEL=PERCENT ...]
                                    [--label RUN=TEXT ...]

Each record's policy is ``wm:RUN`` (the run's last checkpoint) or ``wm:RUN/step_N`` (a snapshot ``swm train``
keeps every quarter of a run); records of other policies (``random``, ``expert``) become horizontal lines, as do
``--line`` values (e.g. the ceiling ``bench/bench_pusht_oracle.py`` prints). The training time of a checkpoint is its
step over the run's steps times the run's training time (``protocol.json``'s provenance: start to end): the runs
train at a steady pace. ``--run RUN`` adds the evaluations a run made as it trained (``swm train --eval-every K
--eval-protocol upstream``: ``eval/success_rate`` at ``eval/train_seconds`` in its ``metrics.jsonl``; its
``loss.png`` shows them too).

Snapshots of one long run are taken at a learning rate its cosine schedule has not yet lowered: a run planned for
that shorter time ends annealed, so the curve of snapshots is a lower bound of what such a run reaches.

Prints a markdown table (run, step, minutes, success with its 95% interval) and writes the plot. Never asserts.
All records must share their starts (``episodes_idx`` / ``start_steps``): the script says when they do not.
"""

from __future__ import annotations

import argparse
import datetime
import json
import re
from pathlib import Path


def _run_folder(run: str) -> Path:
    from stable_worldmodel.wm.utils import checkpoint_root

    return checkpoint_root() / run


def _run_seconds(run: str) -> tuple[int, float]:
    """Planned steps and training seconds (provenance start to end) of checkpoint run ``run``."""
    protocol = json.loads((_run_folder(run) / "protocol.json").read_text())
    prov = protocol["provenance"]
    start, end = (datetime.datetime.fromisoformat(prov[k]) for k in ("started", "ended"))
    return int(protocol["steps"]), (end - start).total_seconds()


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("records", nargs="*", type=Path)
    parser.add_argument("--run", action="append", default=[], help="a run evaluated as it trained")
    parser.add_argument("--out", type=Path, default=Path("curves.png"))
    parser.add_argument("--line", action="append", default=[], metavar="LABEL=PERCENT")
    parser.add_argument("--label", action="append", default=[], metavar="RUN=TEXT", help="legend text of a run")
    parser.add_argument("--title", default="success rate against training time")
    args = parser.parse_args()

    series: dict[str, list[tuple[float, int, float, float, float]]] = {}
    lines = [(label, float(value)) for label, value in (item.rsplit("=", 1) for item in args.line)]
    names = dict(item.split("=", 1) for item in args.label)
    starts = set()
    for path in args.records:
        record = json.loads(path.read_text())
        starts.add(json.dumps([record.get("episodes_idx"), record.get("start_steps")]))
        policy, rate, (low, high) = record["policy"], record["success_rate"], record["ci95"]
        match = re.fullmatch(r"wm:([^/]+)(?:/step_(\d+))?", policy)
        if match is None:
            lines.append((policy, rate))
            continue
        run = match[1]
        steps, seconds = _run_seconds(run)
        step = int(match[2]) if match[2] else steps
        series.setdefault(run, []).append((seconds * step / steps / 60, step, rate, low, high))
    for run in args.run:
        metrics = _run_folder(run) / "metrics.jsonl"
        for line in metrics.read_text().splitlines():
            r = json.loads(line)
            if "eval/success_rate" in r and "eval/train_seconds" in r:
                point = (r["eval/train_seconds"] / 60, r["step"], r["eval/success_rate"])
                series.setdefault(run, []).append((*point, r["eval/ci95_low"], r["eval/ci95_high"]))
    if len(starts) > 1:
        print(f"warning: the records start from {len(starts)} different sets of starts")

    print("| run | step | training (min) | success (95% CI) |\n| --- | ---: | ---: | ---: |")
    for run, points in series.items():
        for minutes, step, rate, low, high in sorted(points):
            print(f"| {run} | {step} | {minutes:.0f} | {rate:.0f}% [{low:.1f}, {high:.1f}] |")
    for label, value in lines:
        print(f"| {label} | | | {value:.0f}% |")

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 4.2), dpi=120)
    for run, points in series.items():
        points = sorted(points)
        x = [p[0] for p in points]
        y = [p[2] for p in points]
        err = [[p[2] - p[3] for p in points], [p[4] - p[2] for p in points]]
        ax.errorbar(x, y, yerr=err, fmt="o-", capsize=3, label=names.get(run, run))
    for label, value in lines:
        ax.axhline(value, linestyle="--", linewidth=0.8, color="grey")
        ax.annotate(f"{label} {value:.0f}%", (0, value), xytext=(2, 2), textcoords="offset points", fontsize=7)
    ax.set_xlim(left=0)
    ax.set_ylim(-2, 102)
    ax.set_xlabel("training time (minutes)")
    ax.set_ylabel("success rate (%)")
    ax.set_title(args.title, fontsize=9)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=6.5, loc="lower right")
    fig.tight_layout()
    fig.savefig(args.out)
    plt.close(fig)
    print(f"plot: {args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

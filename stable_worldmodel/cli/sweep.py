"""The generalization report: success in distribution and with each factor of variation shifted.

``swm eval ENV --policy P[,P2...] --fov-sweep all|F1,F2`` evaluates every policy on the same
seeds (1) in distribution — every factor at the value the env resets to by default, which is
what a dataset recorded without ``--variation`` contains — (2) with each factor (or factor group)
resampled from its whole space every episode, and (3) with all of them resampled together. It
prints one table (success and 95% interval per setting and policy, and the drop versus in
distribution), writes a heatmap PNG with the policies side by side, and a JSON with the protocol.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

from rich.table import Table

from .stats import SuccessSummary

IN_DISTRIBUTION = "in distribution"
ALL_FACTORS = "all factors"


def sweep_settings(env: str, factors: str) -> list[tuple[str, list[str]]]:
    """The ``(label, variation)`` settings of a sweep: in distribution, each factor, then all.

    ``factors`` is ``"all"`` (every top-level factor group of the env) or comma-separated factor
    or group names (checked, with "did you mean").
    """
    from ..errors import ConfigError
    from ..planning.policies import variation_space_of

    space = variation_space_of(env)
    if space is None or not space.names():
        raise ConfigError(f"--fov-sweep requires an env with factors of variation, got {env!r}, which has none")
    names, groups = factor_names(space)
    if factors.strip() == "all":
        chosen = groups or names
    else:
        chosen = [f.strip() for f in factors.split(",") if f.strip()]
        if not chosen:
            raise ConfigError(f"--fov-sweep requires 'all' or comma-separated factor names, got {factors!r}")
        check_factor_names(env, space, chosen)
    return [(IN_DISTRIBUTION, []), *((name, [name]) for name in chosen), (ALL_FACTORS, ["all"])]


def factor_names(space: Any) -> tuple[list[str], list[str]]:
    """The factor names of a variation space and its top-level group names (those that are not factors)."""
    names = list(space.names()) if space is not None else []
    return names, [g for g in getattr(space, "spaces", {}) if g not in names]


def check_factor_names(env: str, space: Any, chosen: Sequence[str], extra: Sequence[str] = ()) -> None:
    """Each of ``chosen`` is ``all``, a factor or a group of ``space``; else "did you mean"."""
    from ..errors import unknown_name

    names, groups = factor_names(space)
    for name in chosen:
        if name != "all" and name not in names and not any(n.startswith(name + ".") for n in names):
            raise unknown_name(f"factor of variation of {env}", name, [*extra, "all", *groups, *names])


def run_sweep(env: str, policies: Sequence[str], factors: str, *, evaluate: Any, **kwargs: Any) -> dict[str, Any]:
    """Evaluate each policy in each setting of :func:`sweep_settings` on the same seeds.

    ``evaluate(env, policy, variation=..., **kwargs)`` is one evaluation returning
    ``(summary, title, record)`` (:func:`~stable_worldmodel.cli.evaluation.evaluate_cli`). The
    returned report holds the settings, the policies and, per policy, a row per setting.
    """
    settings = sweep_settings(env, factors)
    report: dict[str, Any] = {
        "env": env,
        "policies": list(policies),
        "settings": [s for s, _ in settings],
        "results": {},
    }
    for policy in policies:
        rows = []
        for label, variation in settings:
            summary, _, record = evaluate(env, policy, variation=variation, **kwargs)
            rows.append({"setting": label, "variation": variation, "summary": summary, "record": record})
        report["results"][policy] = rows
    return report


def sweep_table(report: dict[str, Any]) -> Table:
    """Rows: settings; columns: policies; cells: success rate, 95% interval and drop."""
    table = Table(title=f"{report['env']}: success when factors of variation shift (same seeds)")
    table.add_column("setting", style="bold")
    for policy in report["policies"]:
        table.add_column(policy, justify="right")
    base = {p: rows[0]["summary"].rate for p, rows in report["results"].items()}
    for i, setting in enumerate(report["settings"]):
        cells = []
        for policy in report["policies"]:
            s: SuccessSummary = report["results"][policy][i]["summary"]
            low, high = s.interval
            drop = "" if i == 0 else f" ({100 * (s.rate - base[policy]):+.0f})"
            cells.append(f"{100 * s.rate:.0f}% [{100 * low:.0f}, {100 * high:.0f}]{drop}")
        table.add_row(setting, *cells)
    return table


def sweep_json(report: dict[str, Any], protocol: dict[str, Any]) -> dict[str, Any]:
    """The report as JSON: per policy and setting the success rate, its interval, the drop
    versus in distribution and the episode outcomes, plus the shared protocol."""
    out: dict[str, Any] = {"env": report["env"], "protocol": protocol, "settings": report["settings"], "results": {}}
    for policy, rows in report["results"].items():
        base = rows[0]["summary"].rate
        out["results"][policy] = [
            {
                "setting": r["setting"],
                "variation": r["variation"],
                "success_rate": round(100 * r["summary"].rate, 2),
                "ci95": [round(100 * v, 2) for v in r["summary"].interval],
                "drop": round(100 * (r["summary"].rate - base), 2),
                "episode_successes": r["record"].get("episode_successes"),
            }
            for r in rows
        ]
    return out


def sweep_heatmap(report: dict[str, Any], path: Path) -> Path:
    """A settings x policies heatmap of success rates (annotated with rate and interval)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np

    policies, settings = report["policies"], report["settings"]
    rates = np.array([[report["results"][p][i]["summary"].rate for p in policies] for i in range(len(settings))])
    fig, ax = plt.subplots(figsize=(1.8 + 1.9 * len(policies), 0.9 + 0.45 * len(settings)))
    im = ax.imshow(100 * rates, cmap="RdYlGn", vmin=0, vmax=100, aspect="auto")
    ax.set_xticks(range(len(policies)), policies, rotation=20, ha="right")
    ax.set_yticks(range(len(settings)), settings)
    for i in range(len(settings)):
        for j, policy in enumerate(policies):
            low, high = report["results"][policy][i]["summary"].interval
            ax.text(
                j,
                i,
                f"{100 * rates[i, j]:.0f}%\n[{100 * low:.0f}, {100 * high:.0f}]",
                ha="center",
                va="center",
                fontsize=7,
            )
    fig.colorbar(im, ax=ax, label="success rate (%)")
    ax.set_title(f"{report['env']}: generalization across factors of variation", fontsize=9)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path


# -- sweeps from a YAML file: envs x policies x factor settings ----------------------------------
#: keys of a sweep file and their defaults (``envs`` and ``policies`` are required)
SWEEP_KEYS = {
    "envs": None,
    "policies": None,
    "factors": ["none"],
    "episodes": 20,
    "seed": 0,
    "num_envs": 1,
    "max_steps": None,
    "image_size": None,
    "device": "auto",
    "plan": {},
}


def load_sweep_file(path: Path) -> dict[str, Any]:
    """The settings of sweep file ``path`` (YAML), checked, defaults filled in.

    ``factors`` lists the settings evaluated for every env and policy: ``none`` (in distribution),
    a factor or group name, ``all``, or a list of names resampled together. ``image_size`` left
    out stays None: ``swm sweep`` takes what the first ``wm:`` / ``gc:`` run was trained on, else 64.
    """
    import yaml

    from ..errors import ConfigError, did_you_mean

    try:
        spec = yaml.safe_load(Path(path).read_text())
    except (OSError, yaml.YAMLError) as exc:
        raise ConfigError(f"swm sweep requires a readable YAML file, got {str(path)!r}: {exc}") from exc
    if not isinstance(spec, dict):
        raise ConfigError(
            f"swm sweep requires a YAML mapping with keys {', '.join(SWEEP_KEYS)}, got {type(spec).__name__}"
        )
    for key in spec:
        if key not in SWEEP_KEYS:
            raise ConfigError(
                f"swm sweep file has an unknown key {key!r}.{did_you_mean(key, SWEEP_KEYS)} "
                f"Keys: {', '.join(SWEEP_KEYS)}"
            )
    out = {k: spec.get(k, v) for k, v in SWEEP_KEYS.items()}
    for key in ("envs", "policies", "factors"):
        value = out[key]
        if isinstance(value, str):
            out[key] = value = [value]
        if not isinstance(value, list) or not value:
            raise ConfigError(f"swm sweep requires {key!r} to be a non-empty list, got {value!r}")
    for key in ("episodes", "seed", "num_envs", "image_size"):
        if key == "image_size" and out[key] is None:  # what the first wm:/gc: run was trained on, else 64
            continue
        if isinstance(out[key], bool) or not isinstance(out[key], int) or out[key] < (0 if key == "seed" else 1):
            raise ConfigError(
                f"swm sweep requires {key!r} to be an integer >= {0 if key == 'seed' else 1}, got {out[key]!r}"
            )
    if not isinstance(out["plan"], dict):
        raise ConfigError(
            f"swm sweep requires 'plan' to be a mapping of planner settings (solver, horizon, ...), got {out['plan']!r}"
        )
    return out


def _setting(entry: Any) -> tuple[str, list[str]]:
    """A ``factors`` entry as ``(label, variation)``."""
    if entry in (None, "none", IN_DISTRIBUTION):
        return IN_DISTRIBUTION, []
    names = [entry] if isinstance(entry, str) else [str(e) for e in entry]
    return ("all factors" if names == ["all"] else "+".join(names)), names


def run_sweep_file(spec: dict[str, Any], *, evaluate: Any, plan: Any, **kwargs: Any) -> list[dict[str, Any]]:
    """One report per env (as :func:`run_sweep`), every policy in every setting on the same seeds."""
    from ..planning.policies import episode_limit, resolve_env, variation_space_of

    reports = []
    for env in spec["envs"]:
        env = resolve_env(env)
        settings = [_setting(e) for e in spec["factors"]]
        space = variation_space_of(env)
        for _, variation in settings:
            check_factor_names(env, space, variation, extra=["none"])
        report: dict[str, Any] = {
            "env": env,
            "policies": list(spec["policies"]),
            "settings": [s for s, _ in settings],
            "results": {},
        }
        for policy in spec["policies"]:
            report["results"][policy] = []
            for label, variation in settings:
                summary, _, record = evaluate(
                    env,
                    policy,
                    variation=variation,
                    episodes=spec["episodes"],
                    seed=spec["seed"],
                    num_envs=spec["num_envs"],
                    max_steps=episode_limit(env, spec["max_steps"]),
                    image_size=spec["image_size"],
                    device=spec["device"],
                    plan=plan if policy.startswith("wm:") else None,
                    **kwargs,
                )
                report["results"][policy].append(
                    {"setting": label, "variation": variation, "summary": summary, "record": record}
                )
        reports.append(report)
    return reports

"""The run folder of a training run: metrics files, the loss-curve plot, protocol and state files.

$STABLEWM_HOME/checkpoints/<run>/
    weights.pt  config.json  protocol.json     the model (loadable with load_pretrained)
    step_<N>/weights.pt + config.json          periodic checkpoints
    train_state.ckpt                           optimizer, scheduler, scaler, RNG, step (--resume)
    metrics.jsonl  metrics.csv  loss.png       what happened
    tensorboard/                               TensorBoard events (logger "tensorboard" or "wandb")
    wandb.json  wandb/                         the W&B run's id (resumed runs continue it) and files (logger "wandb")
"""

from __future__ import annotations

import csv
import json
import logging
import math
from pathlib import Path
from typing import Any

logger = logging.getLogger(__name__)

__all__ = [
    "LOGGERS",
    "MetricsLog",
    "TensorBoardSink",
    "WandbSink",
    "check_logger",
    "load_train_state",
    "plot_losses",
    "rng_state",
    "set_rng_state",
]

STATE_NAME = "train_state.ckpt"
#: version of the train state layout (1: tensors/numbers/strings only, RNG states as tensors)
TRAIN_STATE_FORMAT = 1


# -- the training state, without pickle ---------------------------------------------------------
def rng_state(generator: Any) -> dict[str, Any]:
    """torch (CPU and CUDA), numpy, Python and ``generator``'s RNG states as tensors and numbers."""
    import random

    import numpy as np
    import torch

    name, keys, pos, has_gauss, cached = np.random.get_state()
    version, internal, gauss_next = random.getstate()
    return {
        "torch": torch.get_rng_state(),
        "cuda": torch.cuda.get_rng_state_all() if torch.cuda.is_available() else [],
        "numpy": {
            "name": str(name),
            "keys": torch.from_numpy(np.asarray(keys, dtype=np.int64)),
            "pos": int(pos),
            "has_gauss": int(has_gauss),
            "cached_gaussian": float(cached),
        },
        "python": {
            "version": int(version),
            "state": torch.tensor(internal, dtype=torch.int64),
            "gauss_next": gauss_next,
        },
        "batches": generator.get_state(),
    }


def set_rng_state(rng: dict[str, Any], generator: Any) -> None:
    """Restore what :func:`rng_state` saved (also the tuples of train states written before format 1)."""
    import random

    import numpy as np
    import torch

    torch.set_rng_state(rng["torch"])
    if rng["cuda"] and torch.cuda.is_available():
        torch.cuda.set_rng_state_all(rng["cuda"])
    state = rng["numpy"]
    if isinstance(state, dict):
        keys = np.asarray(state["keys"].numpy(), dtype=np.uint32)
        state = (state["name"], keys, state["pos"], state["has_gauss"], state["cached_gaussian"])
    np.random.set_state(state)
    state = rng["python"]
    if isinstance(state, dict):
        state = (state["version"], tuple(int(v) for v in state["state"].tolist()), state["gauss_next"])
    random.setstate(state)
    generator.set_state(rng["batches"])


def load_train_state(path: Path, map_location: Any = None) -> dict[str, Any]:
    """The training state in ``path``, read with ``weights_only=True``.

    A state written before format 1 holds pickled numpy/Python objects: it is refused when
    ``STABLEWM_REFUSE_PICKLE=1``, else loaded with a warning naming the file (as ``*_object.ckpt``).
    """
    import pickle
    import warnings

    import torch

    from ..errors import CheckpointError
    from ..wm.trust import PICKLE_ENV, pickles_refused

    try:
        return torch.load(path, map_location=map_location, weights_only=True)
    except pickle.UnpicklingError:
        pass
    except Exception as exc:  # a damaged or truncated file
        raise CheckpointError(
            f"Resuming requires a readable {path.name}, got a damaged or truncated {path} ({type(exc).__name__}: "
            f"{str(exc).splitlines()[0][:160] if str(exc) else ''}); start the run again under another name"
        ) from exc
    if pickles_refused():
        raise CheckpointError(
            f"Resuming refuses the pickled training state {path} ({PICKLE_ENV} is set): it was written by an older "
            "version; unset the variable to load it if you trust the file"
        )
    warnings.warn(
        f"{path} is a pickled training state (written by an older version): loading it runs code stored in the file; "
        f"load only files you trust (set {PICKLE_ENV}=1 to refuse pickles). "
        "The next checkpoint rewrites it without pickle.",
        UserWarning,
        stacklevel=2,
    )
    return torch.load(path, map_location=map_location, weights_only=False)


#: where a run's metrics go besides metrics.jsonl / metrics.csv (always written): ``tensorboard``
#: (TensorBoard events in ``tensorboard/``), ``wandb`` (TensorBoard and a Weights & Biases run) or ``none``
LOGGERS = ("tensorboard", "wandb", "none")
#: the W&B project of a run when neither ``wandb_project`` nor ``$WANDB_PROJECT`` names one
WANDB_PROJECT = "stable-worldmodel"
#: the run folder's record of its W&B run (``--resume`` continues the run of that id)
WANDB_RUN_FILE = "wandb.json"


def check_logger(logger: Any) -> str:
    """``logger`` when it is one of :data:`LOGGERS`, else an :class:`~stable_worldmodel.errors.UnknownNameError`
    with a "did you mean"; ``wandb`` also requires the package (``pip install 'stable-worldmodel[wandb]'``)."""
    from .._optional import is_available
    from ..errors import DependencyNotInstalled, unknown_name

    if not isinstance(logger, str) or logger not in LOGGERS:
        raise unknown_name("logger", str(logger), LOGGERS)
    if logger == "wandb" and not is_available("wandb"):
        raise DependencyNotInstalled(
            "The wandb logger (--logger wandb) requires the wandb package, which is not installed. "
            "Install it with: pip install 'stable-worldmodel[wandb]'"
        )
    return logger


def _scalars(record: dict[str, Any]) -> dict[str, float]:
    """The finite numbers of ``record`` but its ``step``."""
    return {
        k: v
        for k, v in record.items()
        if k != "step" and isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)
    }


class TensorBoardSink:
    """Mirrors each record's scalars to TensorBoard events in ``<run>/tensorboard`` (when
    TensorBoard is installed: :meth:`open` returns None otherwise)."""

    def __init__(self, writer: Any):
        self.writer = writer

    @classmethod
    def open(cls, folder: Path) -> TensorBoardSink | None:
        try:
            from torch.utils.tensorboard import SummaryWriter

            return cls(SummaryWriter(log_dir=str(folder / "tensorboard")))
        except Exception:  # tensorboard is optional: any import or start-up failure means no mirror
            return None

    def log(self, record: dict[str, Any]) -> None:
        for key, value in _scalars(record).items():
            self.writer.add_scalar(key, value, record.get("step", 0))

    def close(self, exit_code: int = 0) -> None:
        self.writer.close()


def _beside_other_runs(wandb: Any) -> dict[str, Any]:
    """``wandb.init`` arguments that start a new run even when the process has one active (the
    user's own): ``reinit="create_new"`` where wandb has it (0.19.10 and later)."""
    try:
        version = tuple(int(part) for part in wandb.__version__.split(".")[:3])
    except ValueError:
        return {}
    return {"reinit": "create_new"} if version >= (0, 19, 10) else {}


class WandbSink:
    """Logs each record's scalars at its step to a Weights & Biases run named after the training run.

    The run's config is ``config`` (the model config, the training arguments, the provenance);
    its id is kept in ``<run>/wandb.json`` so that a resumed training run continues the same W&B
    run. ``WANDB_MODE`` (``offline`` needs no network), ``WANDB_DIR`` (default: the run folder),
    ``WANDB_ENTITY`` and the other ``WANDB_*`` variables apply as wandb reads them.
    """

    def __init__(self, run: Any, info: dict[str, Any]):
        self.run, self.info = run, info
        self._floor = int(getattr(run, "step", 0) or 0)  # a resumed W&B run refuses steps it has passed

    @classmethod
    def open(cls, folder: Path, *, name: str, project: str | None, config: dict[str, Any], resume: bool) -> WandbSink:
        import os

        from .._optional import require
        from ..errors import ConfigError

        wandb = require("wandb", "wandb", "--logger wandb")
        project = project or os.environ.get("WANDB_PROJECT") or WANDB_PROJECT
        record = folder / WANDB_RUN_FILE
        previous: dict[str, Any] = {}
        if resume and record.is_file():
            try:
                previous = json.loads(record.read_text())
            except (OSError, ValueError):
                logger.warning("%s is unreadable: the resumed run starts a new W&B run", record)
        run_id = previous.get("id") if previous.get("project", project) == project else None
        try:
            run = wandb.init(
                project=project,
                name=name,
                id=run_id,
                resume="allow" if run_id else None,
                config=config,
                # read here, not once per process as wandb's settings are: each run honours the current ones
                dir=os.environ.get("WANDB_DIR") or str(folder),
                mode=os.environ.get("WANDB_MODE") or None,
                **_beside_other_runs(wandb),
            )
        except Exception as exc:  # no login, no network in online mode, a bad entity...
            raise ConfigError(
                f"--logger wandb requires a W&B run, got {type(exc).__name__}: {' '.join(str(exc).split())[:300]} "
                "(log in with `wandb login`, or set WANDB_MODE=offline to log without a network)"
            ) from exc
        info = {
            "id": run.id,
            "project": project,
            "name": name,
            "mode": str(getattr(run.settings, "mode", "") or os.environ.get("WANDB_MODE", "online")),
            "url": getattr(run, "url", None),
            "dir": str(Path(run.dir).parent),
        }
        record.write_text(json.dumps(info, indent=2) + "\n")
        return cls(run, info)

    def log(self, record: dict[str, Any]) -> None:
        step = int(record.get("step", 0))
        values = _scalars(record)
        if values and step >= self._floor:
            self.run.log(values, step=step)

    def close(self, exit_code: int = 0) -> None:
        self.run.finish(exit_code=exit_code)


class MetricsLog:
    """Appends one JSON line per record to ``metrics.jsonl`` and rewrites ``metrics.csv`` on
    :meth:`close`; passes every record to its ``sinks`` too (default: TensorBoard when it is
    installed; :meth:`open` picks them by the ``logger`` name, :data:`LOGGERS`).

    :meth:`close` is called once whatever happens (it does nothing the second time): with
    ``exit_code`` 0 when the run ended or stopped cleanly, else the W&B run is marked failed.
    """

    def __init__(self, folder: Path, resume_step: int | None = None, sinks: list[Any] | None = None):
        self.folder = folder
        self.path = folder / "metrics.jsonl"
        if resume_step is None:
            self.path.write_text("")
        else:  # keep what was logged up to the resumed step
            kept = [r for r in self.read() if r.get("step", 0) <= resume_step]
            self.path.write_text("".join(json.dumps(r) + "\n" for r in kept))
        self._file = self.path.open("a")
        self.closed = False
        self.sinks = [s for s in ([TensorBoardSink.open(folder)] if sinks is None else sinks) if s is not None]

    @classmethod
    def open(
        cls,
        folder: Path,
        *,
        resume_step: int | None = None,
        logger: str = "tensorboard",
        name: str | None = None,
        project: str | None = None,
        config: dict[str, Any] | None = None,
    ) -> MetricsLog:
        """The metrics log of run folder ``folder`` with the sinks of ``logger`` (:data:`LOGGERS`):
        ``name`` / ``project`` / ``config`` are the W&B run's (``logger="wandb"``)."""
        check_logger(logger)
        sinks: list[Any] = []
        if logger in ("tensorboard", "wandb"):
            sinks.append(TensorBoardSink.open(folder))
        log = cls(folder, resume_step=resume_step, sinks=sinks)
        if logger == "wandb":
            try:
                log.sinks.append(
                    WandbSink.open(
                        folder,
                        name=name or folder.name,
                        project=project,
                        config=config or {},
                        resume=resume_step is not None,
                    )
                )
            except BaseException:
                log.close(exit_code=1)
                raise
        return log

    @property
    def wandb(self) -> dict[str, Any] | None:
        """The W&B run's id, project, mode, URL and folder (None without one)."""
        return next((s.info for s in self.sinks if isinstance(s, WandbSink)), None)

    def read(self) -> list[dict[str, Any]]:
        if not self.path.is_file():
            return []
        return [json.loads(line) for line in self.path.read_text().splitlines() if line.strip()]

    def log(self, record: dict[str, Any]) -> None:
        self._file.write(json.dumps(record) + "\n")
        self._file.flush()
        for sink in self.sinks:
            sink.log(record)

    def close(self, exit_code: int = 0) -> None:
        """Close the file and the sinks (a W&B run finishes with ``exit_code``) and write metrics.csv."""
        if self.closed:
            return
        self.closed = True
        self._file.close()
        try:
            for sink in self.sinks:
                try:
                    sink.close(exit_code)
                except Exception as exc:  # one sink failing to close must not lose the others nor the CSV
                    logger.warning("Closing the %s logger failed: %s", type(sink).__name__, exc)
        finally:
            records = self.read()
            fields = sorted({k for r in records for k in r}, key=lambda k: (k != "step", k))
            with (self.folder / "metrics.csv").open("w", newline="") as f:
                writer = csv.DictWriter(f, fieldnames=fields)
                writer.writeheader()
                writer.writerows(records)


def plot_losses(records: list[dict[str, Any]], path: Path, title: str) -> Path | None:
    """Train loss (and its terms) and validation loss against the step, log scale, as a PNG; with
    evaluations (``eval/success_rate``) a second panel: the success rate and its 95% interval."""
    train = [r for r in records if "train/loss" in r]
    if not train:
        return None
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    evals = [r for r in records if "eval/success_rate" in r]
    fig, axes = plt.subplots(1, 2 if evals else 1, figsize=(11 if evals else 6, 3.8), dpi=120, squeeze=False)
    ax = axes[0][0]
    try:
        if evals:
            _plot_success(axes[0][1], evals)
        steps = [r["step"] for r in train]
        ax.plot(steps, [r["train/loss"] for r in train], label="train loss", color="#2f7ebc")
        for key in sorted({k for r in train for k in r if k.startswith("train/") and k.endswith("_loss")}):
            values = [(r["step"], r[key]) for r in train if key in r and r[key] > 0]
            if values:
                ax.plot(*zip(*values, strict=False), label=key[len("train/") :], linewidth=0.8, alpha=0.7)
        val = [(r["step"], r["val/loss"]) for r in records if "val/loss" in r]
        if val:
            ax.plot(*zip(*val, strict=False), "o-", label="val loss", color="#c4703a")
        if all(r["train/loss"] > 0 for r in train):
            ax.set_yscale("log")
        ax.set_xlabel("step")
        ax.set_title(title, fontsize=9)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7)
        fig.tight_layout()
        fig.savefig(path)
    finally:
        plt.close(fig)
    return path


def _plot_success(ax: Any, evals: list[dict[str, Any]]) -> None:
    """The evaluations' success rate (percent) against the step, with 95% interval bars."""
    steps = [r["step"] for r in evals]
    rate = [r["eval/success_rate"] for r in evals]
    low = [r["eval/success_rate"] - r.get("eval/ci95_low", r["eval/success_rate"]) for r in evals]
    high = [r.get("eval/ci95_high", r["eval/success_rate"]) - r["eval/success_rate"] for r in evals]
    ax.errorbar(steps, rate, yerr=[low, high], fmt="o-", capsize=3, color="#3a9a5b", label="success (95% CI)")
    if all("eval/train_seconds" in r for r in evals):  # training minutes under each point
        for step, value, r in zip(steps, rate, evals, strict=True):
            ax.annotate(f"{r['eval/train_seconds'] / 60:.0f} min", (step, value), fontsize=6, xytext=(3, -9),
                        textcoords="offset points")  # fmt: skip
    ax.set_ylim(-2, 102)
    ax.set_xlabel("step")
    ax.set_ylabel("success rate (%)")
    ax.set_title("evaluation", fontsize=9)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7)


def provenance() -> dict[str, Any]:
    """Where and with what a run is trained: package versions, the git commit of the working
    directory (when it is a repository; ``dirty`` when it has uncommitted changes), the command
    line, the host and the start time (UTC, ISO 8601). Recorded in ``protocol.json``."""
    import datetime
    import platform
    import shlex
    import socket
    import subprocess
    import sys

    import numpy as np
    import torch

    from .. import __version__

    def git(*args: str) -> str | None:
        try:
            out = subprocess.run(["git", *args], capture_output=True, text=True, timeout=5)
        except (OSError, subprocess.SubprocessError):
            return None
        return out.stdout.strip() if out.returncode == 0 else None

    commit = git("rev-parse", "HEAD")
    record: dict[str, Any] = {
        "versions": {
            "stable_worldmodel": __version__,
            "python": platform.python_version(),
            "torch": torch.__version__,
            "numpy": np.__version__,
        },
        "command": shlex.join(sys.argv),
        "host": socket.gethostname(),
        "started": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
    }
    if commit:
        record["git"] = {"commit": commit, "dirty": bool(git("status", "--porcelain", "--untracked-files=no"))}
    return record


def now_utc() -> str:
    """The current time, UTC, ISO 8601 (seconds)."""
    import datetime

    return datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds")

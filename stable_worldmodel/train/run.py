"""The run folder of a training run: metrics files, the loss-curve plot, protocol and state files.

$STABLEWM_HOME/checkpoints/<run>/
    weights.pt  config.json  protocol.json     the model (loadable with load_pretrained)
    step_<N>/weights.pt + config.json          periodic checkpoints
    train_state.ckpt                           optimizer, scheduler, scaler, RNG, step (--resume)
    metrics.jsonl  metrics.csv  loss.png       what happened
"""

from __future__ import annotations

import csv
import json
import logging
import math
from pathlib import Path
from typing import Any

logger = logging.getLogger(__name__)

__all__ = ["MetricsLog", "load_train_state", "plot_losses", "rng_state", "set_rng_state"]

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


class MetricsLog:
    """Appends one JSON line per record to ``metrics.jsonl`` and rewrites ``metrics.csv`` on
    :meth:`close`; mirrors scalars to TensorBoard when it is installed."""

    def __init__(self, folder: Path, resume_step: int | None = None):
        self.folder = folder
        self.path = folder / "metrics.jsonl"
        if resume_step is None:
            self.path.write_text("")
        else:  # keep what was logged up to the resumed step
            kept = [r for r in self.read() if r.get("step", 0) <= resume_step]
            self.path.write_text("".join(json.dumps(r) + "\n" for r in kept))
        self._file = self.path.open("a")
        self._tb = None
        try:
            from torch.utils.tensorboard import SummaryWriter

            self._tb = SummaryWriter(log_dir=str(folder / "tensorboard"))
        except Exception:  # tensorboard is optional: any import or start-up failure means no mirror
            self._tb = None

    def read(self) -> list[dict[str, Any]]:
        if not self.path.is_file():
            return []
        return [json.loads(line) for line in self.path.read_text().splitlines() if line.strip()]

    def log(self, record: dict[str, Any]) -> None:
        self._file.write(json.dumps(record) + "\n")
        self._file.flush()
        if self._tb is not None:
            for key, value in record.items():
                if key != "step" and isinstance(value, (int, float)) and math.isfinite(value):
                    self._tb.add_scalar(key, value, record.get("step", 0))

    def close(self) -> None:
        self._file.close()
        if self._tb is not None:
            self._tb.close()
        records = self.read()
        fields = sorted({k for r in records for k in r}, key=lambda k: (k != "step", k))
        with (self.folder / "metrics.csv").open("w", newline="") as f:
            writer = csv.DictWriter(f, fieldnames=fields)
            writer.writeheader()
            writer.writerows(records)


def plot_losses(records: list[dict[str, Any]], path: Path, title: str) -> Path | None:
    """Train loss (and its terms) and validation loss against the step, log scale, as a PNG."""
    train = [r for r in records if "train/loss" in r]
    if not train:
        return None
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6, 3.8), dpi=120)
    try:
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

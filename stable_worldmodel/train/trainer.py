"""One training loop for every world model: the model gives ``loss(batch)``, the loop does the rest.

AdamW with per-module parameter groups (no weight decay on biases, norms and embeddings;
the encoder's learning rate scaled by ``encoder_lr_scale``), linear warmup then cosine
decay, gradient clipping, autocast (bf16 / fp16 with a grad scaler) where the device
supports it, ``torch.compile`` of the loss on request, validation loss, an
embedding-collapse monitor (per-dim std of the embeddings), periodic checkpoints plus the
last one, and exact resume: model, optimizer, scheduler, scaler, every RNG and the step are
restored, so a resumed run equals an uninterrupted one. Under ``torchrun`` the step runs
data-parallel (:mod:`.distributed`).
"""

from __future__ import annotations

import contextlib
import logging
import math
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import torch

from .._device import resolve_device
from ..errors import ConfigError
from ..wm import utils as wmu
from ..wm.base import HasValidationLoss
from . import distributed
from .distributed import DistInfo
from .run import STATE_NAME, TRAIN_STATE_FORMAT, MetricsLog, now_utc, plot_losses, rng_state, set_rng_state

logger = logging.getLogger(__name__)

__all__ = ["TrainResult", "Trainer", "resolve_device"]

PRECISIONS = ("32", "bf16", "16")
#: the sub-folder of a run holding its best evaluated checkpoint (``swm eval --policy wm:RUN/best``)
BEST_NAME = "best"


_FUSED_ADAMW_DEVICES = ("cpu", "cuda")


def _param_groups(model: torch.nn.Module, lr: float, weight_decay: float, encoder_lr_scale: float) -> list[dict]:
    """Four groups: (encoder or not) x (decayed matrices or not-decayed vectors)."""
    groups: dict[tuple[bool, bool], list] = {}
    for name, p in model.named_parameters():
        if not p.requires_grad:
            continue
        is_encoder = name.startswith("encoder.")
        decay = (
            p.ndim >= 2
            and "pos_embedding" not in name
            and "position_embeddings" not in name
            and "cls_token" not in name
        )
        groups.setdefault((is_encoder, decay), []).append(p)
    return [
        {
            "params": ps,
            "lr": lr * (encoder_lr_scale if enc else 1.0),
            "weight_decay": weight_decay if decay else 0.0,
            "name": f"{'encoder' if enc else 'model'}/{'decay' if decay else 'no_decay'}",
        }
        for (enc, decay), ps in sorted(groups.items())
    ]


def _schedule(warmup: int, total: int):
    def factor(step: int) -> float:
        if warmup and step < warmup:
            return (step + 1) / warmup
        progress = (step - warmup) / max(1, total - warmup)
        return 0.5 * (1.0 + math.cos(math.pi * min(1.0, progress)))

    return factor


@dataclass
class TrainResult:
    """What :func:`stable_worldmodel.train.train` returns."""

    run: str
    folder: Path
    steps: int
    train_loss: float
    val_loss: float | None
    seconds: float
    samples_per_second: float
    history: list[dict[str, Any]] = field(default_factory=list)
    #: the frozen-encoder feature cache this run used (:class:`~stable_worldmodel.train.features.FeatureCache`), if any
    features: Any = None


class _Loss(torch.nn.Module):
    """``forward(batch) = model.loss(batch)``: what DDP wraps (it hooks ``forward`` only)."""

    def __init__(self, model: torch.nn.Module):
        super().__init__()
        self.model = model

    def forward(self, batch: dict[str, torch.Tensor]) -> dict[str, torch.Tensor]:
        return self.model.loss(batch)


#: seconds between the progress lines of a run without a progress bar (stderr not a terminal:
#: SLURM, nohup); ``STABLEWM_PROGRESS_SECONDS`` overrides it
PROGRESS_SECONDS = 30.0


class _Heartbeat:
    """Plain progress lines on stderr, every :data:`PROGRESS_SECONDS`, when there is no bar."""

    def __init__(self, run: str, steps: int, enabled: bool):
        import os

        self.run, self.steps, self.enabled = run, steps, enabled
        self.every = float(os.environ.get("STABLEWM_PROGRESS_SECONDS", PROGRESS_SECONDS))
        self.last = time.monotonic()

    def maybe(self, step: int, loss: float, rate: float, batch: int) -> None:
        import sys

        now = time.monotonic()
        if not self.enabled or now - self.last < self.every:
            return
        self.last = now
        left = (self.steps - step) * batch / max(rate, 1e-9)
        eta = (
            f"{int(left // 3600)}h{int(left % 3600 // 60):02d}m"
            if left >= 3600
            else f"{int(left // 60)}m{int(left % 60):02d}s"
        )
        sys.stderr.write(
            f"train {self.run}: step {step}/{self.steps} ({100 * step / self.steps:.0f}%), loss {loss:.4f}, "
            f"{rate:.0f} samples/s, ETA {eta}\n"
        )
        sys.stderr.flush()


class _GracefulStop:
    """Ctrl-C during :meth:`Trainer.fit`: the first asks to stop after the current step (which then
    saves a checkpoint), a second stops at once. Only in the main thread (signals are delivered there)."""

    def __init__(self):
        import signal
        import threading

        self.requested = False
        self._previous = None
        if threading.current_thread() is threading.main_thread():
            self._previous = signal.signal(signal.SIGINT, self._on_sigint)

    def _on_sigint(self, signum, frame) -> None:
        if self.requested:
            raise KeyboardInterrupt
        self.requested = True

    def restore(self) -> None:
        if self._previous is not None:
            import signal

            signal.signal(signal.SIGINT, self._previous)
            self._previous = None


class Trainer:
    """Trains ``model`` on ``data`` (:class:`~stable_worldmodel.train.data.TrainData`) into ``folder``.

    With ``dist`` (one process of a ``torchrun`` group) each step trains on this process's slice
    of the global batch under DDP; only process 0 logs, validates and saves.
    """

    def __init__(
        self,
        model: torch.nn.Module,
        data: Any,
        cfg: Any,
        *,
        folder: Path,
        run: str,
        device: torch.device,
        precision: str = "32",
        compile: bool = False,
        seed: int = 0,
        steps: int,
        log_every: int = 10,
        val_every: int = 0,
        ckpt_every: int = 0,
        val_samples: int = 512,
        progress: bool = True,
        config_tree: dict,
        protocol: dict,
        dist: DistInfo | None = None,
    ):
        if precision not in PRECISIONS:
            raise ConfigError(f"Training requires precision in {PRECISIONS}, got {precision!r}")
        if not isinstance(compile, bool):
            raise ConfigError(f"Training requires compile to be True or False, got {compile!r}")
        if precision == "16" and device.type != "cuda":
            raise ConfigError(f"Training requires a CUDA device for precision 16, got {device}; use bf16 or 32")
        self.model, self.data, self.cfg = model.to(device), data, cfg
        self.folder, self.run, self.device, self.precision, self.seed = folder, run, device, precision, seed
        self.steps, self.log_every, self.val_every, self.ckpt_every = steps, log_every, val_every, ckpt_every
        self.val_samples, self.progress = val_samples, progress
        self.config_tree, self.protocol = config_tree, protocol
        self.optimizer = torch.optim.AdamW(  # fused: one kernel per step (CPU too: ~5x the default's speed)
            _param_groups(model, cfg.lr, cfg.weight_decay, cfg.encoder_lr_scale),
            lr=cfg.lr,
            fused=device.type in _FUSED_ADAMW_DEVICES,
        )
        self.scheduler = torch.optim.lr_scheduler.LambdaLR(self.optimizer, _schedule(cfg.warmup_steps, steps))
        self.scaler = torch.amp.GradScaler(device.type, enabled=precision == "16")
        self.generator = torch.Generator().manual_seed(seed)
        self.dist = dist or DistInfo()
        self.ddp = None
        # the training step's forward and backward through torch.compile (compiled on the first step; the
        # validation loss and the saved weights are the model's own)
        self.compile = compile
        self._loss = torch.compile(self.model.loss) if self.compile else self.model.loss
        if self.dist.enabled:
            from torch.nn.parallel import DistributedDataParallel

            distributed.global_batch_norm(self.model)
            self.ddp = DistributedDataParallel(
                _Loss(self.model), device_ids=[device] if device.type == "cuda" else None
            )
            if self.compile:
                self.ddp = torch.compile(self.ddp)
        self.step = 0
        #: called with the trainer before each training step (online training collects there)
        self.before_step: Any = None
        #: ``evaluator(trainer) -> {"success_rate", "ci95", "episodes"}`` (percent), run every ``eval_every``
        #: steps and at the end on the checkpoint just written; the best one is kept as ``best/``
        self.evaluator: Any = None
        self.eval_every = 0
        self.best_eval: float | None = None
        # training time (evaluations excluded) of the steps before this fit (a resumed run's); this fit's clock
        self._seconds_before = 0.0
        self._fit_start: float | None = None
        self._eval_spent = 0.0
        # the next train batch, read in a background thread while a step computes (see :meth:`_prefetching`):
        # (its future, the generator state before its draws, its batch size)
        self._pending: Any = None
        self._pool: Any = None
        self.window: list[
            Any
        ] = []  # train losses (floats or 0-d tensors) since the last log (checkpointed, for exact resume)
        self._collapse_warned = False

    # -- state ---------------------------------------------------------------------------------
    def state_dict(self) -> dict[str, Any]:
        """Everything to resume exactly, as tensors, numbers, strings, lists and dicts only
        (loadable with ``torch.load(..., weights_only=True)``: no pickle)."""
        return {
            "format": TRAIN_STATE_FORMAT,
            "model": self.model.state_dict(),
            "optimizer": self.optimizer.state_dict(),
            "scheduler": self.scheduler.state_dict(),
            "scaler": self.scaler.state_dict(),
            "step": self.step,
            "rng": rng_state(self._generator_at_step()),
            "steps": self.steps,
            "loss_window": [float(v) for v in self.window],
            "best_eval": self.best_eval,
            "train_seconds": self.train_seconds(),
        }

    def load_state_dict(self, state: dict[str, Any]) -> None:
        self.model.load_state_dict(state["model"])
        self.optimizer.load_state_dict(state["optimizer"])
        self.scheduler.load_state_dict(state["scheduler"])
        self.scaler.load_state_dict(state["scaler"])
        self.step = int(state["step"])
        self.window = [float(v) for v in state.get("loss_window", [])]
        self.best_eval = state.get("best_eval")
        self._seconds_before = float(state.get("train_seconds", 0.0))
        set_rng_state(state["rng"], self.generator)

    def save(self, final: bool = False) -> None:
        """Write the model (run folder and ``step_<N>/``) and the training state (process 0 only)."""
        if not self.dist.is_main:
            return
        protocol = {**self.protocol, "steps_done": self.step}
        for where in [self.folder] + ([self.folder / f"step_{self.step:06d}"] if not final else []):
            where.mkdir(parents=True, exist_ok=True)
            wmu.write_checkpoint(self.model, where, self.config_tree, protocol)
        wmu._atomic_write(self.folder / STATE_NAME, wmu._write_bytes(wmu.serialize_state(self.state_dict())))

    # -- evaluation during training ------------------------------------------------------------
    def train_seconds(self) -> float:
        """Seconds spent training so far, resumed runs' earlier time included and evaluations excluded."""
        if self._fit_start is None:
            return self._seconds_before
        return self._seconds_before + time.perf_counter() - self._fit_start - self._eval_spent

    def _eval_due(self) -> bool:
        return bool(self.evaluator is not None and self.eval_every and self.step % self.eval_every == 0)

    def _evaluate(self, log: MetricsLog) -> None:
        """Evaluate the checkpoint of this step (process 0), log its success rate and keep the best as ``best/``.

        The evaluation draws from torch's random streams: they are restored after it, so a run with
        evaluations trains exactly as one without (and a resumed one as an uninterrupted one)."""
        if not self.dist.is_main:
            return
        devices = [self.device] if self.device.type == "cuda" else []
        trained = self.train_seconds()
        began = time.perf_counter()
        with torch.random.fork_rng(devices=devices):
            result = self.evaluator(self)
        self._eval_spent += time.perf_counter() - began
        rate = float(result["success_rate"])
        low, high = (float(v) for v in result["ci95"])
        log.log(
            {
                "step": self.step,
                "eval/success_rate": rate,
                "eval/ci95_low": low,
                "eval/ci95_high": high,
                "eval/train_seconds": trained,
            }
        )
        line = (
            f"train {self.run}: step {self.step}/{self.steps}, evaluation: success {rate:.1f}% [{low:.1f}, {high:.1f}] "
            f"on {result['episodes']} episodes"
        )
        if self.progress:  # above the progress bar
            from tqdm.auto import tqdm

            tqdm.write(line, file=sys.stderr)
        else:  # beside the heartbeat's lines
            sys.stderr.write(line + "\n")
            sys.stderr.flush()
        if self.best_eval is None or rate > self.best_eval:
            self.best_eval = rate
            protocol = {**self.protocol, "steps_done": self.step, "best": {"step": self.step, **result}}
            wmu.write_checkpoint(self.model, self.folder / BEST_NAME, self.config_tree, protocol)

    # -- loop --------------------------------------------------------------------------------
    def _autocast(self):
        if self.precision == "32":
            return contextlib.nullcontext()
        dtype = torch.bfloat16 if self.precision == "bf16" else torch.float16
        return torch.autocast(self.device.type, dtype=dtype)

    def _monitor(self, emb: torch.Tensor) -> dict[str, float]:
        std = emb.detach().float().reshape(-1, emb.shape[-1]).std(dim=0)
        out = {"emb_std_mean": float(std.mean()), "emb_std_min": float(std.min())}
        if out["emb_std_mean"] < 1e-3 and not self._collapse_warned:
            logger.warning("embedding collapse at step %d: mean per-dim std %.2e", self.step, out["emb_std_mean"])
            self._collapse_warned = True
        return out

    # -- batches -------------------------------------------------------------------------------
    def _prefetching(self) -> bool:
        """Whether the next batch is read while a step computes: single process, no per-step hook
        (online training adds data there), not from cached features (already in memory)."""
        if self.ddp is not None or self.before_step is not None:
            return False
        return getattr(self.data, "features", None) is None

    def _next_batch(self, bs: int) -> dict[str, torch.Tensor]:
        """This step's batch: the one read in the background during the last step, or read now;
        then the next one is started. Both draw from :attr:`generator` in the same order."""
        if self._pending is not None and self._pending[2] == bs:
            future, _, _ = self._pending
            self._pending = None
            batch = future.result()
        else:
            self._drain()
            batch = self.data.train_batch(self.generator, bs)
        if self._pool is not None and self.step + 1 < self.steps:
            before = self.generator.get_state()
            self._pending = (self._pool.submit(self.data.train_batch, self.generator, bs), before, bs)
        return batch

    def _drain(self) -> None:
        """Wait for a batch read in the background and forget it, its draws undone: the generator is
        where the steps taken left it (before validation, checkpoints, evaluations and at the end)."""
        if self._pending is None:
            return
        future, before, _ = self._pending
        self._pending = None
        with contextlib.suppress(Exception):  # its error, if any, comes back when the batch is read again
            future.result()
        self.generator.set_state(before)

    def _generator_at_step(self) -> torch.Generator:
        self._drain()
        return self.generator

    def _train_step_loss(self, bs: int) -> dict[str, torch.Tensor]:
        if self.ddp is None:
            batch = self._next_batch(bs)
            with self._autocast():
                return self._loss(batch)
        index = self.dist.shard(self.data.train_pick(self.generator, bs))  # same global pick everywhere
        # goals (goal-conditioned models) from a per-step, per-process stream: the shared pick stream stays in step
        goals = torch.Generator().manual_seed((self.seed * 1_000_003 + self.step) * 4099 + self.dist.rank)
        batch = self.data.batch(index, goals)
        with self._autocast(), distributed.global_batch():
            return self.ddp(batch)

    def validate(self) -> float | None:
        if not self.dist.is_main:
            return None
        self._drain()  # the dataset's block cache is not shared with a reading thread
        batches = self.data.val_batches(self.cfg.batch_size, self.val_samples)
        if not batches:
            return None
        was_training = self.model.training
        self.model.eval()
        total, count = 0.0, 0
        # e.g. TD-MPC2: its world model's part, without the actor's
        key = self.model.validation_loss if isinstance(self.model, HasValidationLoss) else "loss"
        with torch.no_grad(), self._autocast():
            for index in batches:
                out = self.model.loss(self.data.batch(index))
                total += float(out[key]) * len(index)
                count += len(index)
        self.model.train(was_training)
        return total / count

    def fit(self, log: MetricsLog) -> TrainResult:
        from tqdm.auto import tqdm

        bs = self.cfg.batch_size
        self.model.train()
        start, start_step = time.perf_counter(), self.step
        self._fit_start, self._eval_spent = start, 0.0
        if self._prefetching():
            from concurrent.futures import ThreadPoolExecutor

            self._pool = ThreadPoolExecutor(1, thread_name_prefix=f"swm-batches-{self.run}")
        logged = log.read()  # a resumed run's records up to its step (a finished run has no step left to log)
        last_loss = next((r["train/loss"] for r in reversed(logged) if "train/loss" in r), float("nan"))
        val_loss = next((r["val/loss"] for r in logged if "val/loss" in r and r.get("step") == self.step), None)
        main = self.dist.is_main
        bar = tqdm(
            total=self.steps,
            initial=self.step,
            desc=f"train {self.run}",
            unit="step",
            disable=not (self.progress and main),
            dynamic_ncols=True,
        )
        beat = _Heartbeat(self.run, self.steps, enabled=main and not self.progress)
        stop = _GracefulStop()
        try:
            while self.step < self.steps:
                if self.before_step is not None:
                    self.before_step(self)
                out = self._train_step_loss(bs)
                loss = out["loss"]
                self.optimizer.zero_grad(set_to_none=True)
                self.scaler.scale(loss).backward()
                if self.cfg.grad_clip:
                    self.scaler.unscale_(self.optimizer)
                    torch.nn.utils.clip_grad_norm_(self.model.parameters(), self.cfg.grad_clip)
                self.scaler.step(self.optimizer)
                self.scaler.update()
                self.scheduler.step()
                self.step += 1
                self.window.append(loss.detach())  # read back at the log: no host-device sync per step
                bar.update(1)
                if self.step % self.log_every == 0 or self.step == self.steps:
                    losses = [float(v) for v in self.window]
                    self.window.clear()
                    last_loss = distributed.mean_over_processes(self.dist, sum(losses) / len(losses))
                    if not math.isfinite(last_loss):  # the same verdict in every process
                        raise FloatingPointError(
                            f"Training diverged: loss {losses} in the {len(losses)} steps up to step {self.step}; "
                            "lower --lr or use --precision 32"
                        )
                    rate = (self.step - start_step) * bs / max(time.perf_counter() - start - self._eval_spent, 1e-9)
                    record = {
                        "step": self.step,
                        "train/loss": last_loss,
                        "lr": self.scheduler.get_last_lr()[0],
                        "samples_per_s": rate,
                    }
                    record.update(
                        {
                            f"train/{k}": float(v.detach())
                            for k, v in out.items()
                            if k != "loss" and torch.is_tensor(v) and v.ndim == 0
                        }
                    )
                    if "emb" in out:
                        record.update(self._monitor(out["emb"]))
                    if self.val_every and (self.step % self.val_every == 0 or self.step == self.steps):
                        val_loss = self.validate()
                        if val_loss is not None:
                            record["val/loss"] = val_loss
                    if main:
                        log.log(record)
                    bar.set_postfix(loss=f"{last_loss:.4f}", samples_s=f"{rate:.0f}")
                    beat.maybe(self.step, last_loss, rate, bs)
                saved = bool(self.ckpt_every and self.step % self.ckpt_every == 0 and self.step < self.steps)
                if saved:
                    self.save()
                if self._eval_due() and self.step < self.steps:
                    if not saved:
                        self.save()  # the evaluation plans with the checkpoint of this step
                        saved = True
                    self._evaluate(log)
                if stop.requested and self.step < self.steps:  # Ctrl-C: between two steps, the state is whole
                    if not saved:
                        self.save()
                    log.close(exit_code=130)  # a W&B run shows as stopped early (resume continues it)
                    exc = KeyboardInterrupt()
                    exc.swm_run = (self.run, self.folder, self.step, self.steps, True)
                    raise exc
        except KeyboardInterrupt as exc:  # a second Ctrl-C, mid-step: the last checkpoint stands
            if not hasattr(exc, "swm_run"):
                exc.swm_run = (self.run, self.folder, self.step, self.steps, False)
            raise
        finally:
            self._drain()
            if self._pool is not None:
                self._pool.shutdown()
                self._pool = None
            stop.restore()
            bar.close()
        if val_loss is None:
            val_loss = self.validate()
            if val_loss is not None:
                log.log({"step": self.step, "val/loss": val_loss})
        seconds = time.perf_counter() - start
        self.protocol["final"] = {"train_loss": last_loss, "val_loss": val_loss}
        if isinstance(self.protocol.get("provenance"), dict):
            self.protocol["provenance"]["ended"] = now_utc()
        self.save(final=True)
        if self.evaluator is not None and self.eval_every:
            self._evaluate(log)
        log.close()
        records = log.read()
        if main:
            plot_losses(
                records,
                self.folder / "loss.png",
                f"{self.run}: {self.protocol.get('model')} on {self.protocol.get('dataset')}",
            )
        rate = (self.step - start_step) * bs / max(seconds, 1e-9)
        return TrainResult(self.run, self.folder, self.step, last_loss, val_loss, seconds, rate, records)

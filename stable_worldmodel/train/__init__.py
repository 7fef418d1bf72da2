"""Training world models on recorded datasets: ``stable_worldmodel.train.train(...)`` and ``swm train``.

Importing this package is cheap; torch is imported when :func:`train` runs.

    >>> from stable_worldmodel.train import train                      # doctest: +SKIP
    >>> result = train("lewm", dataset="tworoom", preset="tiny", name="tr-lewm", seed=0)
    >>> result.folder        # $STABLEWM_HOME/checkpoints/tr-lewm (load_pretrained("tr-lewm"))
"""

from __future__ import annotations

import logging
import math
from typing import TYPE_CHECKING, Any

from ..errors import ConfigError, check_int
from ..wm.base import DerivedFromRun, HasFrozenEncoder
from ..wm.run import PROTOCOL_VERSION, lock_run

if TYPE_CHECKING:  # pragma: no cover
    from .trainer import TrainResult

__all__ = ["TRAIN_KEY_HELP", "train"]

logger = logging.getLogger(__name__)


def _positive(name: str, value: Any) -> int | None:
    return None if value is None else check_int("train", name, value)


#: one line per argument of :func:`train`: what it means (``swm show model TYPE`` prints them; every
#: argument but ``eval_plan`` and ``protocol_extra`` is also a key of ``swm train --set`` / ``--config``)
TRAIN_KEY_HELP: dict[str, str] = {
    "model": "The model to train (a name of wm.list_models(); swm train's MODEL).",
    "dataset": "Dataset in the cache to train on (a frame decoder defaults to its source run's).",
    "preset": "Sizes and recipe: tiny (CPU, minutes), cpu (LeWM, PLDM: the Push-T recipes for a CPU, under an hour), "
    "small (one GPU) or paper (upstream's).",
    "steps": "Optimizer steps (default: the preset's); on --resume, a larger value extends the run.",
    "epochs": "Passes over the train samples, instead of steps.",
    "batch_size": "Samples per step, the global batch under torchrun (default: the preset's).",
    "lr": "Peak learning rate (default: the preset's).",
    "device": "auto, cpu, cuda, cuda:N or mps.",
    "precision": "32, bf16 or 16 (16 needs CUDA).",
    "compile": "Run the training step through torch.compile (compiled on the first step: worth it for long runs).",
    "name": "Run name, its folder under $STABLEWM_HOME/checkpoints (default: <dataset>-<model>).",
    "seed": "Seed of the initial weights, the train/validation split and the batches.",
    "resume": "Continue the run of that name from its last checkpoint.",
    "init_from": "Start from this run's weights (fine-tuning; same model and sizes).",
    "cache_dir": "Cache folder of datasets and checkpoints (default: $STABLEWM_HOME).",
    "log_every": "Steps between two metrics records (train loss, learning rate, samples/s).",
    "val_every": "Steps between two validation losses (0: only at the end; default: a tenth of the run).",
    "ckpt_every": "Steps between two periodic checkpoints in step_<N>/ (0: only the last; default: a quarter).",
    "progress": "Show a progress bar (swm train: when stderr is a terminal).",
    "feature_cache": "Cache a frozen encoder's features on disk, once per dataset (false: encode every batch).",
    "eval_every": "Evaluate the checkpoint in the env every K steps and at the end; keep the best as RUN/best.",
    "eval_episodes": "Episodes per evaluation (with eval_every; default 10, under eval_protocol the protocol's).",
    "eval_protocol": "Evaluate under this protocol (upstream: swm eval --protocol upstream, from the run's "
    "validation episodes).",
    "eval_env": "The env to evaluate in (with eval_every; default: the dataset's).",
    "eval_plan": "Planner settings of the evaluations, a PlanSettings (Python API only).",
    "logger": "Where metrics go besides metrics.jsonl/.csv: tensorboard, wandb (TensorBoard and W&B) or none.",
    "wandb_project": "W&B project of the run with logger wandb (default: $WANDB_PROJECT or stable-worldmodel).",
    "protocol_extra": "Entries added to protocol.json and the W&B config (Python API; swm train --config uses it).",
}
#: :data:`TRAIN_KEY_HELP` keys that ``swm train --set`` / ``--config`` do not take (Python objects)
PYTHON_ONLY_KEYS = ("eval_plan", "protocol_extra")


class _NoLog:
    """The metrics log of processes other than 0 under distributed training: writes nothing."""

    closed = False
    wandb = None

    def log(self, record: dict[str, Any]) -> None:
        pass

    def read(self) -> list[dict[str, Any]]:
        return []

    def close(self, exit_code: int = 0) -> None:
        pass


def train(
    model: str,
    dataset: str | None,
    preset: str = "tiny",
    *,
    steps: int | None = None,
    epochs: float | None = None,
    batch_size: int | None = None,
    lr: float | None = None,
    device: str = "auto",
    precision: str = "32",
    compile: bool = False,
    name: str | None = None,
    seed: int = 0,
    resume: bool = False,
    init_from: str | None = None,
    cache_dir: str | None = None,
    log_every: int = 10,
    val_every: int | None = None,
    ckpt_every: int | None = None,
    progress: bool = True,
    feature_cache: bool = True,
    eval_every: int | None = None,
    eval_episodes: int | None = None,
    eval_env: str | None = None,
    eval_protocol: str | None = None,
    eval_plan: Any = None,
    logger: str = "tensorboard",
    wandb_project: str | None = None,
    protocol_extra: dict[str, Any] | None = None,
    **overrides: Any,
) -> TrainResult:
    """Train world model ``model`` (a name of ``stable_worldmodel.wm.list_models()``) on dataset ``dataset``.

    ``preset`` picks sizes and recipe (``tiny``, ``small``, ``paper``; LeWM and PLDM also ``cpu``); ``overrides``
    set any config field (``frameskip=5``, ``embed_dim=32`` ...; ``train("frame", None, source=RUN)``
    trains a frame decoder on RUN's latents and dataset, as run ``RUN-frame``). ``steps`` or ``epochs`` (passes over
    the train samples) bound the run (default: the preset's steps). The model, its config and
    ``protocol.json`` go to ``<cache>/checkpoints/<name>/`` (default name ``<dataset>-<model>``),
    with metrics (``metrics.jsonl``, ``metrics.csv``, TensorBoard events in ``tensorboard/``) and ``loss.png``.
    ``resume=True`` continues the run of that name from its last checkpoint (same result as
    an uninterrupted run) up to its planned steps, or to ``steps`` when more are given (the run
    is extended: its learning-rate schedule becomes the one planned for the new total, from the
    step it reached); otherwise an existing run folder is an error. ``init_from=RUN`` starts
    from run RUN's weights (fine-tuning; same model and sizes) instead of a fresh initialisation. Under ``torchrun
    --nproc-per-node N`` the run is data-parallel over N processes (:mod:`.distributed`;
    ``batch_size`` is the global batch). A model with a frozen
    encoder (PreJEPA) trains on its features, computed once per dataset and encoder and kept on
    disk (:mod:`stable_worldmodel.train.features`; ``feature_cache=False`` encodes every batch).
    ``eval_every=K`` evaluates the checkpoint every K steps and at the end: ``eval_episodes`` (10)
    seeded episodes of ``eval_env`` (default: the dataset's env) planned as ``swm eval`` plans
    (plain MPC, no subgoals; ``eval_plan``: other
    :class:`~stable_worldmodel.planning.learned.PlanSettings`), or with ``eval_protocol="upstream"``
    what ``swm eval --protocol upstream`` runs (its planner, seed, goal offset and budget; ``eval_episodes``
    default: its 50) from the run's validation episodes; the success rate and its 95% interval
    are logged (``eval/...``, with ``eval/train_seconds``, the training time so far: a success curve
    against training time) and the best checkpoint is kept as ``<run>/best`` (``swm eval --policy
    wm:RUN/best``).
    ``logger`` says where the metrics go besides ``metrics.jsonl`` / ``metrics.csv`` (always written):
    ``"tensorboard"`` (the default), ``"wandb"`` (TensorBoard and a Weights & Biases run named after
    the run, in project ``wandb_project``, continued by ``resume=True``; ``WANDB_MODE=offline`` logs
    without a network) or ``"none"``. ``protocol_extra`` entries are added to ``protocol.json`` (and the
    W&B config). What each argument means: :data:`TRAIN_KEY_HELP`.
    """
    from .._device import resolve_device
    from ..wm import get_config
    from ..wm import utils as wmu
    from . import distributed

    _positive("steps", steps)
    _positive("batch_size", batch_size)
    _positive("eval_every", eval_every)
    _positive("eval_episodes", eval_episodes)
    if eval_protocol is not None:
        from ..cli.evaluation import PROTOCOLS
        from ..errors import unknown_name

        if eval_protocol not in PROTOCOLS:
            raise unknown_name("evaluation protocol", eval_protocol, PROTOCOLS)
    check_int("train", "log_every", log_every)
    for key, value in (("val_every", val_every), ("ckpt_every", ckpt_every)):
        if value is not None:
            check_int("train", key, value, minimum=0)
    from .run import check_logger

    logger_name = check_logger(logger)
    if wandb_project is not None and (not isinstance(wandb_project, str) or not wandb_project.strip()):
        raise ConfigError(f"train requires wandb_project to be a non-empty name, got {wandb_project!r}")
    if protocol_extra is not None and not isinstance(protocol_extra, dict):
        raise ConfigError(f"train requires protocol_extra to be a dict, got {type(protocol_extra).__name__}")
    if epochs is not None and not (isinstance(epochs, (int, float)) and epochs > 0):
        raise ConfigError(f"train requires epochs > 0, got {epochs!r}")
    if steps is not None and epochs is not None:
        raise ConfigError("train requires steps or epochs, got both")
    if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
        raise ConfigError(f"train requires seed to be an int >= 0, got {seed!r}")
    if batch_size is not None:
        overrides["batch_size"] = batch_size
    if lr is not None:
        overrides["lr"] = lr
    cfg = get_config(model, preset, **overrides)
    derived = isinstance(cfg, DerivedFromRun)  # e.g. the frame decoder: built on another run
    if dataset is None:  # a frame decoder trains on its source run's dataset
        dataset = cfg.source_dataset if derived else None
        if not dataset:
            raise ConfigError(f"train requires a dataset name for {model!r}, got None")
    dist_info, dev = distributed.setup(resolve_device(device), cfg.batch_size)
    run = name or (cfg.default_run if derived else None) or f"{dataset}-{model}"
    if not run or "/" in run or "\\" in run or run.startswith("."):
        raise ConfigError(f"train requires a plain run name (no path), got {run!r}")
    folder = wmu.checkpoint_root(cache_dir) / run
    lock = lock_run(folder, run) if dist_info.is_main else None
    try:
        resume = _check_run_folder(folder, resume, run)
        distributed.barrier(dist_info)  # every process has checked before process 0 creates the folder
        return _train_locked(
            model=model,
            dataset=dataset,
            preset=preset,
            steps=steps,
            epochs=epochs,
            precision=precision,
            compile=compile,
            seed=seed,
            resume=resume,
            init_from=init_from,
            cache_dir=cache_dir,
            log_every=log_every,
            val_every=val_every,
            ckpt_every=ckpt_every,
            progress=progress,
            feature_cache=feature_cache,
            evaluation=(eval_every, eval_episodes, eval_env, eval_plan, eval_protocol) if eval_every else None,
            metrics_to=(logger_name, wandb_project),
            protocol_extra=protocol_extra or {},
            cfg=cfg,
            dist_info=dist_info,
            dev=dev,
            run=run,
            folder=folder,
        )
    finally:
        if lock is not None:
            lock.release()


def _evaluate_checkpoint(
    trainer: Any,
    *,
    env: str,
    episodes: int | None,
    seed: int,
    cache_dir: str | None,
    plan: Any = None,
    protocol: str | None = None,
) -> dict[str, Any]:
    """Plan with the run's latest checkpoint in ``env`` (``swm eval``'s defaults, no subgoals) for
    ``episodes`` seeded episodes (default 10), or under evaluation protocol ``protocol`` (``swm eval
    --protocol``: its knobs, from the run's validation episodes; ``episodes`` default: the protocol's);
    the success rate and its 95% interval, in percent (under a protocol also the ``starts``: dataset
    episode and step of each episode)."""
    import numpy as np

    from ..cli.stats import wilson_interval
    from ..planning.learned import PlanSettings, world_model_policy
    from ..planning.policies import episode_limit, make_world

    knobs: dict[str, Any] = {}
    if protocol is not None:
        from ..cli.evaluation import protocol_knobs

        knobs = protocol_knobs(protocol, env)
        seed = knobs["seed"]
        episodes = episodes or knobs["episodes"]
        plan_knobs = ("solver", "horizon", "receding_horizon", "samples", "iterations", "cost", "subgoals")
        settings = plan if plan is not None else PlanSettings(seed=seed, **{k: knobs[k] for k in plan_knobs})
    else:
        episodes = episodes or 10
        settings = plan if plan is not None else PlanSettings(seed=seed, subgoals="none")
    policy, run_protocol = world_model_policy(trainer.run, settings, device=str(trainer.device), cache_dir=cache_dir)
    size = int(run_protocol.get("image_size") or 64)
    if protocol is not None:
        from pathlib import Path

        from ..cli.evaluation import _from_dataset

        budget = knobs["budget"]
        with make_world(env, num_envs=min(10, episodes), image_size=size, max_steps=budget, seed=seed, verbose=0) as w:
            w.set_policy(policy)
            pool = trainer.protocol.get("val_episodes") or None  # the episodes this run never trains on
            path = Path(trainer.protocol["dataset_path"])
            results = _from_dataset(w, path, episodes, knobs["goal_offset"], budget, seed, pool)
    else:
        with make_world(
            env, num_envs=1, image_size=size, max_steps=episode_limit(env, None), seed=seed, verbose=0
        ) as world:
            world.set_policy(policy)
            results = world.evaluate(episodes=episodes, seed=seed)
    successes = int(np.asarray(results["episode_successes"], bool).sum())
    low, high = wilson_interval(successes, episodes)
    out = {"success_rate": 100.0 * successes / episodes, "ci95": [100.0 * low, 100.0 * high], "episodes": episodes}
    if protocol is not None:  # where each episode started: (dataset episode, step)
        out["starts"] = [[int(e), int(t)] for e, t in zip(results["episodes_idx"], results["start_steps"], strict=True)]
    return out


def _check_protocol_starts(data: Any, protocol: dict[str, Any], name: str, env: str) -> None:
    """Before training: evaluations under protocol ``name`` need held-out episodes longer than its goal offset."""
    import numpy as np

    from ..cli.evaluation import protocol_knobs

    offset = protocol_knobs(name, env)["goal_offset"]
    lengths = np.asarray(data.dataset.lengths)
    pool = protocol.get("val_episodes") or list(range(len(lengths)))
    longest = int(lengths[pool].max()) if len(pool) else 0
    if longest <= offset:
        raise ConfigError(
            f"train(eval_protocol={name!r}) requires validation episodes longer than the protocol's goal offset "
            f"({offset} steps on {env}), got at most {longest} rows; record longer episodes or drop eval_protocol"
        )


def _load_init_weights(net: Any, source: str, cache_dir: str | None) -> dict[str, Any]:
    """Load run ``source``'s weights into ``net`` (``init_from``); what the protocol records of it."""
    from ..wm.run import Run

    opened = Run.open(source, cache_dir)
    loaded = opened.load_model()
    try:
        net.load_state_dict(loaded.state_dict(), strict=True)
    except RuntimeError as exc:
        first = str(exc).strip().splitlines()[0]
        raise ConfigError(
            f"train(init_from={source!r}) requires a run of the same model and sizes, got {opened.protocol.model} "
            f"weights that do not fit ({first})"
        ) from exc
    return {"run": opened.name, "weights_sha256": opened.protocol.weights_sha256}


def _check_run_folder(folder: Any, resume: bool, run: str) -> bool:
    """Whether to resume: a run with a training state resumes (``resume``) or is an error (not
    ``resume``); a folder without any checkpoint (killed before its first one) starts again from step 0."""
    import shutil

    from .run import STATE_NAME

    has_state = (folder / STATE_NAME).is_file()
    has_weights = folder.is_dir() and any(folder.rglob("*.pt"))
    if resume and has_state:
        return True
    if resume and not folder.exists():  # no such run: likely a typo, not a run killed early
        from ..errors import did_you_mean

        runs = sorted(p.name for p in folder.parent.iterdir() if p.is_dir()) if folder.parent.is_dir() else []
        raise FileNotFoundError(
            f"Resuming (swm train --resume, train(resume=True)) requires a previous run with {folder / STATE_NAME}, "
            "which does not exist."
            f"{did_you_mean(run, runs)}"
        )
    if resume:
        if has_weights:
            raise FileNotFoundError(
                f"Resuming (swm train --resume, train(resume=True)) requires {folder / STATE_NAME} to continue run "
                f"{run!r}, which does not exist (the run holds weights but no training state); train under another "
                "name (--name)"
            )
        logger.warning("Run %r has no checkpoint to resume (%s): starting from step 0", run, folder)
    elif has_weights or has_state:
        raise FileExistsError(
            f"Run folder {folder} exists: continue it with swm train --resume (train(resume=True)), or pick "
            "another name (--name)"
        )
    if folder.exists():  # killed before its first checkpoint: nothing in it is worth keeping
        logger.info("Run folder %s holds no checkpoint: reusing it", folder)
        shutil.rmtree(folder)
    return False


def _train_locked(
    *,
    model,
    dataset,
    preset,
    steps,
    epochs,
    precision,
    compile,
    seed,
    resume,
    init_from,
    cache_dir,
    log_every,
    val_every,
    ckpt_every,
    progress,
    feature_cache,
    evaluation,
    metrics_to,
    protocol_extra,
    cfg,
    dist_info,
    dev,
    run,
    folder,
) -> TrainResult:
    import shutil

    import torch

    from ..wm import utils as wmu
    from . import distributed
    from .data import TrainData
    from .run import STATE_NAME, MetricsLog, load_train_state, provenance
    from .trainer import Trainer

    state_path = folder / STATE_NAME
    torch.manual_seed(seed)
    data = TrainData(dataset, cfg, seed=seed, device=dev, cache_dir=cache_dir)
    if epochs is not None:
        steps = max(1, math.ceil(epochs * data.num_train / cfg.batch_size))
    state = load_train_state(state_path, map_location=dev) if resume else None
    if state is not None:
        planned = int(state.get("steps", steps or cfg.steps))
        if steps is None:
            steps = planned  # resume to the run's own plan
        elif steps < planned:
            raise ConfigError(
                f"Resuming run {run!r} requires --steps at least its planned {planned} (extending it is allowed), "
                f"got {steps}"
            )
        elif steps > planned:
            logger.info("Extending run %r from %d to %d steps (from step %s)", run, planned, steps, state.get("step"))
    steps = steps or cfg.steps
    tree = cfg.target_tree(data.action_dim)
    torch.manual_seed(seed)
    net = wmu.instantiate(tree)
    if isinstance(cfg, DerivedFromRun):  # e.g. the frame decoder loads its source run
        cfg.prepare_model(net)
    init = _load_init_weights(net, init_from, cache_dir) if init_from is not None and state is None else None
    features = None
    frozen = isinstance(net, HasFrozenEncoder)
    # statistics of the data (a frozen encoder's standardization, Dreamer's mean frame) are learned here, once
    from .features import fit_frozen_encoder

    if fit_frozen_encoder(
        (net.frozen_encoder() if frozen else net).to(dev), data.dataset, data.train_episodes, cfg, dev
    ):
        logger.info("%s fitted to the training frames of %s", "Frozen encoder" if frozen else "Model", dataset)
    if feature_cache and frozen and not data.goals:
        from .features import load_or_compute_features

        if not dist_info.is_main:
            distributed.barrier(dist_info)  # process 0 computes the cache, the others read it
        features = load_or_compute_features(data.dataset, net.to(dev).encode_pixels, net.frozen_encoder(), cfg, dev)
        if dist_info.is_main:
            distributed.barrier(dist_info)
        data.use_features(features.features)
        logger.info("%s", features.describe())
    protocol = {
        "version": PROTOCOL_VERSION,
        "model": model,
        "preset": preset,
        "config": cfg.to_dict(),
        "seed": seed,
        "steps": steps,
        "frameskip": cfg.frameskip,
        "history_size": cfg.history_size,
        "num_preds": cfg.num_preds,
        "image_size": cfg.image_size,
        "image_mean": list(cfg.image_mean),
        "image_std": list(cfg.image_std),
        "precision": precision,
        **({"compile": True} if compile else {}),
        **data.protocol(),
        "final": None,  # set when the run ends: a run killed mid-way shows as partial
        "provenance": provenance(),  # versions, git commit, command line, host, start (and end) time
    }
    taken = sorted(set(protocol_extra) & (set(protocol) | {"logger", "wandb", "steps_done", "best"}))
    if taken:
        raise ConfigError(f"train requires protocol_extra keys that protocol.json does not use itself, got {taken}")
    protocol.update(protocol_extra)
    if init is not None:
        protocol["init_from"] = init
    if features is not None:
        protocol["feature_cache"] = {
            "file": str(features.path),
            "computed": features.computed,
            "seconds": round(features.seconds, 3),
        }
    val_every = val_every if val_every is not None else max(log_every, steps // 10)
    ckpt_every = ckpt_every if ckpt_every is not None else max(1, steps // 4)
    trainer = Trainer(
        net,
        data,
        cfg,
        folder=folder,
        run=run,
        device=dev,
        precision=precision,
        compile=compile,
        seed=seed,
        steps=steps,
        log_every=log_every,
        val_every=val_every,
        ckpt_every=ckpt_every,
        progress=progress,
        config_tree=tree,
        protocol=protocol,
        dist=dist_info,
    )
    if dist_info.enabled:
        protocol["distributed"] = {
            "processes": dist_info.world_size,
            "backend": "nccl" if dev.type == "cuda" else "gloo",
        }
    if dist_info.is_main:
        folder.mkdir(parents=True, exist_ok=True)
    if evaluation is not None:
        every, episodes, env, plan, eval_protocol = evaluation
        env = env or protocol.get("env")
        if not env:
            raise ConfigError(
                f"train(eval_every=...) requires an env to evaluate in: dataset {dataset!r} records none; pass eval_env"
            )
        if episodes is None:  # 10, or the protocol's number of starts
            from ..cli.evaluation import protocol_knobs

            episodes = protocol_knobs(eval_protocol, env)["episodes"] if eval_protocol is not None else 10
        from functools import partial

        trainer.evaluator = partial(
            _evaluate_checkpoint,
            env=env,
            episodes=episodes,
            seed=seed,
            cache_dir=cache_dir,
            plan=plan,
            protocol=eval_protocol,
        )
        trainer.eval_every = every
        protocol["evaluation"] = {"env": env, "every": every, "episodes": episodes, "seed": seed}
        if eval_protocol is not None:
            _check_protocol_starts(data, protocol, eval_protocol, env)
            protocol["evaluation"]["protocol"] = eval_protocol
    if state is not None:  # the trainer was built for `steps`: an extended run's schedule is the new total's
        trainer.load_state_dict(state)
    kind, project = metrics_to
    protocol["logger"] = kind
    log: Any = None
    try:
        if dist_info.is_main:
            log = MetricsLog.open(
                folder,
                resume_step=trainer.step if resume else None,
                logger=kind,
                name=run,
                project=project,
                config=_wandb_config(protocol, trainer) if kind == "wandb" else None,
            )
        else:
            log = _NoLog()
        if log.wandb is not None:
            protocol["wandb"] = {k: log.wandb[k] for k in ("id", "project", "mode", "url")}
        result = trainer.fit(log)
        result.features = features
        trainer.ddp = None  # DDP holds the process group: release it before leaving the group, not at exit
        distributed.cleanup(dist_info)
        return result
    except BaseException as exc:
        if log is not None:  # a W&B run finishes, marked failed (fit closed the log itself on a clean Ctrl-C)
            log.close(exit_code=130 if isinstance(exc, KeyboardInterrupt) else 1)
        if dist_info.is_main and not resume and trainer.step == 0 and not any(folder.glob("*.pt")):
            shutil.rmtree(folder, ignore_errors=True)  # nothing worth keeping
        raise


def _wandb_config(protocol: dict[str, Any], trainer: Any) -> dict[str, Any]:
    """The W&B run's config: the resolved model config, the training arguments and the provenance."""
    skip = ("config", "provenance", "train_episodes", "val_episodes", "final")
    return {
        "model_config": protocol.get("config"),
        "train": {
            **{k: v for k, v in protocol.items() if k not in skip},
            "log_every": trainer.log_every,
            "val_every": trainer.val_every,
            "ckpt_every": trainer.ckpt_every,
            "device": str(trainer.device),
        },
        "provenance": protocol.get("provenance"),
    }

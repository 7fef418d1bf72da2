"""Online training: act with the model being trained, train it on what it collected, repeat
(upstream's ``tdmpc2_online`` recipe, for any model with an actor).

The loop, on one :class:`~stable_worldmodel.world.World` and one
:class:`~stable_worldmodel.data.ReplayBuffer`:

1. ``seed_episodes`` episodes of random actions fill the buffer; the action (and extra column)
   normalizers are fitted on them once and kept, since the model learns in their units;
2. training runs as offline training does (same :class:`~.trainer.Trainer`: checkpoints,
   ``metrics.jsonl``, ``loss.png``, ``protocol.json``), sampling windows from the buffer;
3. every ``collect_every`` training steps, ``episodes_per_collect`` more episodes are collected
   with the model's actor (``model.get_action``: TD-MPC2's policy prior, a goal-conditioned
   policy), the buffer takes them in (the oldest evicted past ``buffer_steps``), and the mean
   return and success of those episodes are logged (``online/return``, ``online/success``).

Every collected episode is also committed, crash-safe, to ``replay.h5`` beside the checkpoint (the
run's dataset: it can be trained on offline, or evaluated from). ``resume=True`` continues a run
from its last checkpoint: the normalizers are fitted again on the same seed episodes and the
buffer is refilled with the file's last episodes (the collection after it is not bit-identical
to an uninterrupted run's: the actor's samples draw from torch's global stream).
``swm train MODEL --online ENV [--resume]`` runs it.
"""

from __future__ import annotations

import importlib
import logging
from typing import Any

import numpy as np

from .. import keys
from ..errors import ConfigError
from ..policy import BasePolicy

logger = logging.getLogger(__name__)

__all__ = ["ActorPolicy", "train_online"]

#: the run folder's copy of the replay buffer
REPLAY_FILE = "replay.h5"


class ActorPolicy(BasePolicy):
    """Acts in a World with a model's actor: the World's infos are preprocessed as the trainer
    preprocesses batches (images resized and normalized, extra columns normalized), the model
    gives a normalized action block ``(B, frameskip * A)``, which is mapped back to env actions
    and played one env step at a time. A new block is drawn when the last one is played out or
    when an env starts a new episode."""

    def __init__(self, model: Any, data: Any, cfg: Any, device: Any):
        super().__init__()
        self.type = "online"
        self.model, self.data, self.cfg, self.device = model, data, cfg, device
        self.queue: list[np.ndarray] = []

    def get_action(self, infos: dict, **kwargs: Any) -> np.ndarray:
        step = np.asarray(infos.get("step_idx", np.ones((1, 1))))[:, -1]
        if not self.queue or bool((step == 0).any()):
            self.queue = self._block(infos)
        return self.queue.pop(0)

    def _block(self, infos: dict) -> list[np.ndarray]:
        import torch

        from ..wm.preprocess import preprocess_images

        cfg, data = self.cfg, self.data
        frames = torch.from_numpy(np.ascontiguousarray(infos[keys.PIXELS][:, -cfg.history_size :]))
        b, t = frames.shape[:2]
        info: dict[str, Any] = {
            keys.PIXELS: preprocess_images(
                frames.permute(0, 1, 4, 2, 3).to(self.device), cfg.image_mean, cfg.image_std, cfg.image_size
            )
        }
        for key in data.extra_keys:
            values = torch.as_tensor(np.asarray(infos[key][:, -t:], dtype=np.float32), device=self.device)
            info[key] = data.extra_normalizers[key].torch(values.reshape(b, t, -1))
        if keys.GOAL in infos and data.goals:  # a goal-conditioned actor sees the episode's goal image
            goal = torch.from_numpy(np.ascontiguousarray(infos[keys.GOAL][:, -1:]))
            info[keys.GOAL] = preprocess_images(
                goal.permute(0, 1, 4, 2, 3).to(self.device), cfg.image_mean, cfg.image_std, cfg.image_size
            )
        with torch.no_grad():
            block = self.model.get_action(info)
        fs = cfg.frameskip
        normalized = block.detach().float().cpu().numpy().reshape(b * fs, -1)
        actions = data.normalizer.inverse_transform(normalized).reshape(b, fs, -1)
        space = self._require_env().action_space
        actions = np.clip(actions, space.low[:, None], space.high[:, None]).astype(space.dtype)
        return [actions[:, i] for i in range(fs)]


class _Tee:
    """The writer collection records into: the replay buffer (what training samples) and the run's
    ``replay.h5`` (every episode ever collected, committed crash-safe: what a resumed run reloads)."""

    def __init__(self, buffer: Any, writer: Any):
        self.buffer, self.writer = buffer, writer

    @property
    def next_seed(self) -> int | None:
        return self.writer.next_seed

    @property
    def num_episodes(self) -> int:
        return self.writer.num_episodes

    def write_episodes(self, episodes: list, next_seed: int | None = None) -> None:
        self.writer.write_episodes(episodes, next_seed=next_seed)  # on disk first: a kill keeps it
        self.buffer.write_episodes(episodes)


def _refill(buffer: Any, path: Any) -> int:
    """Put the last episodes of ``path`` (the run's replay file) into ``buffer``, oldest first, as
    many as it holds; returns the number of episodes in the file."""
    from ..data import HDF5Dataset

    replay = HDF5Dataset(path=path, preload=False)
    try:
        lengths, total, first = np.asarray(replay.lengths), 0, len(replay.lengths)
        while first > 0 and total + int(lengths[first - 1]) <= buffer.max_steps:
            first -= 1
            total += int(lengths[first])
        for ep in range(first, len(lengths)):
            o, n = int(replay.offsets[ep]), int(lengths[ep])
            buffer.write_episode({col: replay._read(col, o, o + n) for col in replay.stored_columns})
        return len(lengths)
    finally:
        replay.close()


def _first_episodes(path: Any, count: int) -> list[dict[str, np.ndarray]]:
    """The first ``count`` episodes of the replay file ``path`` (the seed episodes), as column -> rows."""
    from ..data import HDF5Dataset

    replay = HDF5Dataset(path=path, preload=False)
    try:
        out = []
        for ep in range(min(count, replay.num_episodes)):
            o, n = int(replay.offsets[ep]), int(replay.lengths[ep])
            out.append({col: replay._read(col, o, o + n) for col in replay.stored_columns})
        return out
    finally:
        replay.close()


def _episode_stats(buffer: Any, count: int) -> dict[str, float]:
    """Mean return and success (any ``terminated``) of the last ``count`` episodes of ``buffer``."""
    lengths, offsets = buffer.lengths[-count:], buffer.offsets[-count:]
    rewards = buffer.get_col_data(keys.REWARD).reshape(buffer.num_rows, -1).sum(-1)
    done = buffer.get_col_data("terminated").reshape(buffer.num_rows, -1).any(-1)
    returns = [float(np.nansum(rewards[o : o + n])) for o, n in zip(offsets, lengths, strict=True)]
    success = [bool(done[o : o + n].any()) for o, n in zip(offsets, lengths, strict=True)]
    return {"online/return": float(np.mean(returns)), "online/success": float(np.mean(success))}


def train_online(
    model: str,
    env: str,
    preset: str = "tiny",
    *,
    steps: int | None = None,
    batch_size: int | None = None,
    lr: float | None = None,
    seed_episodes: int = 8,
    collect_every: int = 100,
    episodes_per_collect: int = 2,
    buffer_steps: int = 100_000,
    num_envs: int = 1,
    max_episode_steps: int = 100,
    name: str | None = None,
    seed: int = 0,
    resume: bool = False,
    device: str = "auto",
    cache_dir: str | None = None,
    progress: bool = True,
    log_every: int = 10,
    ckpt_every: int | None = None,
    logger: str = "tensorboard",
    wandb_project: str | None = None,
    protocol_extra: dict[str, Any] | None = None,
    **overrides: Any,
) -> Any:
    """Train ``model`` online in ``env`` (module docstring); returns the
    :class:`~.trainer.TrainResult`. ``overrides`` set config fields as in
    :func:`~stable_worldmodel.train.train`; the run goes to ``<cache>/checkpoints/<name>/``
    (default ``<env name>-<model>-online``); ``logger``, ``wandb_project`` and ``protocol_extra`` as
    :func:`~stable_worldmodel.train.train`'s."""
    import torch

    from .. import World
    from .._device import resolve_device
    from ..data import ReplayBuffer
    from ..data.writer import ENV_ID_ATTR, HDF5Writer
    from ..errors import check_int
    from ..policy import RandomPolicy
    from ..wm import get_config
    from ..wm import utils as wmu
    from ..wm.base import Actor
    from ..wm.run import PROTOCOL_VERSION, lock_run
    from ..world.recording import record_episodes
    from . import _check_run_folder, _wandb_config
    from .data import TrainData
    from .run import STATE_NAME, MetricsLog, check_logger, load_train_state
    from .trainer import Trainer

    who = "train_online"
    for key, value in (
        ("seed_episodes", seed_episodes),
        ("collect_every", collect_every),
        ("episodes_per_collect", episodes_per_collect),
        ("buffer_steps", buffer_steps),
        ("num_envs", num_envs),
        ("max_episode_steps", max_episode_steps),
        ("log_every", log_every),
    ):
        check_int(who, key, value)
    if steps is not None:
        check_int(who, "steps", steps)
    check_logger(logger)
    if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
        raise ConfigError(f"{who} requires seed to be an int >= 0, got {seed!r}")
    if batch_size is not None:
        overrides["batch_size"] = check_int(who, "batch_size", batch_size)
    if lr is not None:
        overrides["lr"] = lr
    cfg = get_config(model, preset, **overrides)
    module, _, cls_name = str(getattr(cfg, "target", "")).rpartition(".")
    if not module or not callable(
        getattr(getattr(importlib.import_module(module), cls_name, None), "get_action", None)
    ):
        raise ConfigError(
            f"{who} requires a model with an actor (get_action), got {model!r}; "
            "train it offline on a recorded dataset instead (swm collect, then swm train)"
        )
    steps = steps or cfg.steps
    dev = resolve_device(device)
    run = name or f"{env.rpartition('/')[2]}-{model}-online"
    if not run or "/" in run or "\\" in run or run.startswith("."):
        raise ConfigError(f"{who} requires a plain run name (no path), got {run!r}")
    folder = wmu.checkpoint_root(cache_dir) / run
    lock = lock_run(folder, run)
    world = writer = log = None
    try:
        resume = _check_run_folder(folder, resume, run)
        size = (cfg.image_size, cfg.image_size)
        world = World(
            env, num_envs, size, max_episode_steps=max_episode_steps, verbose=0, history_size=cfg.history_size
        )
        folder.mkdir(parents=True, exist_ok=True)
        writer = HDF5Writer(folder / REPLAY_FILE, attrs={ENV_ID_ATTR: env})
        buffer = ReplayBuffer(buffer_steps, history_len=cfg.num_steps, frameskip=cfg.frameskip, seed=seed)
        sink = _Tee(buffer, writer)
        if resume:  # the normalizers are fitted on the same seed episodes, the buffer holds the last episodes
            seeds_only = ReplayBuffer(buffer_steps, history_len=cfg.num_steps, frameskip=cfg.frameskip)
            for episode in _first_episodes(folder / REPLAY_FILE, seed_episodes):
                seeds_only.write_episode(episode)
            _refill(buffer, folder / REPLAY_FILE)
            next_seed = int(writer.next_seed if writer.next_seed is not None else seed + writer.num_episodes)
        else:
            world.set_policy(RandomPolicy(seed=seed))
            record_episodes(world, sink, seed_episodes, seed, None, "Seed episodes", with_idx=False)
            next_seed = seed + seed_episodes
            seeds_only = buffer
        torch.manual_seed(seed)
        data = TrainData(f"online:{env}", cfg, seed=seed, device=dev, dataset=seeds_only)
        if seeds_only is not buffer:
            data.dataset = buffer
            data.refresh()
        tree = cfg.target_tree(data.action_dim)
        torch.manual_seed(seed)
        net = wmu.instantiate(tree)
        assert isinstance(net, Actor), type(net)  # checked on its class above
        net.to(dev)
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
            "precision": "32",
            **data.protocol(),
            "env": env,
            "dataset": f"{run}/{REPLAY_FILE}",
            "dataset_path": str(folder / REPLAY_FILE),
            "online": {
                "seed_episodes": seed_episodes,
                "collect_every": collect_every,
                "episodes_per_collect": episodes_per_collect,
                "buffer_steps": buffer_steps,
                "num_envs": num_envs,
                "max_episode_steps": max_episode_steps,
            },
            "final": None,
            "logger": logger,
        }
        protocol = {**(protocol_extra or {}), **protocol}  # its own entries win
        trainer = Trainer(
            net,
            data,
            cfg,
            folder=folder,
            run=run,
            device=dev,
            seed=seed,
            steps=steps,
            log_every=log_every,
            val_every=0,
            ckpt_every=ckpt_every if ckpt_every is not None else max(1, steps // 4),
            progress=progress,
            config_tree=tree,
            protocol=protocol,
        )
        if resume:
            state = load_train_state(folder / STATE_NAME, map_location=dev)
            if int(state.get("steps", steps)) != steps:
                raise ConfigError(
                    f"{who}(resume=True) requires the same number of steps as the run ({state.get('steps')}), "
                    f"got {steps}"
                )
            trainer.load_state_dict(state)
        log = MetricsLog.open(
            folder,
            resume_step=trainer.step if resume else None,
            logger=logger,
            name=run,
            project=wandb_project,
            config=_wandb_config(protocol, trainer) if logger == "wandb" else None,
        )
        if log.wandb is not None:
            protocol["wandb"] = {k: log.wandb[k] for k in ("id", "project", "mode", "url")}
        policy = ActorPolicy(net, data, cfg, dev)

        def collect(tr: Any) -> None:
            nonlocal next_seed
            if tr.step == 0 or tr.step % collect_every:
                return
            net.eval()
            world.set_policy(policy)
            policy.queue = []
            record_episodes(world, sink, episodes_per_collect, next_seed, None, "Collecting", with_idx=False)
            next_seed += episodes_per_collect
            net.train()
            data.refresh()
            stats = _episode_stats(buffer, episodes_per_collect)
            log.log({"step": tr.step, **stats, "online/episodes": buffer.num_episodes})
            logging.getLogger(__name__).info("step %d: %s", tr.step, stats)  # `logger` is the argument here

        trainer.before_step = collect
        return trainer.fit(log)
    except BaseException as exc:
        if log is not None:  # a W&B run finishes, marked failed (fit closed the log itself on a clean Ctrl-C)
            log.close(exit_code=130 if isinstance(exc, KeyboardInterrupt) else 1)
        raise
    finally:
        if writer is not None:
            writer.close()
        if world is not None:
            world.close()
        lock.release()

"""Stepping many envs: in-process (``sync``) or in worker processes (``async``).

Both paths run the same :class:`EnvGroup` code, so for the same seeds they give identical
results. Worker processes each own a contiguous slice of the envs and return their infos
already stacked, so the main process only concatenates a few arrays per step.
Autoreset never happens: an env is reset only when :meth:`VecEnv.reset_envs` asks.

Worker processes never outlive the VecEnv's process, a dead or failing worker raises
:class:`WorkerError` (naming the worker, its envs and the env id) and leaves the VecEnv closed,
and a script that would re-run in every worker is refused: see :mod:`._workers` for how, and
:mod:`.shm` for how the shared memory is freed.
"""

from __future__ import annotations

import atexit
import logging
import multiprocessing as mp
import os
import weakref
from collections.abc import Callable, Sequence
from functools import partial
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium.vector.utils import batch_space

from ..errors import ConfigError, WorkerError
from ._workers import WorkerPool, check_main_guard, get_context, guard_hint
from .batching import concat_batches, stack, stack_dicts
from .shm import ShmReader, unpack_result

__all__ = ["VecEnv", "EnvGroup", "WorkerError", "MODES"]

logger = logging.getLogger(__name__)

MODES = ("auto", "sync", "async")
# "auto" uses worker processes only where they pay: the built-in 2-D envs step in 0.1-0.3 ms,
# so the pipe round trip and the main process's own work (policy, batching) eat the gain
# unless there are enough envs *and* enough cores besides the main process's
# (bench/bench_world.py: on 2 cores, async == sync at 16 PushT envs and slower below).
AUTO_ASYNC_MIN_ENVS = 8
AUTO_ASYNC_MIN_CPUS = 4


class EnvGroup:
    """A list of envs stepped together; returns stacked results."""

    def __init__(self, factory: Callable[[], gym.Env], n: int):
        self.envs = [factory() for _ in range(n)]
        self.current: int | None = None  # the env being called, named in worker error reports

    def reset(self, ids: Sequence[int], seeds: Sequence[int | None], options: Sequence[dict | None]):
        obs, infos = [], []
        for i, seed, opt in zip(ids, seeds, options, strict=False):
            self.current = i
            o, info = self.envs[i].reset(seed=None if seed is None else int(seed), options=opt)
            obs.append(o)
            infos.append(info)
        return _stack_obs(obs), stack_dicts(infos)

    def step(self, actions: Sequence[Any]):
        obs, rewards, terms, truncs, infos = [], [], [], [], []
        for i, (env, action) in enumerate(zip(self.envs, actions, strict=False)):
            self.current = i
            o, r, te, tr, info = env.step(action)
            obs.append(o)
            rewards.append(r)
            terms.append(te)
            truncs.append(tr)
            infos.append(info)
        return (
            _stack_obs(obs),
            np.asarray(rewards, np.float64),
            np.asarray(terms, bool),
            np.asarray(truncs, bool),
            stack_dicts(infos),
        )

    def call(self, ids: Sequence[int], name: str, args_list: Sequence[tuple], kwargs_list: Sequence[dict]) -> list:
        out = []
        for i, args, kwargs in zip(ids, args_list, kwargs_list, strict=False):
            self.current = i
            attr = getattr(self.envs[i].unwrapped, name)
            out.append(attr(*args, **kwargs) if callable(attr) else attr)
        return out

    def spaces(self) -> dict[str, Any]:
        env = self.envs[0]
        return {
            "observation": env.observation_space,
            "action": env.action_space,
            "variation": [getattr(e.unwrapped, "variation_space", None) for e in self.envs],
            "env_id": getattr(env.spec, "id", None),
        }

    def close(self) -> None:
        for env in self.envs:
            env.close()


def _stack_obs(obs: list) -> Any:
    if obs and isinstance(obs[0], dict):
        return stack_dicts(obs)
    return stack([np.asarray(o) for o in obs])


class VecEnv:
    """``num_envs`` copies of one env, stepped together.

    Attributes follow Gymnasium's vector API: ``num_envs``, ``single_observation_space``,
    ``single_action_space``, ``observation_space`` and ``action_space`` (batched), plus
    ``sub_variation_spaces()``. ``call(name, ...)`` / ``call_each(name, args_list)`` call a
    method (or read an attribute) of each env's ``unwrapped`` env.
    """

    metadata: dict[str, Any] = {"autoreset_mode": "disabled"}

    def __init__(
        self,
        factory: Callable[[], gym.Env],
        num_envs: int,
        mode: str = "auto",
        num_workers: int | None = None,
        start_method: str | None = None,
    ):
        if mode not in MODES:
            raise ConfigError(f"VecEnv requires mode in {MODES}, got {mode!r}")
        methods = mp.get_all_start_methods()
        if start_method is not None and start_method not in methods:
            raise ConfigError(f"VecEnv requires start_method in {methods} (or None: automatic), got {start_method!r}")
        cpus = os.cpu_count() or 1
        if mode == "auto":
            mode = "async" if num_envs >= AUTO_ASYNC_MIN_ENVS and cpus >= AUTO_ASYNC_MIN_CPUS else "sync"
        self.mode = mode
        self.num_envs = int(num_envs)
        self.closed = False
        self._pool: WorkerPool | None = None
        self._atexit: Callable[[], None] | None = None
        self._closed_reason: str | None = None
        self._env_id: str | None = None
        if mode == "sync":
            self._local = EnvGroup(factory, self.num_envs)
            self._slices = [(0, self.num_envs)]
            spaces = self._local.spaces()
            self._variation = spaces["variation"]
        else:
            self._local = None
            self._start_workers(factory, min(num_workers or cpus, self.num_envs), start_method)
            spaces = self._spaces
        self.single_observation_space = spaces["observation"]
        self.single_action_space = spaces["action"]
        self.observation_space = batch_space(self.single_observation_space, self.num_envs)
        self.action_space = batch_space(self.single_action_space, self.num_envs)
        self.single_variation_space = self._variation[0] if self._variation else None
        self.variation_space = (
            batch_space(self.single_variation_space, self.num_envs) if self.single_variation_space is not None else None
        )
        self.render_mode = "rgb_array"

    # -- workers ------------------------------------------------------------------------
    def _start_workers(self, factory, n_workers: int, start_method: str | None) -> None:
        import cloudpickle

        ctx = get_context(start_method)
        check_main_guard(ctx.get_start_method())
        bounds = np.linspace(0, self.num_envs, n_workers + 1).round().astype(int)
        self._slices = [(int(a), int(b)) for a, b in zip(bounds[:-1], bounds[1:], strict=False)]
        self._reader = ShmReader()
        payload = cloudpickle.dumps(factory)
        self._pool = WorkerPool(ctx, [(EnvGroup, payload, b - a) for a, b in self._slices])
        # close gracefully at exit, before multiprocessing terminates its daemon workers
        self._atexit = partial(_close_at_exit, weakref.ref(self))
        atexit.register(self._atexit)
        try:
            replies = [cloudpickle.loads(self._reply(k, "start")) for k in range(len(self._slices))]
        except BaseException:
            self.close(terminate=True)
            raise
        self._env_id = replies[0]["env_id"]
        self._spaces = replies[0]
        self._variation = [v for reply in replies for v in reply["variation"]]

    @property
    def _procs(self) -> list:
        """The worker processes (empty in sync mode)."""
        return list(self._pool.procs) if self._pool is not None else []

    def _who(self, k: int) -> str:
        a, b = self._slices[k]
        envs = f"env {a}" if b - a == 1 else f"envs {a}-{b - 1}"
        of = f" of {self._env_id!r}" if self._env_id else ""
        return f"VecEnv worker {k} (pid {self._pool.procs[k].pid}, {envs}{of})"

    def _reply(self, k: int, cmd: str) -> Any:
        """Worker ``k``'s answer to ``cmd``; on a death or an error, close and raise WorkerError."""
        status, value = self._pool.recv(k)
        if status == "ok":
            return value
        if status == "died":
            hint = " " + guard_hint(self._pool.method) if cmd == "start" and self._pool.method != "fork" else ""
            raise self._fail(f"{self._who(k)} {value} during {cmd}.{hint}")
        env, trace = value
        if env is not None:
            what = f"env {self._slices[k][0] + env} raised in {cmd}"
        else:
            what = "failed to make its envs" if cmd == "start" else f"failed during {cmd}"
        raise self._fail(f"{self._who(k)}: {what}:\n{trace}")

    def _fail(self, message: str) -> WorkerError:
        self._closed_reason = message.splitlines()[0].rstrip(".")
        self.close(terminate=True)
        return WorkerError(message + "\nThe VecEnv is now closed.")

    def _check_usable(self) -> None:
        if self.closed:
            raise WorkerError(f"VecEnv is closed ({self._closed_reason}); make a new World or VecEnv")
        if os.getpid() != self._pool.owner:
            raise WorkerError(
                f"VecEnv workers belong to process {self._pool.owner}; a forked child cannot use them: "
                "make its own World there"
            )

    def _run(self, cmd: str, per_worker: list[tuple | None]) -> list:
        """Send ``cmd`` with its payload to the workers that have one; gather replies in order."""
        if self._local is not None:
            return [getattr(self._local, cmd)(*per_worker[0])] if per_worker[0] is not None else []
        self._check_usable()
        sent = [k for k, payload in enumerate(per_worker) if payload is not None]
        try:
            for k in sent:
                self._pool.send(k, (cmd, per_worker[k]))
            return [unpack_result(self._reader, cmd, self._reply(k, cmd)) for k in sent]
        except WorkerError:
            raise
        except BaseException:  # e.g. Ctrl-C: a reply may be half read, the pipes cannot be trusted
            self._closed_reason = f"interrupted during {cmd}"
            self.close(terminate=True)
            raise

    def _split(self, env_ids: Sequence[int], *columns: Sequence) -> list[tuple | None]:
        """Group per-env arguments by worker: ``[(local_ids, col1, col2, ...) | None, ...]``."""
        out: list[tuple | None] = []
        for a, b in self._slices:
            sel = [k for k, i in enumerate(env_ids) if a <= i < b]
            if not sel:
                out.append(None)
                continue
            out.append(tuple([[env_ids[k] - a for k in sel], *[[col[k] for k in sel] for col in columns]]))
        return out

    def _order(self, env_ids: Sequence[int]) -> np.ndarray:
        """Permutation from worker-grouped order back to the order of ``env_ids``."""
        grouped = [i for a, b in self._slices for i in env_ids if a <= i < b]
        position = {env: k for k, env in enumerate(grouped)}
        return np.array([position[i] for i in env_ids], dtype=np.intp)

    # -- public API ---------------------------------------------------------------------
    def check_ids(self, env_ids: Sequence[int]) -> list[int]:
        ids = [int(i) for i in env_ids]
        bad = [i for i in ids if not 0 <= i < self.num_envs]
        if bad or len(set(ids)) != len(ids):
            raise ConfigError(f"env ids must be distinct integers in [0, {self.num_envs}), got {list(env_ids)}")
        return ids

    def reset_envs(self, env_ids: Sequence[int], seeds: Sequence[int | None], options: Sequence[dict | None]):
        """Reset the envs ``env_ids``; returns (obs, infos) batched in the order of ``env_ids``."""
        ids = self.check_ids(env_ids)
        replies = self._run("reset", self._split(ids, seeds, options))
        order = self._order(ids)
        obs = _take(_concat_obs([r[0] for r in replies]), order)
        infos = _take(concat_batches([r[1] for r in replies]), order)
        return obs, infos

    def step(self, actions: Any):
        """Step every env with its row of ``actions``."""
        rows = [actions[i] for i in range(self.num_envs)]
        per_worker = [(rows[a:b],) for a, b in self._slices]
        replies = self._run("step", per_worker)
        obs = _concat_obs([r[0] for r in replies])
        rewards = np.concatenate([r[1] for r in replies])
        terms = np.concatenate([r[2] for r in replies])
        truncs = np.concatenate([r[3] for r in replies])
        infos = concat_batches([r[4] for r in replies])
        return obs, rewards, terms, truncs, infos

    def call(self, name: str, *args: Any, **kwargs: Any) -> list:
        """``getattr(env.unwrapped, name)(*args, **kwargs)`` on every env (attributes are read)."""
        n = self.num_envs
        return self.call_each(name, [args] * n, [kwargs] * n)

    def call_each(
        self, name: str, args_list: Sequence, kwargs_list: Sequence[dict] | None = None, env_ids=None
    ) -> list:
        """Like :meth:`call` with each env's own ``args_list[i]`` (a tuple, or one argument)."""
        ids = list(range(self.num_envs)) if env_ids is None else self.check_ids(env_ids)
        args_list = [a if isinstance(a, tuple) else (a,) for a in args_list]
        kwargs_list = list(kwargs_list) if kwargs_list is not None else [{}] * len(ids)
        if not len(args_list) == len(kwargs_list) == len(ids):
            raise ConfigError(f"call_each requires one argument entry per env ({len(ids)}), got {len(args_list)}")
        split = [None if p is None else (p[0], name, p[1], p[2]) for p in self._split(ids, args_list, kwargs_list)]
        replies = self._run("call", split)
        flat = [x for r in replies for x in r]
        return [flat[k] for k in self._order(ids)]

    def get_attr(self, name: str) -> tuple:
        return tuple(self.call(name))

    def sub_variation_spaces(self) -> list:
        return list(self._variation)

    @property
    def envs(self) -> list[gym.Env]:
        """The env objects (in-process mode only)."""
        if self._local is None:
            raise AttributeError("the envs live in worker processes (async mode); use call()/call_each()")
        return self._local.envs

    @property
    def unwrapped(self) -> VecEnv:
        return self

    def close(self, terminate: bool = False) -> None:
        """Close the envs and stop the workers (``terminate``: without asking them); idempotent."""
        if self.closed:
            return
        if self._local is not None:
            self.closed = True
            self._local.close()
            return
        if self._pool is None or os.getpid() != self._pool.owner:
            return  # not started, or a forked copy: the workers belong to the process that started them
        self.closed = True
        self._closed_reason = self._closed_reason or "close() was called"
        if self._atexit is not None:
            atexit.unregister(self._atexit)
        self._pool.close(graceful=not terminate)
        self._reader.close()

    def __del__(self):
        try:
            self.close()
        except Exception:  # interpreter shutdown
            pass


def _close_at_exit(ref: weakref.ref) -> None:
    vec = ref()
    if vec is not None:
        vec.close()


def _concat_obs(parts: list) -> Any:
    if parts and isinstance(parts[0], dict):
        return concat_batches(parts)
    return np.concatenate(parts) if len(parts) > 1 else parts[0]


def _take(batch: Any, order: np.ndarray) -> Any:
    if np.array_equal(order, np.arange(len(order))):
        return batch
    if isinstance(batch, dict):
        return {k: v[order] for k, v in batch.items()}
    return batch[order]

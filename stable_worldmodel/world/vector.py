"""Stepping many envs: in-process (``sync``) or in worker processes (``async``).

Both paths run the same :class:`EnvGroup` code, so for the same seeds they give identical
results. Worker processes each own a contiguous slice of the envs and return their infos
already stacked, so the main process only concatenates a few arrays per step.
Autoreset never happens: an env is reset only when :meth:`VecEnv.reset_envs` asks.
"""

from __future__ import annotations

import atexit
import logging
import multiprocessing as mp
import os
import sys
import traceback
import weakref
from collections.abc import Callable, Sequence
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium.vector.utils import batch_space

from ..errors import ConfigError
from .batching import concat_batches, stack_dicts

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

    def reset(self, ids: Sequence[int], seeds: Sequence[int | None], options: Sequence[dict | None]):
        obs, infos = [], []
        for i, seed, opt in zip(ids, seeds, options):
            o, info = self.envs[i].reset(seed=None if seed is None else int(seed), options=opt)
            obs.append(o)
            infos.append(info)
        return _stack_obs(obs), stack_dicts(infos)

    def step(self, actions: Sequence[Any]):
        obs, rewards, terms, truncs, infos = [], [], [], [], []
        for env, action in zip(self.envs, actions):
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
        for i, args, kwargs in zip(ids, args_list, kwargs_list):
            attr = getattr(self.envs[i].unwrapped, name)
            out.append(attr(*args, **kwargs) if callable(attr) else attr)
        return out

    def spaces(self) -> dict[str, Any]:
        env = self.envs[0]
        return {
            "observation": env.observation_space,
            "action": env.action_space,
            "variation": [getattr(e.unwrapped, "variation_space", None) for e in self.envs],
        }

    def close(self) -> None:
        for env in self.envs:
            env.close()


def _stack_obs(obs: list) -> Any:
    if obs and isinstance(obs[0], dict):
        return stack_dicts(obs)
    return np.stack([np.asarray(o) for o in obs])


def _pack(writer, cmd: str, result: Any) -> Any:
    """Route the large arrays of a reset/step result through shared memory."""
    if cmd == "reset":
        return (writer.pack(0, result[0]), writer.pack(1, result[1]))
    if cmd == "step":
        return (writer.pack(2, result[0]), *result[1:4], writer.pack(3, result[4]))
    return result


def _unpack(reader, cmd: str, result: Any) -> Any:
    if cmd == "reset":
        return (reader.unpack(result[0]), reader.unpack(result[1]))
    if cmd == "step":
        return (reader.unpack(result[0]), *result[1:4], reader.unpack(result[4]))
    return result


def _worker(conn, factory_bytes: bytes, n: int) -> None:
    import cloudpickle

    from .shm import ShmWriter

    writer = ShmWriter()
    try:
        group = EnvGroup(cloudpickle.loads(factory_bytes), n)
        conn.send(("ok", cloudpickle.dumps(group.spaces())))
    except BaseException:  # report construction errors to the parent, then quit
        conn.send(("error", traceback.format_exc()))
        conn.close()
        return
    while True:
        try:
            cmd, payload = conn.recv()
        except (EOFError, KeyboardInterrupt):
            break
        if cmd == "close":
            group.close()
            writer.close()
            conn.send(("ok", None))
            break
        try:
            conn.send(("ok", _pack(writer, cmd, getattr(group, cmd)(*payload))))
        except BaseException:
            conn.send(("error", traceback.format_exc()))
    writer.close()
    conn.close()


def _context() -> mp.context.BaseContext:
    # fork is fast and safe while no threaded runtime (torch) is loaded in the parent
    if sys.platform.startswith("linux") and "torch" not in sys.modules:
        return mp.get_context("fork")
    return mp.get_context("forkserver" if sys.platform != "win32" else "spawn")


class VecEnv:
    """``num_envs`` copies of one env, stepped together.

    Attributes follow Gymnasium's vector API: ``num_envs``, ``single_observation_space``,
    ``single_action_space``, ``observation_space`` and ``action_space`` (batched), plus
    ``sub_variation_spaces()``. ``call(name, ...)`` / ``call_each(name, args_list)`` call a
    method (or read an attribute) of each env's ``unwrapped`` env.
    """

    metadata: dict[str, Any] = {"autoreset_mode": "disabled"}

    def __init__(self, factory: Callable[[], gym.Env], num_envs: int, mode: str = "auto", num_workers: int | None = None):
        if mode not in MODES:
            raise ConfigError(f"VecEnv requires mode in {MODES}, got {mode!r}")
        cpus = os.cpu_count() or 1
        if mode == "auto":
            mode = "async" if num_envs >= AUTO_ASYNC_MIN_ENVS and cpus >= AUTO_ASYNC_MIN_CPUS else "sync"
        self.mode = mode
        self.num_envs = int(num_envs)
        self.closed = False
        if mode == "sync":
            self._local = EnvGroup(factory, self.num_envs)
            self._slices = [(0, self.num_envs)]
            spaces = self._local.spaces()
            self._variation = spaces["variation"]
        else:
            self._local = None
            self._start_workers(factory, min(num_workers or cpus, self.num_envs))
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
    def _start_workers(self, factory, n_workers: int) -> None:
        import cloudpickle

        from .shm import ShmReader

        self._reader = ShmReader()
        payload = cloudpickle.dumps(factory)
        bounds = np.linspace(0, self.num_envs, n_workers + 1).round().astype(int)
        self._slices = [(int(a), int(b)) for a, b in zip(bounds[:-1], bounds[1:])]
        ctx = _context()
        self._conns, self._procs = [], []
        for a, b in self._slices:
            parent, child = ctx.Pipe()
            proc = ctx.Process(target=_worker, args=(child, payload, b - a), daemon=True)
            proc.start()
            child.close()
            self._conns.append(parent)
            self._procs.append(proc)
        # close gracefully at exit, before multiprocessing terminates its daemon workers (which
        # would leave their shared memory to the resource tracker)
        atexit.register(_close_at_exit, weakref.ref(self))
        replies = [self._recv(c) for c in self._conns]
        variation = []
        for reply in replies:
            spaces = cloudpickle.loads(reply)
            variation.extend(spaces["variation"])
        self._spaces = spaces
        self._variation = variation

    def _recv(self, conn) -> Any:
        status, value = conn.recv()
        if status != "ok":
            self.close(terminate=True)
            raise RuntimeError(f"an environment worker failed:\n{value}")
        return value

    def _run(self, cmd: str, per_worker: list[tuple | None]) -> list:
        """Send ``cmd`` with its payload to the workers that have one; gather replies in order."""
        if self._local is not None:
            return [getattr(self._local, cmd)(*per_worker[0])] if per_worker[0] is not None else []
        sent = []
        for conn, payload in zip(self._conns, per_worker):
            if payload is not None:
                conn.send((cmd, payload))
                sent.append(conn)
        return [_unpack(self._reader, cmd, self._recv(conn)) for conn in sent]

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

    def call_each(self, name: str, args_list: Sequence, kwargs_list: Sequence[dict] | None = None, env_ids=None) -> list:
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
        if self.closed:
            return
        self.closed = True
        if self._local is not None:
            self._local.close()
            return
        for conn, proc in zip(self._conns, self._procs):
            try:
                if not terminate and proc.is_alive():
                    conn.send(("close", ()))  # the worker unlinks its shared memory and exits
                    if conn.poll(5.0):
                        conn.recv()
            except (BrokenPipeError, EOFError, OSError):
                pass
            conn.close()
        for proc in self._procs:
            if terminate:  # forked siblings hold copies of each other's pipes: no EOF to wait for
                proc.terminate()
            proc.join(timeout=2)
            if proc.is_alive():
                proc.kill()
                proc.join()
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

"""Env worker processes that never outlive the process that started them.

How a worker notices that its parent is gone (SIGKILL, SIGTERM, ``os._exit``, a crash):

- **Lifeline pipe** (every platform). A :class:`WorkerPool` makes one pipe and keeps its write
  end; nothing is ever written to it. Each worker blocks on the read end in a daemon thread, so
  it sees EOF as soon as the last write end closes, which happens when the parent dies, even
  while the worker's main thread is inside a long ``env.step``. The worker then unlinks its
  shared memory and exits.
- **Only the parent holds those write ends.** A fork copies every descriptor, so a worker forked
  later (or any later ``os.fork`` of the parent: a DataLoader worker, another pool) would keep
  the lifeline open. An ``os.register_at_fork`` hook closes, in every forked child, the lifeline
  write ends and the parent ends of the command pipes of every pool of this process; children
  that exec never get them (Python opens both close-on-exec).
- **PR_SET_PDEATHSIG** (Linux, an extra). The kernel sends SIGTERM to the worker when its parent
  dies, which also covers a parent whose descriptors leaked to a child forked outside Python.
  Linux ties it to the *thread* that forked, so it is armed only when the pool is started from
  the main thread (or by the forkserver, whose one thread lives as long as our process).
- In a worker, SIGTERM unlinks the worker's shared memory and then ends the worker by that same
  signal; SIGINT is ignored, so that on Ctrl-C the parent decides (it raises and closes the pool).

Shared memory (see :mod:`.shm`): the parent unlinks each block right after mapping it, a worker
unlinks the blocks nobody mapped yet when it exits (normally or by the paths above), and the
parent removes whatever still carries the pool's name prefix when it closes the pool (on Linux,
which lists them in /dev/shm; this covers a worker killed by SIGKILL). A block can only outlive
us if a worker and its parent are both killed by SIGKILL while that block is written but unread.

Start methods: ``fork`` on Linux while :func:`fork_is_safe` (no torch or jax imported, no GL
context made by :class:`~stable_worldmodel.envs.mujoco_render.MjRenderer`; fast: nothing is imported again,
so a script without an ``if __name__ == "__main__":`` guard works), else ``forkserver``
(``spawn`` on Windows). Those two import the main script again in the children, so an unguarded
script would run once more per child: :func:`check_main_guard` refuses to start workers from
such a script, in the parent and before any process starts, with a message that shows the
guard. If a child still reaches a VecEnv while it re-imports the main module, it raises the same
error there, and the parent reports that the worker died while starting.
"""

from __future__ import annotations

import ast
import multiprocessing as mp
import os
import signal
import sys
import threading
import traceback
import weakref
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from multiprocessing.connection import Connection, wait
from pathlib import Path
from typing import Any

from ..errors import WorkerError
from .shm import ShmWriter, new_prefix, pack_result, sweep

STOP = "close"  # the command after which a worker replies once and returns
PR_SET_PDEATHSIG = 1  # from <linux/prctl.h>


# -- the parent's private descriptors -----------------------------------------------------
_PARENT_ONLY: weakref.WeakSet[Connection] = weakref.WeakSet()
_hook_installed = False


def _close_parent_only() -> None:
    """In a forked child: close the descriptors that only the parent may hold."""
    for conn in list(_PARENT_ONLY):
        conn.close()
    _PARENT_ONLY.clear()


def _parent_only(conn: Connection) -> Connection:
    global _hook_installed
    if not _hook_installed and hasattr(os, "register_at_fork"):
        os.register_at_fork(after_in_child=_close_parent_only)
        _hook_installed = True
    _PARENT_ONLY.add(conn)
    return conn


# -- start method and the main-module guard -----------------------------------------------
def get_context(start_method: str | None = None) -> mp.context.BaseContext:
    if start_method is not None:
        return mp.get_context(start_method)
    if sys.platform.startswith("linux") and fork_is_safe():
        return mp.get_context("fork")
    return mp.get_context("forkserver" if sys.platform != "win32" else "spawn")


#: runtimes that start native threads: a forked child inherits their locks but not their threads
THREADED_RUNTIMES = ("torch", "jax")


def fork_is_safe() -> bool:
    """Whether a forked child can use what this process has started: not after a threaded runtime
    is imported, nor after a GL context drew a frame (Mesa's software rasterizer threads do not
    survive a fork, so a child that renders would wait for them for ever)."""
    if any(name in sys.modules for name in THREADED_RUNTIMES):
        return False
    render = sys.modules.get("stable_worldmodel.envs.mujoco_render")
    return render is None or not render.gl_started()


def guard_hint(method: str) -> str:
    return (
        f"With the {method!r} start method each worker imports the main script again, so code outside "
        'an `if __name__ == "__main__":` block runs once more in every worker. Put the script\'s code '
        'under that guard (or in a function called from it), or use vectorization_mode="sync".'
    )


def check_main_guard(method: str) -> None:
    """Raise :class:`WorkerError` where starting workers would run the main script again."""
    if getattr(mp.current_process(), "_inheriting", False):  # the flag multiprocessing itself checks
        raise WorkerError(
            "VecEnv cannot start workers while this process is importing the main script as a worker. "
            + guard_hint(method)
        )
    if method == "fork":
        return
    site = _main_script_call_site()
    if site is not None and _inside_main_guard(*site) is False:
        path, line = site
        raise WorkerError(
            f'VecEnv workers require the main script to start them under `if __name__ == "__main__":`, '
            f"got an unguarded call at {path}:{line}. " + guard_hint(method)
        )


def _main_script_call_site() -> tuple[str, int] | None:
    """(path, line) of the main script's module-level statement that led here, if the children
    will re-import that script (multiprocessing leaves a package's ``__main__`` and scripts
    without a file alone)."""
    main = sys.modules.get("__main__")
    spec_name = getattr(getattr(main, "__spec__", None), "name", None)
    if spec_name is not None and (spec_name == "__main__" or spec_name.endswith(".__main__")):
        return None
    path = getattr(main, "__file__", None)
    if path is None:  # interactive, ``python -c``, notebooks
        return None
    frame = sys._getframe(1)
    while frame is not None:
        if frame.f_globals is main.__dict__ and frame.f_code.co_name == "<module>":
            return str(path), frame.f_lineno
        frame = frame.f_back
    return None


def _inside_main_guard(path: str, line: int) -> bool | None:
    """Whether ``line`` lies in an ``if __name__ == "__main__":`` block; None when unreadable."""
    try:
        tree = ast.parse(Path(path).read_bytes(), filename=path)
    except (OSError, SyntaxError, ValueError):
        return None
    for node in ast.walk(tree):
        if isinstance(node, ast.If) and node.lineno <= line <= (node.end_lineno or node.lineno):
            names = {n.id for n in ast.walk(node.test) if isinstance(n, ast.Name)}
            values = {n.value for n in ast.walk(node.test) if isinstance(n, ast.Constant)}
            if "__name__" in names and "__main__" in values:
                return True
    return False


# -- worker side --------------------------------------------------------------------------
@dataclass
class ParentWatch:
    """What a worker needs to notice its parent's death; see the module docstring."""

    lifeline: Connection
    parent_pid: int | None  # to catch a parent that died before PR_SET_PDEATHSIG was armed
    death_signal: bool

    def start(self, on_exit: Callable[[], None]) -> None:
        """In the worker's main thread: from now on, run ``on_exit`` then end the process when
        the parent dies or on SIGTERM. ``on_exit`` must not return control to other code."""

        def exit_now(signum: int | None = None, frame: Any = None) -> None:
            try:
                on_exit()
            finally:
                if signum is not None:
                    signal.signal(signum, signal.SIG_DFL)
                    os.kill(os.getpid(), signum)
                os._exit(1)

        signal.signal(signal.SIGINT, signal.SIG_IGN)
        signal.signal(signal.SIGTERM, exit_now)
        threading.Thread(target=self._wait_for_eof, args=(exit_now,), name="swm-parent-watch", daemon=True).start()
        if self.death_signal:
            _arm_death_signal(signal.SIGTERM, self.parent_pid)

    def _wait_for_eof(self, exit_now: Callable[[], None]) -> None:
        try:
            self.lifeline.recv_bytes()  # the parent never writes: this returns only at EOF
        except (EOFError, OSError):
            pass
        exit_now()


def _arm_death_signal(sig: int, parent_pid: int | None) -> None:
    if not sys.platform.startswith("linux"):
        return
    import ctypes

    try:
        if ctypes.CDLL(None, use_errno=True).prctl(PR_SET_PDEATHSIG, int(sig), 0, 0, 0) != 0:
            return
    except (OSError, AttributeError):
        return
    if parent_pid is not None and os.getppid() != parent_pid:
        os.kill(os.getpid(), sig)  # the parent died before the signal was armed


def worker_main(conn: Connection, watch: ParentWatch, shm_prefix: str, group_cls: type, factory_bytes: bytes, n: int):
    """A worker process: ``group_cls(factory, n)`` (an :class:`EnvGroup`) answers
    ``(command, payload)`` messages with ``("ok", result)`` or ``("error", (env, traceback))``."""
    import cloudpickle

    writer = ShmWriter(shm_prefix)
    watch.start(on_exit=writer.abandon)
    try:
        try:
            group = group_cls(cloudpickle.loads(factory_bytes), n)
        except BaseException:  # report construction errors to the parent, then quit
            conn.send(("error", (None, traceback.format_exc())))
            return
        conn.send(("ok", cloudpickle.dumps(group.spaces())))
        _serve(conn, group, writer)
    except OSError:  # the parent's end of the pipe is gone: nobody to report to
        pass
    finally:
        writer.close()
        conn.close()


def _serve(conn: Connection, group: Any, writer: ShmWriter) -> None:
    while True:
        try:
            cmd, payload = conn.recv()
        except EOFError:  # the parent closed our pipe without a STOP
            return
        if cmd == STOP:
            group.close()
            writer.close()
            conn.send(("ok", None))
            return
        try:
            group.current = None
            result = getattr(group, cmd)(*payload)
            group.current = None  # from here on, a failure is not the env's
            conn.send(("ok", pack_result(writer, cmd, result)))
        except BaseException:  # the env's error goes to the parent, which then closes the pool
            conn.send(("error", (group.current, traceback.format_exc())))


# -- parent side --------------------------------------------------------------------------
class WorkerPool:
    """Daemon processes running :func:`worker_main` ``(conn, watch, shm_prefix, *args)``, one per ``args``.

    Messages are ``(command, payload)`` tuples; :meth:`recv` returns the worker's reply, or
    ``("died", how)`` if the worker died first. Worker ``k``'s shared-memory blocks are named
    ``f"{shm_prefix}{k}_<n>"``, so that :meth:`close` can find what is left of them.
    """

    def __init__(self, ctx: mp.context.BaseContext, args: Sequence[tuple]):
        self.owner = os.getpid()
        self.method = ctx.get_start_method()
        self.shm_prefix = new_prefix()
        self.conns: list[Connection] = []
        self.procs: list[mp.process.BaseProcess] = []
        lifeline, self._lifeline = ctx.Pipe(duplex=False)
        _parent_only(self._lifeline)
        from_server = self.method == "forkserver"
        watch = ParentWatch(
            lifeline,
            parent_pid=None if from_server else os.getpid(),
            death_signal=from_server or threading.current_thread() is threading.main_thread(),
        )
        try:
            for k, extra in enumerate(args):
                parent, child = ctx.Pipe()
                self.conns.append(_parent_only(parent))
                worker_args = (child, watch, f"{self.shm_prefix}{k}_", *extra)
                proc = ctx.Process(target=worker_main, args=worker_args, name=f"swm-env-worker-{k}", daemon=True)
                try:
                    proc.start()
                except (OSError, EOFError) as exc:  # e.g. a forkserver that died importing the main script
                    raise WorkerError(
                        f"VecEnv could not start worker {k} with the {self.method!r} start method ({exc!r}). "
                        + guard_hint(self.method)
                    ) from exc
                finally:
                    child.close()
                self.procs.append(proc)
        except BaseException:
            self.close(graceful=False)
            raise
        finally:
            lifeline.close()

    def send(self, k: int, message: tuple) -> None:
        """Send to worker ``k``; a dead worker is reported by the next :meth:`recv`."""
        try:
            self.conns[k].send(message)
        except OSError:
            pass

    def recv(self, k: int) -> tuple[str, Any]:
        conn, proc = self.conns[k], self.procs[k]
        if conn in wait([conn, proc.sentinel]):
            try:
                return conn.recv()
            except (EOFError, OSError):
                pass
        proc.join(timeout=1.0)
        return "died", exit_text(proc.exitcode)

    def close(self, graceful: bool = True) -> None:
        """Stop the workers (``graceful``: ask each to close its envs first), then free what they
        left in shared memory. Does nothing in a forked copy of the owner."""
        if os.getpid() != self.owner:
            return
        for conn, proc in zip(self.conns, self.procs, strict=False):
            if not graceful or not proc.is_alive():
                continue
            try:
                conn.send((STOP, ()))
                if conn.poll(5.0):
                    conn.recv()
            except (EOFError, OSError):
                pass
        for proc in self.procs:
            if proc.is_alive() and not graceful:
                proc.terminate()  # the worker unlinks its blocks, then dies by SIGTERM
        for proc in self.procs:
            proc.join(timeout=2)
            if proc.is_alive():
                proc.kill()
                proc.join()
        for conn in self.conns:
            conn.close()
        self._lifeline.close()
        sweep(self.shm_prefix)


def exit_text(code: int | None) -> str:
    if code is None:
        return "stopped answering"
    if code < 0:
        try:
            return f"was killed by signal {signal.Signals(-code).name}"
        except ValueError:
            return f"was killed by signal {-code}"
    return f"exited with code {code}"

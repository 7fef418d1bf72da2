"""Env worker processes: they die with their parent, a dead or failing worker is a typed error that
closes the VecEnv, shared memory never outlives them, and unguarded scripts are refused where the
start method would run them again. Linux only (they read /proc and /dev/shm)."""

from __future__ import annotations

import json
import multiprocessing as mp
import os
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest

import stable_worldmodel as swm
from stable_worldmodel.errors import SWMError
from stable_worldmodel.policy import RandomPolicy
from stable_worldmodel.world.vector import VecEnv, WorkerError

pytestmark = pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc and /dev/shm")

TOY = "swm/Toy-v0"
SHAPE = (128, 128)  # large enough that pixels and goal go through shared memory (shm.MIN_BYTES)


def alive(pid: int) -> bool:
    """A zombie counts as dead: nothing may reap orphans in a container."""
    try:
        stat = Path(f"/proc/{pid}/stat").read_text()
    except (FileNotFoundError, ProcessLookupError):
        return False
    return stat.rsplit(")", 1)[1].split()[0] not in ("Z", "X")


def wait_gone(pids, timeout: float = 5.0) -> list[int]:  # about 0.1 s when the machine is idle
    """The pids still alive after ``timeout`` seconds."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline and any(alive(p) for p in pids):
        time.sleep(0.02)
    return [p for p in pids if alive(p)]


def shm_names(prefix: str) -> list[str]:
    return sorted(n for n in os.listdir("/dev/shm") if n.startswith(prefix))


def run_script(tmp_path: Path, body: str, *args: str, name: str = "script.py") -> subprocess.Popen:
    path = tmp_path / name
    path.write_text(textwrap.dedent(body))
    return subprocess.Popen(
        [sys.executable, str(path), *args],
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        cwd=tmp_path,
        start_new_session=True,  # its own process group, which the "group" case kills
    )


# -- the parent dies ----------------------------------------------------------------------
PARENT = """
import json, os, sys, threading, time
import gymnasium as gym
import numpy as np
import stable_worldmodel as swm

SLOW = 0.25  # an action whose step lasts a minute


class Slow(gym.Wrapper):
    def step(self, action):
        if np.isclose(action[0], SLOW):
            time.sleep(60)
        return self.env.step(action)


def make():
    return swm.World(
        "swm/Toy-v0", num_envs=2, image_shape=(128, 128), vectorization_mode="async", verbose=0, extra_wrappers=[Slow]
    )


def step_unread(vec, action):
    for k in range(len(vec._procs)):
        vec._pool.send(k, ("step", ([np.full(2, action, np.float32)],)))


how, where = sys.argv[1], sys.argv[2]
out = {"pids": [], "prefixes": [], "names": [], "mapped": 0, "bystander": None}
if where == "thread":  # two Worlds made by a thread that then ends: no PR_SET_PDEATHSIG
    worlds = []
    maker = threading.Thread(target=lambda: worlds.extend([make(), make()]))
    maker.start()
    maker.join()
    out["bystander"] = os.fork()  # a later fork (a DataLoader worker, say) must not hold the lifelines
    if out["bystander"] == 0:
        quiet = os.open(os.devnull, os.O_WRONLY)
        os.dup2(quiet, 1)  # let go of the test's pipes
        os.dup2(quiet, 2)
        time.sleep(60)
        os._exit(0)
else:
    worlds = [make()]
for world in worlds:
    world.reset(seed=0)  # the workers outlive the thread that started them
    vec = world.envs
    out["mapped"] += len(vec._reader._blocks)  # the reset's pixels and goal, read and so unlinked
    out["pids"] += [p.pid for p in vec._procs]
    out["prefixes"].append(vec._pool.shm_prefix)
    if where == "group":  # all die at once: only blocks already read can be freed
        continue
    if where == "thread" and world is worlds[0]:
        step_unread(vec, SLOW)  # busy in env.step: only the lifeline thread can notice the parent's death
        continue
    step_unread(vec, 0.0)  # the workers make shared memory that this process never maps
    deadline = time.monotonic() + 15
    while time.monotonic() < deadline:
        names = [n for n in os.listdir("/dev/shm") if n.startswith(vec._pool.shm_prefix)]
        if len(names) == 4:  # pixels and goal of each worker's step
            break
        time.sleep(0.01)
    out["names"] += names
print(json.dumps(out), flush=True)
if how == "os._exit":
    sys.stdin.readline()  # the test has seen the workers alive
    os._exit(3)
time.sleep(60)
"""


@pytest.mark.parametrize(
    "how, where",
    [("SIGKILL", "main"), ("SIGTERM", "main"), ("os._exit", "main"), ("SIGKILL", "thread"), ("SIGKILL", "group")],
)
def test_workers_and_shared_memory_go_with_their_parent(tmp_path, how, where):
    """``group``: SIGKILL to the parent and its workers at once (``kill -9 -PGID``, a job scheduler)."""
    proc = run_script(tmp_path, PARENT, how, where)
    info = {}
    try:
        line = proc.stdout.readline()
        assert line, proc.stderr.read()
        info = json.loads(line)
        assert all(alive(p) for p in info["pids"])
        assert info["mapped"] == 4 * len(info["prefixes"])
        assert len(info["names"]) == (0 if where == "group" else 4)  # unread blocks, before the parent dies
        if where == "group":
            os.killpg(proc.pid, signal.SIGKILL)
        elif how == "os._exit":
            proc.stdin.write("exit now\n")
            proc.stdin.flush()
        else:
            proc.send_signal(getattr(signal, how))
        proc.wait(timeout=10)
        assert wait_gone(info["pids"]) == []
        assert [n for prefix in info["prefixes"] for n in shm_names(prefix)] == []
        assert "Traceback" not in proc.stderr.read()
    finally:
        proc.kill()
        proc.wait()
        if info.get("bystander"):
            os.kill(info["bystander"], signal.SIGKILL)


# -- a worker dies or fails ---------------------------------------------------------------
def make_world(**kw):
    world = swm.World(TOY, num_envs=2, image_shape=SHAPE, vectorization_mode="async", verbose=0, **kw)
    world.set_policy(RandomPolicy(seed=0))
    world.reset(seed=0)
    return world


def assert_closed_and_freed(world, pids, prefix):
    assert world.envs.closed
    assert wait_gone(pids) == []
    assert shm_names(prefix) == []
    with pytest.raises(WorkerError, match="VecEnv is closed"):
        world.step()
    with pytest.raises(WorkerError, match="VecEnv is closed"):
        world.reset(seed=0)


@pytest.mark.parametrize("sig", [signal.SIGKILL, signal.SIGTERM])
def test_a_killed_worker_is_a_typed_error_naming_it_and_closes_the_world(sig):
    world = make_world()
    pids, prefix = [p.pid for p in world.envs._procs], world.envs._pool.shm_prefix
    world.step()
    os.kill(pids[1], sig)
    expected = rf"worker 1 \(pid {pids[1]}, env 1 of 'swm/Toy-v0'\) was killed by signal {sig.name} during step"
    with pytest.raises(WorkerError, match=expected) as err:
        world.step()
    assert isinstance(err.value, SWMError) and isinstance(err.value, RuntimeError)
    assert_closed_and_freed(world, pids, prefix)
    world.close()  # still idempotent


def test_close_removes_the_blocks_a_killed_worker_left_unread():
    import numpy as np

    world = make_world()
    vec = world.envs
    pid, prefix = vec._procs[1].pid, vec._pool.shm_prefix
    vec._pool.send(1, ("step", ([np.zeros(2, np.float32)],)))  # its reply is never read
    deadline = time.monotonic() + 15
    while len(shm_names(f"{prefix}1_")) < 2 and time.monotonic() < deadline:
        time.sleep(0.01)
    assert len(shm_names(f"{prefix}1_")) == 2  # pixels and goal of the unread step
    os.kill(pid, signal.SIGKILL)  # no chance to unlink them itself
    assert wait_gone([pid]) == []
    world.close()
    assert shm_names(prefix) == []


class _ExplodingReset:
    """Wrapper factory: the env raises when reset with seed 13."""

    def __call__(self, env):
        import gymnasium as gym

        class Exploding(gym.Wrapper):
            def reset(self, *, seed=None, options=None):
                if seed == 13:
                    raise ValueError("boom in reset")
                return self.env.reset(seed=seed, options=options)

        return Exploding(env)


def test_an_env_raising_in_a_worker_names_worker_env_and_id_and_closes_the_world():
    world = make_world(extra_wrappers=[_ExplodingReset()])
    pids, prefix = [p.pid for p in world.envs._procs], world.envs._pool.shm_prefix
    with pytest.raises(WorkerError, match=r"worker 1 .*env 1 of 'swm/Toy-v0'\): env 1 raised in reset") as err:
        world.reset_envs([1], seeds=[13])
    assert "ValueError: boom in reset" in str(err.value)
    assert_closed_and_freed(world, pids, prefix)


def test_an_interrupted_wait_closes_the_world_instead_of_leaving_replies_half_read(monkeypatch):
    world = make_world()
    pids, prefix = [p.pid for p in world.envs._procs], world.envs._pool.shm_prefix

    def interrupted(k):
        raise KeyboardInterrupt

    monkeypatch.setattr(world.envs._pool, "recv", interrupted)
    with pytest.raises(KeyboardInterrupt):
        world.step()
    assert_closed_and_freed(world, pids, prefix)


def test_an_env_that_cannot_be_made_is_a_worker_error():
    def broken():
        raise RuntimeError("no such simulator")

    with pytest.raises(WorkerError, match=r"worker 0 \(pid \d+, env 0\): failed to make its envs") as err:
        VecEnv(broken, 2, mode="async", num_workers=2)
    assert "RuntimeError: no such simulator" in str(err.value)


def test_a_forked_child_cannot_close_or_use_its_parents_workers():
    world = make_world()
    pid = os.fork()
    if pid == 0:  # the child: its copy must leave the parent's workers alone, at close and at exit
        code = 3
        try:
            world.close()  # a no-op here
            world.step()
            code = 1
        except WorkerError as exc:
            code = 0 if "forked child" in str(exc) else 2
        finally:
            os._exit(code)
    _, status = os.waitpid(pid, 0)
    assert os.waitstatus_to_exitcode(status) == 0
    world.step()  # the workers still answer
    world.close()


# -- scripts without an `if __name__ == "__main__":` guard --------------------------------
UNGUARDED = """
import sys
from stable_worldmodel.envs.toy import ToyEnv
from stable_worldmodel.world.vector import VecEnv

print("START", flush=True)
vec = VecEnv(ToyEnv, 2, mode="async", start_method=None if sys.argv[1] == "default" else sys.argv[1])
vec.reset_envs([0, 1], [0, 1], [None, None])
print("AFTER", flush=True)
vec.close()
"""


@pytest.mark.parametrize("method", ["forkserver", "spawn"])
def test_an_unguarded_script_is_refused_before_it_runs_again(tmp_path, method):
    proc = run_script(tmp_path, UNGUARDED, method)
    out, err = proc.communicate(timeout=30)
    assert proc.returncode == 1
    assert out.count("START") == 1 and "AFTER" not in out  # refused in the parent: nothing ran twice
    assert "WorkerError" in err and 'if __name__ == "__main__":' in err and "script.py:7" in err


def test_an_unguarded_script_runs_once_with_fork(tmp_path):
    # fork (the default on Linux without torch) re-imports nothing: the script just works
    proc = run_script(tmp_path, UNGUARDED, "fork")
    out, err = proc.communicate(timeout=30)
    assert proc.returncode == 0, err
    assert out.split() == ["START", "AFTER"]


GUARDED = """
import sys
from stable_worldmodel.envs.toy import ToyEnv
from stable_worldmodel.world.vector import VecEnv

def main():
    print("START", flush=True)
    vec = VecEnv(ToyEnv, 2, mode="async", start_method="spawn")
    obs, _ = vec.reset_envs([0, 1], [0, 1], [None, None])
    print("AFTER", obs["state"].shape, flush=True)
    vec.close()

if __name__ == "__main__":
    main()
"""


def test_a_guarded_script_starts_spawned_workers(tmp_path):
    proc = run_script(tmp_path, GUARDED)
    out, err = proc.communicate(timeout=60)
    assert proc.returncode == 0, err
    assert out.split() == ["START", "AFTER", "(2,", "2)"]


def test_a_worker_importing_the_main_script_refuses_to_start_workers(monkeypatch):
    # what a spawned child sees if the parent's check could not read the script
    monkeypatch.setattr(mp.current_process(), "_inheriting", True, raising=False)
    with pytest.raises(WorkerError, match='if __name__ == "__main__":'):
        VecEnv(lambda: None, 2, mode="async")


def test_start_method_is_validated():
    from stable_worldmodel.errors import ConfigError

    with pytest.raises(ConfigError, match="start_method"):
        VecEnv(lambda: None, 2, mode="async", start_method="thread")


def test_fork_is_not_chosen_after_torch_jax_or_a_gl_context(monkeypatch):
    from stable_worldmodel.envs import mujoco_render
    from stable_worldmodel.world import _workers

    clean = {k: v for k, v in sys.modules.items() if k not in _workers.THREADED_RUNTIMES}
    monkeypatch.setattr(sys, "modules", clean)
    monkeypatch.setattr(mujoco_render, "_GL_STARTED", [])
    assert _workers.fork_is_safe()
    monkeypatch.setitem(sys.modules, "jax", object())
    assert not _workers.fork_is_safe()
    del sys.modules["jax"]
    monkeypatch.setattr(mujoco_render, "_GL_STARTED", [True])
    assert not _workers.fork_is_safe()
    assert _workers.get_context().get_start_method() != "fork"


RENDERED_FIRST = """
import sys
import stable_worldmodel as swm
from stable_worldmodel.policy import RandomPolicy

def main():
    for n in (1, 2):  # the first World renders in this process, the second starts workers
        world = swm.World("swm/OGBMaze-v0", num_envs=n, image_shape=(16, 16), verbose=0, render_quality="low")
        world.set_policy(RandomPolicy(seed=0))
        world.reset(seed=0)
        world.step()
        print(n, world.infos["pixels"].shape, flush=True)
        world.close()
    print("torch" in sys.modules, flush=True)

if __name__ == "__main__":
    main()
"""


def test_workers_started_after_a_gl_context_render_instead_of_hanging(tmp_path):
    # a forked child inherits the GL driver's locks but not its threads: it waited for ever
    pytest.importorskip("ogbench")
    proc = run_script(tmp_path, RENDERED_FIRST)
    try:
        out, err = proc.communicate(timeout=120)
    finally:
        os.killpg(proc.pid, signal.SIGKILL) if proc.poll() is None else None
    assert proc.returncode == 0, err
    lines = out.splitlines()
    assert lines[0].startswith("1 ") and lines[1].startswith("2 ") and lines[2] == "False"

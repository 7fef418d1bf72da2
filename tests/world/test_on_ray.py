"""Collection and evaluation on a local Ray (2 CPUs): sharded datasets read as one and equal a
single-process recording, a SIGKILLed worker followed by a re-run completes the dataset without
duplicates, and Ray evaluation equals a single-process one."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import threading
import time
from pathlib import Path

import numpy as np
import pytest

import stable_worldmodel as swm
from stable_worldmodel.data.hdf5 import HDF5Dataset
from stable_worldmodel.errors import ConfigError
from stable_worldmodel.world import on_ray

ray = pytest.importorskip("ray")
TOY = "swm/Toy-v0"


@pytest.fixture(scope="module")
def local_ray(tmp_path_factory):
    root = Path(tempfile_dir := str(tmp_path_factory.mktemp("r")))
    on_ray.init_ray(num_cpus=2, cache_dir=tempfile_dir)
    yield root
    ray.shutdown()


def _single(
    cache: Path, name: str, episodes: int, seed: int, policy: str = "expert", max_steps: int = 20
) -> HDF5Dataset:
    with swm.World(TOY, 1, (16, 16), max_episode_steps=max_steps, verbose=0) as world:
        world.set_policy(swm.envs.expert_policy(TOY) if policy == "expert" else swm.policy.RandomPolicy(seed=seed))
        world.record_dataset(name, episodes=episodes, seed=seed, cache_dir=cache)
    return HDF5Dataset(name, cache_dir=cache)


def _columns_equal(a: HDF5Dataset, b: HDF5Dataset) -> None:
    assert a.column_names == b.column_names and list(a.lengths) == list(b.lengths)
    for col in b.column_names:
        np.testing.assert_array_equal(a.get_col_data(col), b.get_col_data(col), err_msg=col)


def test_sharded_dataset_equals_the_single_process_recording(local_ray, tmp_path):
    folder = on_ray.record_dataset_on_ray(
        TOY, "toy", 7, seed=3, shards=3, image_size=16, max_steps=20, cache_dir=tmp_path, progress=False
    )
    assert sorted(p.name for p in folder.glob("shard_*.h5")) == ["shard_00000.h5", "shard_00001.h5", "shard_00002.h5"]
    manifest = json.loads((folder / "manifest.json").read_text())
    assert [(s["seed"], s["episodes"]) for s in manifest["shards"]] == [(3, 3), (6, 2), (8, 2)]
    sharded = HDF5Dataset("toy", cache_dir=tmp_path)
    _columns_equal(sharded, _single(tmp_path, "one", 7, 3))
    assert sharded.get_col_data("ep_idx")[-1] == 6  # episode numbers count across shards
    # windows across a shard boundary read the same as in the single file
    a = HDF5Dataset("toy", cache_dir=tmp_path, num_steps=2, preload=False)
    b = HDF5Dataset("one", cache_dir=tmp_path, num_steps=2, preload=False)
    assert len(a) == len(b)
    for i in range(len(b)):
        np.testing.assert_array_equal(a[i]["pixels"], b[i]["pixels"])

    # a re-run records nothing more; other settings under the same name are refused
    mtimes = [p.stat().st_mtime_ns for p in sorted(folder.glob("shard_*.h5"))]
    on_ray.record_dataset_on_ray(
        TOY, "toy", 7, seed=3, shards=5, image_size=16, max_steps=20, cache_dir=tmp_path, progress=False
    )
    assert [p.stat().st_mtime_ns for p in sorted(folder.glob("shard_*.h5"))] == mtimes
    with pytest.raises(ConfigError, match="same settings, got seed: 3 on disk, 4 now"):
        on_ray.record_dataset_on_ray(
            TOY, "toy", 7, seed=4, image_size=16, max_steps=20, cache_dir=tmp_path, progress=False
        )


def _worker_pids(marker: str) -> list[int]:
    out = subprocess.run(["ps", "-eo", "pid,args"], capture_output=True, text=True).stdout
    return [int(line.split()[0]) for line in out.splitlines() if marker in line]


def test_a_killed_worker_loses_at_most_its_episode_and_a_rerun_completes(local_ray, tmp_path):
    """Random-policy episodes run to the step limit (slow enough to kill a worker mid-shard)."""
    args = dict(seed=0, policy="random", shards=2, image_size=16, max_steps=150, cache_dir=tmp_path, progress=False)
    errors: list[BaseException] = []

    def run():
        try:
            on_ray.record_dataset_on_ray(TOY, "slow", 8, max_retries=0, **args)
        except BaseException as exc:  # the killed task's error reaches the driver
            errors.append(exc)

    thread = threading.Thread(target=run)
    thread.start()
    shard = tmp_path / "slow" / "shard_00000.h5"
    deadline = time.monotonic() + 60
    killed = False
    while time.monotonic() < deadline and not killed:
        if shard.exists() and on_ray._shard_done(shard) >= 1:
            pids = _worker_pids("_record_shard")
            for pid in pids[:1]:
                os.kill(pid, signal.SIGKILL)
                killed = True
        time.sleep(0.02)
    thread.join(timeout=120)
    assert killed and errors, "no worker was killed mid-collection"
    partial = sum(on_ray._shard_done(p) for p in (tmp_path / "slow").glob("shard_*.h5"))
    assert 1 <= partial < 8  # what was committed before the kill is readable
    HDF5Dataset("slow", cache_dir=tmp_path)

    on_ray.record_dataset_on_ray(TOY, "slow", 8, **args)  # the re-run completes it
    ds = HDF5Dataset("slow", cache_dir=tmp_path)
    assert ds.num_episodes == 8
    assert sorted(set(ds.get_col_data("ep_idx").tolist())) == list(range(8))
    # every seed 0..7 exactly once: the first state of each episode is its seed's start state
    starts = ds.get_col_data("state")[np.asarray(ds.offsets)]
    ref = _single(tmp_path, "ref", 8, 0, policy="random", max_steps=1)
    np.testing.assert_array_equal(starts, ref.get_col_data("state")[np.asarray(ref.offsets)])


def test_evaluation_on_ray_equals_a_single_process_run(local_ray):
    out = on_ray.evaluate_on_ray(TOY, "expert", 7, 10, image_size=16, max_steps=20, progress=False)
    with swm.World(TOY, 3, (16, 16), max_episode_steps=20, verbose=0) as world:
        world.set_policy(swm.envs.expert_policy(TOY))
        ref = world.evaluate(episodes=7, seed=10)
    assert out["episode_successes"] == np.asarray(ref["episode_successes"]).tolist()
    assert out["episode_lengths"] == np.asarray(ref["episode_lengths"]).tolist()


def test_a_private_ray_stays_inside_the_project(local_ray, tmp_path):
    assert os.environ["RAY_USAGE_STATS_ENABLED"] == "0" and os.environ["RAY_AUTH_MODE"] == "disabled"
    assert any((local_ray / "ray").glob("session_*"))  # its session files are under the cache folder
    assert on_ray.ray_temp_dir("/c") == Path("/c/ray").resolve()
    long = tmp_path / ("x" * 60)
    assert on_ray.ray_temp_dir(long).name.startswith("swm-ray-")  # too long for Ray's sockets
    assert on_ray.shard_plan(5, 10, 8) == [{"shard": k, "seed": 10 + k, "episodes": 1} for k in range(5)]


def test_swm_collect_and_eval_with_ray(local_ray, swm, _stablewm_home, error_line):
    result = swm(
        "collect",
        TOY,
        "-n",
        "3",
        "--policy",
        "expert",
        "--name",
        "tr",
        "--ray",
        "--image-size",
        "16",
        "--max-steps",
        "20",
    )
    assert result.exit_code == 0, result.output
    assert "on Ray to" in result.stdout and HDF5Dataset("tr").num_episodes == 3
    listed = swm("list", "dataset")
    assert "tr" in listed.stdout and "shard_" not in listed.stdout  # the shards are one dataset
    out = _stablewm_home / "e.json"
    result = swm("eval", TOY, "-n", "4", "--policy", "expert", "--ray", "--image-size", "16", "--json", str(out))
    assert result.exit_code == 0, result.output
    record = json.loads(out.read_text())
    assert record["ray"] == "local" and record["success_rate"] == 100.0 and len(record["episode_successes"]) == 4
    bad = swm("collect", TOY, "-n", "3", "--ray", "--num-envs", "2")
    assert bad.exit_code != 0 and "each Ray task runs one env" in error_line(bad)


SWEEP = """envs: [swm/Toy-v0]
policies: [expert]
factors: [none, agent.speed, [agent, goal], all]
episodes: 5
num_envs: 2
max_steps: 20
image_size: 16
"""


def test_swm_sweep_file_on_ray_equals_the_single_process_sweep(local_ray, swm, tmp_path, error_line):
    (tmp_path / "s.yaml").write_text(SWEEP)
    results = {}
    for how in ((), ("--ray",)):
        out = tmp_path / ("ray" if how else "one") / "s.json"
        result = swm("sweep", str(tmp_path / "s.yaml"), "--json", str(out), *how)
        assert result.exit_code == 0, result.output
        data = json.loads(out.read_text())
        (env,) = data["envs"]
        assert env["settings"] == ["in distribution", "agent.speed", "agent+goal", "all factors"]
        results[how] = [(r["setting"], r["episode_successes"]) for r in env["results"]["expert"]]
        assert (out.parent / "sweep-Toy-v0.png").is_file()
    assert results[()] == results[("--ray",)] and data["protocol"]["ray"] == "local"
    (tmp_path / "bad.yaml").write_text("envs: [swm/Toy-v0]\npolicys: [expert]\n")
    bad = swm("sweep", str(tmp_path / "bad.yaml"))
    assert bad.exit_code != 0 and "unknown key 'policys'. Did you mean 'policies'" in error_line(bad)
    (tmp_path / "bad2.yaml").write_text("envs: [swm/Toy-v0]\npolicies: [expert]\nfactors: [agnt]\n")
    bad = swm("sweep", str(tmp_path / "bad2.yaml"))
    assert bad.exit_code != 0 and "Did you mean" in error_line(bad) and "'agent'" in error_line(bad)


def test_an_evaluation_task_reads_checkpoints_from_the_drivers_cache(tmp_path, monkeypatch):
    """A worker of an existing cluster does not inherit the driver's STABLEWM_HOME: the task is given it."""
    import os

    from stable_worldmodel.planning import policies as worlds
    from stable_worldmodel.world.on_ray import _evaluate_chunk

    seen = []
    monkeypatch.setenv("STABLEWM_HOME", str(tmp_path / "worker_default"))
    monkeypatch.setattr(
        worlds,
        "evaluate_policy",
        lambda world, policy, *a, **k: (
            seen.append(os.environ["STABLEWM_HOME"]) or {"episode_successes": [True], "episode_lengths": [3]}
        ),
    )
    out = _evaluate_chunk("swm/Toy-v0", "random", [0], 16, 5, [], None, "cpu", str(tmp_path / "driver"))
    assert seen == [str(tmp_path / "driver")] and out == {"episode_successes": [True], "episode_lengths": [3]}

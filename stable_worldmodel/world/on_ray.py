"""Collection and evaluation spread over Ray: across the cores of one machine or a cluster.

**Collection** (``swm collect ... --ray [ADDRESS]``, :func:`record_dataset_on_ray`): the
episodes are split by seed into shards; one Ray task records each shard with one env into
``<cache>/<name>/shard_<k>.h5`` (episode ``j`` of the dataset keeps seed ``seed + j``), and
``HDF5Dataset("<name>")`` reads the shards as one dataset, in seed order: the same episodes as
``World(env, 1).record_dataset(name, episodes, seed)`` for a deterministic policy (a stochastic
policy's random stream is seeded per shard). The split is written to ``<name>/manifest.json``
first and reused by every later run, and each shard commits episode by episode: a killed worker
loses at most its episode in flight, and re-running the same command records only what is
missing, without duplicates.

**Evaluation** (``swm eval ... --ray``, :func:`evaluate_on_ray`): the seeds are split into
chunks, one task evaluates each chunk, and the outcomes are put back in seed order: for a
deterministic policy the same per-episode results as a single-process run with the same seeds.

**A Ray we start ourselves** (no ``ADDRESS``) stays on this machine and inside the project: bound
to 127.0.0.1, no dashboard, no usage statistics, no token file in the home folder, its temporary
files under the cache folder (``<cache>/ray``; a short folder under the system temp dir when that
path is too long for Ray's sockets).
"""

from __future__ import annotations

import hashlib
import json
import os
import tempfile
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import ConfigError

#: Ray's unix sockets live under its temp dir: paths longer than this leave them too little room
MAX_TEMP_DIR = 40
MANIFEST = "manifest.json"
#: seconds to wait for a cluster at ``HOST:PORT`` to accept a connection
RAY_CONNECT_TIMEOUT = 5.0


def ray_temp_dir(cache_dir: str | os.PathLike | None = None) -> Path:
    """Where a Ray we start keeps its session files: ``<cache>/ray`` when short enough."""
    from ..data.utils import get_cache_dir

    root = Path(cache_dir) if cache_dir is not None else Path(get_cache_dir())
    here = root.resolve() / "ray"
    if len(str(here)) <= MAX_TEMP_DIR:
        return here
    digest = hashlib.sha1(str(here).encode()).hexdigest()[:10]
    return Path(tempfile.gettempdir()) / f"swm-ray-{digest}"


def init_ray(
    address: str | None = None, *, num_cpus: int | None = None, cache_dir: str | os.PathLike | None = None
) -> Any:
    """Connect to the Ray cluster at ``address``, or start a private local one (see the module doc).

    Does nothing when Ray is already initialised in this process. Returns the ``ray`` module.
    """
    for key, value in (
        ("RAY_USAGE_STATS_ENABLED", "0"),
        ("RAY_AUTH_MODE", "disabled"),
        ("RAY_ENABLE_WINDOWS_OR_OSX_CLUSTER", "0"),
    ):
        os.environ.setdefault(key, value)
    from .._optional import require

    ray = require("ray", "ray", purpose="--ray")
    if ray.is_initialized():
        return ray
    if address:
        why = _unreachable(address)  # Ray itself waits for ever on a HOST:PORT where nothing listens
        if why is None:
            try:
                ray.init(address=address, log_to_driver=False, configure_logging=False)
                return ray
            except ConnectionError as exc:  # 'auto' and no cluster: "Could not find any running Ray instance..."
                why = " ".join(str(exc).split()) or type(exc).__name__
        raise ConfigError(
            f"--ray-address requires a running Ray cluster, got {address!r} where none answers ({why}); start one "
            f"with `ray start --head` (then --ray-address auto), or drop --ray-address to use a private local Ray"
        )
    temp = ray_temp_dir(cache_dir)
    temp.mkdir(parents=True, exist_ok=True)
    ray.init(
        num_cpus=num_cpus,
        include_dashboard=False,
        _temp_dir=str(temp),
        _node_ip_address="127.0.0.1",
        log_to_driver=False,
        configure_logging=False,
    )
    return ray


def _unreachable(address: str, timeout: float = RAY_CONNECT_TIMEOUT) -> str | None:
    """Why nothing accepts a connection at ``address`` (``HOST:PORT``, or ``ray://HOST:PORT``), within
    ``timeout`` seconds; None when something does, or when ``address`` is not of that form (``auto``)."""
    import socket

    host, sep, port = address.split("://", 1)[-1].rpartition(":")
    if not sep or not host or not port.isdigit():
        return None
    try:
        with socket.create_connection((host.strip("[]"), int(port)), timeout=timeout):
            return None
    except OSError as exc:
        return f"{host}:{port}: {exc.strerror or exc}"


# -- collection ----------------------------------------------------------------------------------
def shard_plan(episodes: int, seed: int, shards: int) -> list[dict[str, int]]:
    """Split ``episodes`` (seeds ``seed ..``) into ``shards`` contiguous, near-equal seed ranges."""
    sizes = [len(c) for c in np.array_split(np.arange(episodes), min(shards, episodes))]
    starts = np.cumsum([0, *sizes[:-1]])
    return [
        {"shard": k, "seed": int(seed + s), "episodes": int(n)}
        for k, (s, n) in enumerate(zip(starts, sizes, strict=False))
    ]


def _manifest(folder: Path, spec: dict[str, Any], shards: int) -> dict[str, Any]:
    """The split of a sharded recording: read back when it exists (it must match ``spec``), else written."""
    path = folder / MANIFEST
    if path.exists():
        manifest = json.loads(path.read_text())
        differs = {k: (manifest.get(k), v) for k, v in spec.items() if manifest.get(k) != v}
        if differs:
            what = ", ".join(f"{k}: {old!r} on disk, {new!r} now" for k, (old, new) in differs.items())
            raise ConfigError(
                f"swm collect --ray resumes {folder} only with the same settings, got {what}; pick another --name"
            )
        return manifest
    manifest = {**spec, "shards": shard_plan(spec["episodes"], spec["seed"], shards)}
    folder.mkdir(parents=True, exist_ok=True)
    tmp = path.with_suffix(".tmp")
    tmp.write_text(json.dumps(manifest, indent=2) + "\n")
    os.replace(tmp, path)
    return manifest


def _record_shard(
    env_id: str,
    name: str,
    shard: dict[str, int],
    policy: str,
    noise: float | None,
    image_size: int,
    max_steps: int | None,
    options: dict | None,
    cache_dir: str,
    policy_options: dict | None = None,
) -> str:
    """One Ray task: record a shard with one env (resuming what a killed attempt committed)."""
    from ..planning.policies import make_policy, make_world

    with make_world(env_id, 1, image_size, max_steps, verbose=0) as world:
        world.set_policy(make_policy(policy, env_id, seed=shard["seed"], noise=noise, **(policy_options or {})))
        path = world.record_dataset(
            f"{name}/shard_{shard['shard']:05d}",
            episodes=shard["episodes"],
            seed=shard["seed"],
            cache_dir=cache_dir,
            options=options,
        )
    return str(path)


def _shard_done(path: Path) -> int:
    """Episodes committed in shard file ``path`` (0 when absent)."""
    if not path.exists():
        return 0
    from ..data._index import read_index
    from ..data.hdf5 import open_h5

    f = open_h5(path)  # read-only: a finished shard is left untouched
    try:
        return len(read_index(f, path)[0])
    finally:
        f.close()


def record_dataset_on_ray(
    env_id: str,
    dataset_name: str,
    episodes: int,
    *,
    seed: int = 0,
    policy: str = "expert",
    noise: float | None = None,
    policy_options: dict | None = None,
    shards: int | None = None,
    image_size: int = 64,
    max_steps: int | None = None,
    options: dict | None = None,
    cache_dir: str | os.PathLike | None = None,
    address: str | None = None,
    num_cpus: int | None = None,
    max_retries: int = 3,
    progress: bool = True,
) -> Path:
    """Record ``episodes`` episodes of ``env_id`` under ``policy`` as a sharded dataset, on Ray.

    ``policy_options``: the other arguments of :func:`~stable_worldmodel.planning.policies.make_policy`
    (``repeat_prob``, ``dist_constraint``).

    ``shards`` defaults to the cluster's CPU count (at most one per episode); a task that dies is
    retried ``max_retries`` times (each retry resumes its shard). Returns the dataset folder.
    """
    from ..data.utils import dataset_file, get_cache_dir

    if isinstance(episodes, bool) or not isinstance(episodes, (int, np.integer)) or episodes < 1:
        raise ConfigError(f"record_dataset_on_ray requires episodes to be a positive int, got {episodes!r}")
    cache = str(Path(cache_dir if cache_dir is not None else get_cache_dir()).resolve())
    folder = dataset_file(f"{dataset_name}/x", cache).parent
    if dataset_file(dataset_name, cache).exists():
        raise ConfigError(
            f"swm collect --ray records a sharded dataset in {folder}/, got a name whose single file "
            f"{dataset_file(dataset_name, cache)} exists; pick another --name"
        )
    ray = init_ray(address, num_cpus=num_cpus, cache_dir=cache)
    count = shards or max(1, int(ray.cluster_resources().get("CPU", 1)))
    spec = {
        "env": env_id,
        "episodes": int(episodes),
        "seed": int(seed),
        "policy": policy,
        "noise": noise,
        **({"policy_options": dict(policy_options)} if policy_options else {}),
        "image_size": int(image_size),
        "max_steps": max_steps,
        "options": options,
    }
    manifest = _manifest(folder, spec, count)
    todo = [s for s in manifest["shards"] if _shard_done(folder / f"shard_{s['shard']:05d}.h5") < s["episodes"]]
    task = ray.remote(num_cpus=1, max_retries=max_retries)(_record_shard)
    refs = [
        task.remote(env_id, dataset_name, s, policy, noise, image_size, max_steps, options, cache, policy_options)
        for s in todo
    ]
    _wait(
        ray, refs, progress, f"Recording {dataset_name} on Ray ({len(todo)} of {len(manifest['shards'])} shards to do)"
    )
    return folder


def _wait(ray: Any, refs: list, progress: bool, label: str) -> list:
    """Results of ``refs`` in order, with a progress bar over finished tasks; the first failure raises."""
    from tqdm.auto import tqdm

    pending, done = list(refs), {}
    with tqdm(total=len(refs), desc=label, unit="task", disable=not progress) as bar:
        while pending:
            ready, pending = ray.wait(pending, num_returns=1)
            for ref in ready:
                done[ref] = ray.get(ref)
                bar.update(1)
    return [done[r] for r in refs]


# -- evaluation ----------------------------------------------------------------------------------
def _evaluate_chunk(
    env_id: str,
    policy: str,
    seeds: Sequence[int],
    image_size: int,
    max_steps: int | None,
    factors: Sequence[str],
    plan: Any,
    device: str,
    cache_dir: str,
) -> dict[str, list]:
    """One Ray task: evaluate ``policy`` on consecutive ``seeds`` with one env, reading checkpoints
    from the driver's cache folder (a worker of an existing cluster does not inherit its environment)."""
    from ..planning.policies import evaluate_policy, make_world

    os.environ["STABLEWM_HOME"] = cache_dir

    with make_world(env_id, 1, image_size, max_steps, verbose=0) as world:
        out = evaluate_policy(world, policy, len(seeds), int(seeds[0]), factors, plan=plan, device=device)
    return {k: np.asarray(out[k]).tolist() for k in ("episode_successes", "episode_lengths") if k in out}


def evaluate_on_ray(
    env_id: str,
    policy: str,
    episodes: int,
    seed: int,
    *,
    factors: Sequence[str] = (),
    image_size: int = 64,
    max_steps: int | None = None,
    plan: Any = None,
    device: str = "cpu",
    chunks: int | None = None,
    address: str | None = None,
    num_cpus: int | None = None,
    cache_dir: str | os.PathLike | None = None,
    progress: bool = True,
) -> dict[str, Any]:
    """Evaluate ``policy`` on seeds ``seed .. seed + episodes - 1`` spread over Ray tasks.

    Returns ``episode_successes`` / ``episode_lengths`` in seed order (as ``World.evaluate``) and
    ``success_rate``.
    """
    from ..data.utils import get_cache_dir

    cache = str(Path(cache_dir if cache_dir is not None else get_cache_dir()).resolve())
    ray = init_ray(address, num_cpus=num_cpus, cache_dir=cache)
    count = chunks or max(1, int(ray.cluster_resources().get("CPU", 1)))
    parts = [c for c in np.array_split(np.arange(seed, seed + episodes), min(count, episodes)) if len(c)]
    task = ray.remote(num_cpus=1)(_evaluate_chunk)
    refs = [
        task.remote(env_id, policy, c.tolist(), image_size, max_steps, list(factors), plan, device, cache)
        for c in parts
    ]
    results = _wait(ray, refs, progress, f"Evaluating {policy} on Ray")
    out = {k: [v for r in results for v in r.get(k, [])] for k in ("episode_successes", "episode_lengths")}
    out["success_rate"] = 100.0 * float(np.mean(out["episode_successes"])) if out["episode_successes"] else 0.0
    return out

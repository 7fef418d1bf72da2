"""What ``swm eval`` runs: an evaluation on fresh seeded episodes or on held-out dataset
episodes (upstream's protocol), summarized with a 95% interval and a JSON record of the protocol."""

from __future__ import annotations

import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import ConfigError
from ..planning.policies import checkpoint_run, evaluate_policy, make_policy, make_world, policy_history, reset_options
from .stats import SuccessSummary

__all__ = ["PROTOCOLS", "dataset_starts", "evaluate_cli", "protocol_knobs"]

#: upstream's evaluation protocol (its ``scripts/plan/config/<env>.yaml`` and ``solver/cem.yaml``): 50 starts
#: from dataset episodes, the goal 25 steps later, 50 steps to reach it, CEM 300 x 30 over 5 blocks, all 5
#: executed before replanning, the cost of the final predicted step, no subgoals, seed 42
_UPSTREAM = {
    "episodes": 50,
    "seed": 42,
    "solver": "cem",
    "horizon": 5,
    "receding_horizon": 5,
    "samples": 300,
    "iterations": 30,
    "cost": "final",
    "subgoals": "none",
    "goal_offset": 25,
    "budget": 50,
}
#: env-specific knobs of upstream's configs (the others use :data:`_UPSTREAM`'s)
_UPSTREAM_ENVS = {"swm/OGBCube-v0": {"goal_offset": 200, "budget": 400}}
#: ``swm eval --protocol`` names
PROTOCOLS = ("upstream",)
#: the start pool of policies that are no run (random, expert, ...) under a protocol: the validation episodes
#: of ``swm train``'s default split (val_fraction 0.1, seed 0), the episodes a run trained with defaults never saw
DEFAULT_SPLIT = (0.1, 0)


def protocol_knobs(name: str, env: str) -> dict[str, Any]:
    """The evaluation knobs of protocol ``name`` (one of :data:`PROTOCOLS`) on ``env``."""
    from ..errors import unknown_name

    if name not in PROTOCOLS:
        raise unknown_name("evaluation protocol", name, PROTOCOLS)
    return {**_UPSTREAM, **_UPSTREAM_ENVS.get(env, {})}


#: the dataset column ``--min-goal-distance`` measures (the distance the envs' ``eval_state`` reports)
DISTANCE_COLUMN = "state"


def dataset_starts(
    dataset: Any,
    episodes: int,
    goal_offset: int,
    seed: int,
    pool: Sequence[int] | None = None,
    min_distance: float | None = None,
) -> tuple[list[int], list[int]]:
    """``episodes`` (episode, start step) pairs with ``start + goal_offset < length``, drawn with
    ``seed`` from ``pool`` (default: every episode), without repeating a pair while possible.
    ``min_distance``: only pairs whose goal row is at least that far from the start row (Euclidean
    distance of their :data:`DISTANCE_COLUMN`, the distance TwoRoom's and Push-T's ``eval_state``
    report), the harder variant where a random policy rarely succeeds."""
    lengths = np.asarray(dataset.lengths)
    pool = np.asarray(list(pool) if pool is not None else range(len(lengths)), dtype=np.int64)
    pool = pool[lengths[pool] > goal_offset]
    if not len(pool):
        raise ConfigError(
            f"swm eval --from-dataset requires episodes longer than --goal-offset {goal_offset}, got none "
            f"(longest: {int(lengths.max()) if len(lengths) else 0} steps); lower --goal-offset"
        )
    rng = np.random.default_rng(seed)
    pairs = [(int(e), s) for e in pool for s in range(int(lengths[e]) - goal_offset)]
    if min_distance is not None:
        pairs = _far_pairs(dataset, pairs, goal_offset, float(min_distance))
    pick = rng.permutation(len(pairs))
    if len(pick) < episodes:
        pick = np.concatenate([pick, rng.integers(0, len(pairs), episodes - len(pick))])
    chosen = [pairs[i] for i in pick[:episodes]]
    return [e for e, _ in chosen], [s for _, s in chosen]


def _far_pairs(dataset: Any, pairs: list[tuple[int, int]], goal_offset: int, min_distance: float) -> list:
    """The (episode, start) ``pairs`` whose goal row is at least ``min_distance`` from the start row."""
    if DISTANCE_COLUMN not in dataset.column_names:
        raise ConfigError(
            f"swm eval --min-goal-distance requires a {DISTANCE_COLUMN!r} column in the dataset, got columns "
            f"{sorted(dataset.column_names)}"
        )
    values = np.asarray(dataset.get_col_data(DISTANCE_COLUMN), np.float64).reshape(int(np.sum(dataset.lengths)), -1)
    offsets = np.concatenate([[0], np.cumsum(dataset.lengths)[:-1]]).astype(np.int64)
    rows = np.asarray([offsets[e] + s for e, s in pairs], np.int64)
    distance = np.linalg.norm(values[rows + goal_offset] - values[rows], axis=1)
    far = distance >= min_distance
    if not far.any():
        raise ConfigError(
            f"swm eval --min-goal-distance requires goals at least {min_distance:g} from their start, got none "
            f"among the goals {goal_offset} steps on (the farthest: {distance.max():.3g}); lower it"
        )
    return [pair for pair, keep in zip(pairs, far, strict=True) if keep]


def _from_dataset(
    world: Any,
    name: str | Path,
    episodes: int,
    goal_offset: int,
    budget: int,
    seed: int,
    pool: Sequence[int] | None,
    min_distance: float | None = None,
) -> dict:
    from ..data import HDF5Dataset

    # a Path: the dataset's file (or shard folder) itself, as a run's protocol records it
    dataset = HDF5Dataset(path=name, preload=False) if isinstance(name, Path) else HDF5Dataset(name, preload=False)
    eps, starts = dataset_starts(dataset, episodes, goal_offset, seed, pool, min_distance)
    n = world.num_envs
    successes, steps = [], []
    for i in range(0, episodes, n):
        chunk_e, chunk_s = eps[i : i + n], starts[i : i + n]
        pad = n - len(chunk_e)  # the last chunk fills the spare envs with repeats, then drops them
        out = world.evaluate_from_dataset(
            dataset, chunk_e + chunk_e[:1] * pad, chunk_s + chunk_s[:1] * pad, goal_offset, budget, save_video=False
        )
        successes += list(np.asarray(out["episode_successes"])[: n - pad])
        steps += list(np.asarray(out["steps_to_success"])[: n - pad])
    lengths = [s if s >= 0 else budget for s in steps]
    return {
        "episode_successes": np.asarray(successes, bool),
        "episode_lengths": np.asarray(lengths),
        "episodes_idx": eps,
        "start_steps": starts,
    }


def evaluate_cli(
    env: str,
    policy: str,
    *,
    episodes: int,
    seed: int,
    variation: Sequence[str],
    num_envs: int,
    max_steps: int,
    image_size: int,
    plan: Any = None,
    device: str = "auto",
    from_dataset: str | None = None,
    goal_offset: int = 25,
    budget: int = 50,
    video: Path | None = None,
    decoder: str | None = None,
    ray: bool = False,
    ray_address: str | None = None,
    held_out_of: str | None = None,
    protocol: str | None = None,
    min_goal_distance: float | None = None,
) -> tuple[SuccessSummary, str, dict[str, Any]]:
    """Evaluate ``policy`` and return its summary, a table title and the JSON record (``ray``:
    the episodes spread over Ray tasks, see :func:`stable_worldmodel.world.on_ray.evaluate_on_ray`).

    With ``from_dataset``, episodes start from the validation episodes of run ``held_out_of`` (default: the
    policy's own run), else, under a ``protocol``, from those of ``swm train``'s default split
    (:data:`DEFAULT_SPLIT`), else from any episode."""
    start = time.perf_counter()
    if plan is not None and policy.startswith("wm:"):  # subgoals='auto' -> what this run gets, recorded as such
        from ..planning.learned import resolve_subgoals

        plan = resolve_subgoals(checkpoint_run(policy), plan)
    record: dict[str, Any] = {
        "env": env,
        "policy": policy,
        "episodes": episodes,
        "seed": seed,
        "num_envs": num_envs,
        "image_size": image_size,
    }
    limit = budget if from_dataset else max_steps
    history = policy_history(policy)
    if history > 1:
        record["history_size"] = history
    steps = max(limit, budget) if from_dataset else max_steps
    if ray or ray_address:
        from ..world.on_ray import evaluate_on_ray

        results = evaluate_on_ray(
            env,
            policy,
            episodes,
            seed,
            factors=variation,
            image_size=image_size,
            max_steps=max_steps,
            plan=plan,
            device=device,
            address=ray_address,
            progress=False,
        )
        title = f"{env}: seeds {seed}..{seed + episodes - 1}, at most {max_steps} steps (on Ray)"
        record.update(
            protocol="seeds",
            seeds=[seed, seed + episodes - 1],
            max_steps=max_steps,
            variation=list(variation),
            ray=ray_address or "local",
        )
        return _finish(policy, results, record, plan, start), title, record
    with make_world(
        env, num_envs=num_envs, image_size=image_size, max_steps=steps, seed=seed, history_size=history
    ) as world:
        if from_dataset:
            pol = make_policy(policy, env, seed=seed, plan=plan, device=device)
            world.set_policy(pol)
            pool, held_out = _start_pool(policy, from_dataset, held_out_of, protocol)
            results = _from_dataset(world, from_dataset, episodes, goal_offset, budget, seed, pool, min_goal_distance)
            far = f", at least {min_goal_distance:g} away" if min_goal_distance is not None else ""
            title = f"{env}: {episodes} starts from {from_dataset} (goal +{goal_offset} steps{far}, budget {budget})"
            record.update(
                protocol="dataset",
                dataset=from_dataset,
                goal_offset=goal_offset,
                budget=budget,
                episodes_idx=results["episodes_idx"],
                start_steps=results["start_steps"],
                held_out=pool is not None,
                start_pool=held_out,
            )
            if protocol is not None:
                record["protocol_name"] = protocol
            if min_goal_distance is not None:
                record["min_goal_distance"] = min_goal_distance
        else:
            results = evaluate_policy(world, policy, episodes, seed, variation, plan=plan, device=device)
            title = f"{env}: seeds {seed}..{seed + episodes - 1}, at most {max_steps} steps"
            record.update(
                protocol="seeds", seeds=[seed, seed + episodes - 1], max_steps=max_steps, variation=list(variation)
            )
        if video is not None:
            run = checkpoint_run(policy)
            if run is not None and policy.startswith("wm:"):
                from ..planning.learned import attach_prediction_panel

                used = attach_prediction_panel(world.policy, run, decoder, device=device)
                if used is not None:
                    record["decoder"] = used
            paths = world.record_video(video, max_steps=limit, seed=seed, options=reset_options(variation))
            record["videos"] = [str(p) for p in paths]
    return _finish(policy, results, record, plan, start), title, record


def _finish(policy: str, results: dict, record: dict[str, Any], plan: Any, start: float) -> SuccessSummary:
    """The summary of ``results``; fills the outcome fields of ``record``."""
    summary = SuccessSummary.from_results(policy, results)
    record.update(
        success_rate=round(100 * summary.rate, 2),
        ci95=[round(100 * v, 2) for v in summary.interval],
        successes=summary.successes,
        mean_length=round(summary.mean_length, 2),
        seconds=round(time.perf_counter() - start, 1),
        episode_successes=[bool(v) for v in results["episode_successes"]],
    )
    if plan is not None:
        record["plan"] = plan.as_dict()
    if checkpoint_run(policy) is not None:
        record["model"] = _model_summary(policy)
    return summary


def _start_pool(policy: str, dataset: str, held_out_of: str | None, protocol: str | None) -> tuple[list | None, str]:
    """The dataset episodes an evaluation starts from, and where they come from (for the record)."""
    source = held_out_of or policy
    pool = _held_out(source, dataset)
    if pool is not None:
        return pool, f"validation episodes of {source}"
    if held_out_of is not None:
        raise ConfigError(
            f"swm eval --held-out-of requires a wm:/gc: run trained on {dataset!r} whose protocol lists its "
            f"validation episodes, got {held_out_of!r}"
        )
    if protocol is not None:
        from ..data import load_dataset
        from ..train.data import split_episodes

        fraction, seed = DEFAULT_SPLIT
        _, val = split_episodes(load_dataset(dataset).num_episodes, fraction, seed)
        return [int(e) for e in val], f"validation episodes of swm train's default split (val {fraction}, seed {seed})"
    return None, "all episodes"


def _held_out(policy: str, dataset: str) -> list[int] | None:
    """The validation episodes of a wm: / gc: run trained on ``dataset`` (None: use every episode)."""
    run = checkpoint_run(policy)
    if run is None:
        return None
    from ..wm.run import Run

    protocol = Run.open(run).protocol
    if protocol.dataset == Path(dataset).stem and protocol.val_episodes:
        return list(protocol.val_episodes)
    return None


def _model_summary(policy: str) -> dict[str, Any]:
    from ..wm.run import Run

    run = Run.open(policy)
    protocol = run.protocol.to_dict()
    keep = ("model", "preset", "dataset", "steps", "seed", "frameskip", "history_size", "image_size", "final")
    return {"checkpoint": str(run.folder), **{k: protocol[k] for k in keep if k in protocol}}

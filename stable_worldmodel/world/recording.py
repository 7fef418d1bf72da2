"""Recording loops behind ``World.record_dataset`` / ``record_video`` / ``evaluate_from_dataset``.

They use only the public World contract: ``reset``, ``reset_envs``, ``step``, ``infos``
(every entry ``(B, T, ...)``), ``terminateds`` / ``truncateds`` ``(B,)``, ``envs.call`` /
``envs.call_each``, ``num_envs`` and ``verbose``.
"""

from __future__ import annotations

import logging
import os
import time
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from .. import keys
from ..errors import ConfigError
from .batching import stack

logger = logging.getLogger(__name__)

SEED_LIMIT = 2**31 - 1


def _progress(world: Any, total: int, desc: str, initial: int = 0):
    from .progress import progress

    return progress(total, desc, enabled=int(getattr(world, "verbose", 1)) > 0, initial=initial)


NOT_RECORDED = frozenset({keys.RENDER_TIME})  # wall-clock timings: the same seed must give the same bytes


def _last_frames(infos: Mapping[str, Any]) -> dict[str, np.ndarray]:
    """Recordable info columns at the last history frame: ``{key: (B, ...)}`` (copies).

    Private keys (``_...``) and timings (:data:`NOT_RECORDED`) are left out.
    """
    from ..data.writer import is_recordable

    out = {}
    for key, value in infos.items():
        if key.startswith("_") or key in NOT_RECORDED:
            continue
        arr = np.asarray(value)
        if arr.ndim < 2 or not is_recordable(arr):
            continue
        out[key] = np.array(arr[:, -1])
    return out


def _finish_episode(rows: dict[str, list[np.ndarray]], ep_idx: int | None = None) -> dict[str, np.ndarray]:
    """Stack an episode's rows; row t gets the action of step t+1 (NaN on the last row).

    Keys missing from some rows (an env whose reset info has keys its step info lacks, such as
    ALE's ``seeds``) are skipped, so every episode has the same columns. ``ep_idx`` adds the
    :data:`~stable_worldmodel.keys.EP_IDX` column.
    """
    length = max((len(v) for v in rows.values()), default=0)
    episode = {k: stack(v) for k, v in rows.items() if len(v) == length}
    action = episode.get(keys.ACTION)
    if action is not None:
        action = action.astype(np.result_type(action.dtype, np.float32), copy=False)
        shifted = np.empty_like(action)
        shifted[:-1] = action[1:]
        shifted[-1] = np.nan
        episode[keys.ACTION] = shifted
    if ep_idx is not None:
        episode[keys.EP_IDX] = np.full(length, ep_idx, np.int64)
    return episode


def record_dataset(
    world: Any,
    dataset_name: str,
    episodes: int = 10,
    seed: int | None = None,
    cache_dir: str | os.PathLike | None = None,
    options: dict | None = None,
) -> Path:
    """Make ``<cache_dir>/<dataset_name>.h5`` hold ``episodes`` complete episodes in all.

    Each env runs its own episodes; an env that finishes is reset alone (``reset_envs``) with
    the next seed, and episodes still running when enough are written are discarded. Episode
    ``k`` of a new file uses seed ``seed + k`` (a random base when ``seed`` is None). As in
    release 0.0.3, an existing dataset is *resumed*: a file holding ``k`` episodes gets
    ``episodes - k`` more (none when ``k >= episodes``), so re-running a crashed recording
    completes it without duplicates; seeds continue from the file's ``next_seed`` so they never
    repeat. Each finished batch of episodes is committed (see :mod:`stable_worldmodel.data.writer`),
    so an interrupted recording keeps what it wrote. Every row gets ``ep_idx``, its episode's
    index in the file. Returns the file path.
    """
    from ..data.utils import dataset_file
    from ..data.writer import ENV_ID_ATTR, HDF5Writer
    from .checks import check_seed

    if isinstance(episodes, bool) or not isinstance(episodes, (int, np.integer)) or episodes < 1:
        raise ConfigError(f"record_dataset requires episodes to be a positive int, got {episodes!r}")
    seed = check_seed("World.record_dataset", seed)
    path = dataset_file(dataset_name, cache_dir)
    with HDF5Writer(path, attrs={ENV_ID_ATTR: world.env_name}) as writer:
        have = writer.num_episodes
        if have >= episodes:
            logger.info("%s already holds %d episodes (>= %d asked): nothing to record", path, have, episodes)
            return path
        if have:
            logger.info("Resuming %s: %d of %d episodes on disk", path, have, episodes)
        with_idx = have == 0 or keys.EP_IDX in writer.columns  # files of older versions have no ep_idx
        first_seed = writer.next_seed if writer.next_seed is not None else seed
        record_episodes(world, writer, episodes - have, first_seed, options, f"Recording {path.name}", with_idx, have)
    return path


def record_episodes(
    world: Any,
    writer: Any,
    episodes: int,
    seed: int | None,
    options: dict | None,
    label: str,
    with_idx: bool = True,
    done_before: int = 0,
) -> int:
    """Record ``episodes`` complete episodes into ``writer``; episode k gets seed ``seed + k``.

    ``writer`` is an :class:`~stable_worldmodel.data.writer.HDF5Writer` (batches committed with
    ``next_seed``) or any writer with ``write_episode(episode)`` (upstream 0.1.1's protocol).
    Returns the number of rows written.
    """
    from .evaluate import reseed_policy

    n = int(world.num_envs)
    next_seed = int(seed) if seed is not None else int(np.random.SeedSequence().entropy % SEED_LIMIT)
    committing = hasattr(writer, "write_episodes") and hasattr(writer, "next_seed")
    written = int(getattr(writer, "num_episodes", 0) or 0)

    def take(k: int) -> list[int]:
        nonlocal next_seed
        seeds = [(next_seed + i) % SEED_LIMIT for i in range(k)]
        next_seed = (next_seed + k) % SEED_LIMIT
        return seeds

    reseed_policy(world.policy, next_seed)
    world.reset(seed=take(n), options=options)
    buffers: list[dict[str, list[np.ndarray]]] = [{} for _ in range(n)]

    def push(env_ids: Sequence[int]) -> None:
        frames = _last_frames(world.infos)
        for i in env_ids:
            for key, value in frames.items():
                buffers[i].setdefault(key, []).append(value[i])

    push(range(n))
    done = rows = 0
    t0 = time.perf_counter()
    with _progress(world, episodes + done_before, label, initial=done_before) as bar:
        while done < episodes:
            world.step()
            push(range(n))
            ended = np.flatnonzero(np.asarray(world.terminateds) | np.asarray(world.truncateds))
            if not len(ended):
                continue
            batch = [
                _finish_episode(buffers[i], written + j if with_idx else None)
                for j, i in enumerate(ended[: episodes - done])
            ]
            if committing:
                writer.write_episodes(batch, next_seed=next_seed)
            else:
                for episode in batch:
                    writer.write_episode(episode)
            written += len(batch)
            done += len(batch)
            rows += sum(len(next(iter(ep.values()))) for ep in batch)
            bar.set_postfix_str(f"{rows / max(time.perf_counter() - t0, 1e-9):.0f} rows/s", refresh=False)
            bar.update(len(batch))
            if done >= episodes:
                break
            ids = [int(i) for i in ended]
            world.reset_envs(ids, seeds=take(len(ids)), options=[options] * len(ids))
            for i in ids:
                buffers[i] = {}
            push(ids)
    logger.info("%s: recorded %d episodes (%d rows)", label, done, rows)
    return rows


def collect(
    world: Any,
    path: str | os.PathLike | None = None,
    episodes: int = 0,
    seed: int | None = None,
    options: dict | None = None,
    format: str | None = None,  # noqa: A002 - upstream 0.1.1's name
    writer: Any = None,
    progress: bool = True,
) -> None:
    """Upstream 0.1.1's ``World.collect``: record ``episodes`` more episodes to ``path`` (or into ``writer``).

    ``format`` is a registered dataset format (:func:`stable_worldmodel.data.list_formats`);
    by default it follows the path: ``x.lance`` is Lance (0.1.1's default), ``.h5`` / ``.hdf5``
    or a path without a suffix is HDF5 (the file gets ``.h5``), a folder already holding a
    dataset keeps its format. Parent folders are created. Appends to an existing dataset.
    """
    from ..data.format import detect_format, get_format
    from .checks import check_seed

    if (path is None) == (writer is None):
        raise ConfigError(
            "World.collect requires exactly one of path= or writer=, got " + ("both" if path is not None else "neither")
        )
    if isinstance(episodes, bool) or not isinstance(episodes, (int, np.integer)) or episodes < 1:
        raise ConfigError(f"World.collect requires episodes to be a positive int, got {episodes!r}")
    seed = check_seed("World.collect", seed)
    verbose = world.verbose
    world.verbose = verbose if progress else 0
    try:
        if writer is not None:
            record_episodes(world, writer, int(episodes), seed, options, "Recording", with_idx=False)
            return
        target = Path(path).expanduser()
        if format is None:
            known = detect_format(target) if target.exists() else None
            format = known.name if known is not None else "lance" if target.suffix.lower() == ".lance" else "hdf5"
        fmt = get_format(format)
        if fmt.name == "hdf5" and target.suffix not in (".h5", ".hdf5"):
            target = target.with_name(target.name + ".h5")
        target.parent.mkdir(parents=True, exist_ok=True)
        with fmt.open_writer(target) as sink:
            have = int(getattr(sink, "num_episodes", 0) or 0)
            first = sink.next_seed if getattr(sink, "next_seed", None) is not None else seed
            with_idx = have == 0 or keys.EP_IDX in getattr(sink, "columns", [keys.EP_IDX])
            record_episodes(world, sink, int(episodes), first, options, f"Recording {target.name}", with_idx, have)
    finally:
        world.verbose = verbose


def _frame(infos: Mapping[str, Any], views: Sequence[str], env: int, predicted: np.ndarray | None = None) -> np.ndarray:
    from ..data.video import hstack_frames, vstack_frames

    row = [np.asarray(infos[v])[env, -1] for v in views]
    if predicted is not None:  # what the planning model expects to see, at the first view's size
        from ..wrapper._image import resize

        row.append(resize(np.ascontiguousarray(predicted[env]), row[0].shape[:2]))
    top = hstack_frames(row)
    if keys.GOAL in infos and keys.GOAL not in views:
        return vstack_frames([top, np.asarray(infos[keys.GOAL])[env, -1]])
    return top


def _check_views(infos: Mapping[str, Any], viewname: str | Sequence[str]) -> list[str]:
    from ..errors import unknown_name

    views = [viewname] if isinstance(viewname, str) else list(viewname)
    for v in views:
        if v not in infos:
            raise unknown_name("info key (viewname)", v, [k for k in infos if not k.startswith("_")])
    return views


def record_video(
    world: Any,
    video_path: str | os.PathLike,
    max_steps: int = 500,
    fps: int = 30,
    viewname: str | Sequence[str] = keys.PIXELS,
    seed: int | None = None,
    options: dict | None = None,
) -> list[Path]:
    """Roll out the policy and write ``<video_path>/env_<i>.mp4`` for every env.

    Each frame shows the ``viewname`` views side by side with the goal image below (when the
    infos have one). A policy with a ``prediction_panel`` (a world model with a frame decoder)
    adds, right of the views, the frame it predicted for the end of the action block it is
    executing (black before its first plan). Recording stops after ``max_steps`` steps or when
    any env ends. Returns the written paths.
    """
    from ..data.video import write_mp4

    world.reset(seed=seed, options=options)
    views = _check_views(world.infos, viewname)
    n = int(world.num_envs)
    policy = getattr(world, "policy", None)
    blank = (
        np.zeros_like(np.asarray(world.infos[views[0]])[:, -1]) if getattr(policy, "prediction_panel", None) else None
    )

    def predicted() -> np.ndarray | None:
        if blank is None:
            return None
        frames = getattr(policy, "predicted_frames", None)
        return blank if frames is None else frames

    frames: list[list[np.ndarray]] = [[_frame(world.infos, views, i, predicted())] for i in range(n)]
    for _ in range(int(max_steps)):
        world.step()
        for i in range(n):
            frames[i].append(_frame(world.infos, views, i, predicted()))
        if np.any(np.asarray(world.terminateds) | np.asarray(world.truncateds)):
            break
    return [write_mp4(Path(video_path) / f"env_{i}.mp4", frames[i], fps=fps) for i in range(n)]


def record_video_from_dataset(
    world: Any,
    video_path: str | os.PathLike,
    dataset_name: str,
    episode_idx: int | Sequence[int],
    max_steps: int = 500,
    fps: int = 30,
    num_proc: int = 4,
    viewname: str | Sequence[str] = keys.PIXELS,
    cache_dir: str | os.PathLike | None = None,
) -> list[Path]:
    """Write ``<video_path>/episode_<idx>.mp4`` for recorded episodes (``num_proc`` is unused:
    HDF5 episodes are read directly). See :func:`stable_worldmodel.data.video.record_video_from_dataset`."""
    from ..data.video import record_video_from_dataset as replay

    return replay(
        video_path, dataset_name, episode_idx, max_steps=max_steps, fps=fps, viewname=viewname, cache_dir=cache_dir
    )


def _check_eval_args(world, dataset, episodes_idx, start_steps, goal_offset_steps, eval_budget) -> tuple[list, list]:
    episodes_idx = [int(e) for e in np.atleast_1d(episodes_idx)]
    start_steps = [int(s) for s in np.atleast_1d(start_steps)]
    n = int(world.num_envs)
    if len(episodes_idx) != len(start_steps):
        raise ConfigError(
            f"evaluate_from_dataset requires episodes_idx and start_steps of the same length, "
            f"got {len(episodes_idx)} episodes_idx and {len(start_steps)} start_steps"
        )
    if len(episodes_idx) != n:
        raise ConfigError(
            f"evaluate_from_dataset requires one episode per env (num_envs={n}), got {len(episodes_idx)} episodes_idx"
        )
    for name, value, low in (("goal_offset_steps", goal_offset_steps, 0), ("eval_budget", eval_budget, 1)):
        if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < low:
            raise ConfigError(f"evaluate_from_dataset requires {name} to be an int >= {low}, got {value!r}")
    lengths = dataset.lengths
    for ep, start in zip(episodes_idx, start_steps, strict=False):
        if not 0 <= ep < len(lengths):
            raise ConfigError(f"evaluate_from_dataset requires episodes_idx in [0, {len(lengths)}), got {ep}")
        if start < 0 or start + goal_offset_steps >= lengths[ep]:
            raise ConfigError(
                f"evaluate_from_dataset requires start_steps + goal_offset_steps < episode length, got episode {ep} "
                f"(length {int(lengths[ep])}) with start_steps={start}, goal_offset_steps={goal_offset_steps}"
            )
    return episodes_idx, start_steps


def _apply_callables(
    world: Any, callables: Sequence[Mapping[str, Any]] | None, starts: Sequence[Mapping[str, Any]]
) -> None:
    """Call ``env.unwrapped.<method>(**args)`` on every env after the reset, as release 0.0.3.

    ``callables``: ``[{"method": name, "args": {arg: {"value": column}}}]``: each argument's
    ``value`` names a column read from that env's start row (``"in_dataset": False`` passes
    ``value`` itself). A method the env lacks, or a column the dataset lacks, is skipped with
    one warning.
    """
    from .checks import env_class

    cls = env_class(world.env_name)
    n = int(world.num_envs)
    for spec in callables or []:
        if not isinstance(spec, Mapping) or not isinstance(spec.get("method"), str):
            raise ConfigError(
                f"evaluate_from_dataset requires callables as {{'method': name, 'args': {{arg: {{'value': column}}}}}} "
                f"dicts, got {spec!r}"
            )
        name = spec["method"]
        if cls is not None and not hasattr(cls, name):
            logger.warning("%s has no method %r: callable skipped", cls.__name__, name)
            continue
        args = spec.get("args", spec)
        kwargs_list: list[dict[str, Any]] = [{} for _ in range(n)]
        for arg, data in (args or {}).items():
            if arg == "method" and args is spec:
                continue
            data = data if isinstance(data, Mapping) else {"value": data, "in_dataset": False}
            value = data.get("value")
            if data.get("in_dataset", True):
                if value not in starts[0]:
                    logger.warning("column %r is not in the dataset: argument %r of %s skipped", value, arg, name)
                    continue
                for i in range(n):
                    kwargs_list[i][arg] = np.array(starts[i][value])
            else:
                for i in range(n):
                    kwargs_list[i][arg] = value
        world.envs.call_each(name, [()] * n, kwargs_list)


def evaluate_from_dataset(
    world: Any,
    dataset: Any,
    episodes_idx: Sequence[int],
    start_steps: Sequence[int],
    goal_offset_steps: int,
    eval_budget: int,
    callables: list[dict] | None = None,
    save_video: bool = True,
    video_path: str | os.PathLike = "./",
) -> dict:
    """Start env i at step ``start_steps[i]`` of episode ``episodes_idx[i]`` of ``dataset``.

    The goal is the recorded state ``goal_offset_steps`` later; the env builds its reset
    options from both rows (``SupportsDatasetReset.reset_options_from_dataset``). The
    policy then gets ``eval_budget`` steps; an env succeeds when it terminates. ``callables``
    are called on every env after the reset (see :func:`_apply_callables`).
    ``dataset`` is a :class:`~stable_worldmodel.data.Dataset` or an HDF5 dataset name.

    Returns ``success_rate`` (percent), ``episode_successes`` ``(B,)`` bool,
    ``steps_to_success`` ``(B,)`` (-1 when not reached), ``episodes_idx`` and ``start_steps``.
    Raises ValueError (:class:`ConfigError`) for mismatched lengths, a count other than
    ``num_envs`` or a goal past an episode's end.
    """
    from ..data.video import write_mp4

    if isinstance(dataset, (str, os.PathLike)):
        from ..data.hdf5 import HDF5Dataset

        dataset = HDF5Dataset(dataset, preload=False)  # reads a few rows
    episodes_idx, start_steps = _check_eval_args(
        world, dataset, episodes_idx, start_steps, goal_offset_steps, eval_budget
    )
    rows = [int(dataset.offsets[e]) + s for e, s in zip(episodes_idx, start_steps, strict=False)]
    starts = [dataset.get_row_data(r) for r in rows]
    goals = [dataset.get_row_data(r + int(goal_offset_steps)) for r in rows]
    options = world.envs.call_each("reset_options_from_dataset", [(s, g) for s, g in zip(starts, goals, strict=False)])
    n = int(world.num_envs)
    seeds = world.draw_seeds(n)
    world.reset_envs(list(range(n)), seeds=seeds, options=list(options))
    _apply_callables(world, callables, starts)
    views = [keys.PIXELS] if save_video and keys.PIXELS in world.infos else []
    frames: list[list[np.ndarray]] = [[_frame(world.infos, views, i)] if views else [] for i in range(n)]
    steps_to_success = np.full(n, -1, np.int64)
    for t in range(int(eval_budget)):
        world.step()
        newly = np.asarray(world.terminateds, bool) & (steps_to_success < 0)
        steps_to_success[newly] = t + 1
        if views:
            for i in range(n):
                frames[i].append(_frame(world.infos, views, i))
        if np.all(steps_to_success >= 0):
            break
    if views:
        for i in range(n):
            write_mp4(Path(video_path) / f"env_{i}.mp4", frames[i])
    successes = steps_to_success >= 0
    return {
        "success_rate": float(successes.mean() * 100.0),
        "episode_successes": successes,
        "steps_to_success": steps_to_success,
        "episodes_idx": episodes_idx,
        "start_steps": start_steps,
        "seeds": np.asarray(seeds, np.int64),  # the reset seeds (upstream 0.1.1 returns them too)
    }

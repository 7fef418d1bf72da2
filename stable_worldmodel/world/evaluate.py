"""World.evaluate: success rates over many seeded episodes."""

from __future__ import annotations

import json
import logging
import os
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from .. import keys
from ..errors import ConfigError, unknown_name
from .checks import check_seed

if TYPE_CHECKING:
    from .world import World

logger = logging.getLogger(__name__)


def _progress(world: World, total: int, desc: str):
    from .progress import progress

    return progress(total, desc, enabled=bool(world.verbose))


def reseed_policy(policy: Any, seed: int | None) -> None:
    """``policy.set_seed(seed)`` when a seed is given and the policy has the method (user policies may not)."""
    if seed is not None and callable(getattr(policy, "set_seed", None)):
        policy.set_seed(int(seed))


def episode_seeds(world: World, episodes: int, seed: int | None) -> list[int]:
    """One distinct seed per episode: ``seed + k``, or fresh draws from the world's generator."""
    if seed is not None:
        return [int(seed) + k for k in range(episodes)]
    seeds: list[int] = []
    seen: set[int] = set()
    while len(seeds) < episodes:
        for s in world.draw_seeds(episodes - len(seeds)):
            if s not in seen:
                seen.add(s)
                seeds.append(s)
    return seeds


def evaluate(
    world: World,
    episodes: int = 10,
    eval_keys=None,
    seed: int | None = None,
    options=None,
    dump_every: int = -1,
    video: str | os.PathLike | None = None,
) -> dict[str, Any]:
    """The episodic evaluation loop of :meth:`World.evaluate` (see there); ``video``: one MP4 per episode."""
    if isinstance(episodes, bool) or not isinstance(episodes, (int, np.integer)) or episodes < 1:
        raise ConfigError(f"World.evaluate requires episodes to be an integer >= 1, got {episodes!r}")
    if world.policy is None:
        raise RuntimeError("World.evaluate requires a policy: call world.set_policy(policy) first")
    seed = check_seed("World.evaluate", seed)
    eval_keys = list(eval_keys or [])
    seeds = episode_seeds(world, episodes, seed)
    reseed_policy(world.policy, seed)
    n = world.num_envs
    first = min(n, episodes)
    # envs beyond the episode count run their own throw-away episodes and are never counted
    spare = world.draw_seeds(n - first) if n > first else []
    world.reset(seed=seeds[:first] + spare, options=options)
    for key in eval_keys:
        if key not in world.infos:
            raise unknown_name("eval key", key, world.infos)

    successes = np.zeros(episodes, bool)
    finished_mask = np.zeros(episodes, bool)
    lengths = np.zeros(episodes, np.int64)
    collected: dict[str, list] = {k: [None] * episodes for k in eval_keys}
    slot = np.full(n, -1, np.int64)  # episode index each env is playing (-1: none)
    slot[:first] = np.arange(first)
    frames: list[list[np.ndarray]] | None = None
    if video is not None:
        if keys.PIXELS not in world.infos:
            raise ConfigError(
                f"World.evaluate(video=...) requires {keys.PIXELS!r} in the infos, got {sorted(world.infos)}"
            )
        frames = [[np.asarray(world.infos[keys.PIXELS])[i, -1].copy()] for i in range(n)]
    next_episode = first
    done_count = 0
    bar = _progress(world, episodes, f"evaluate {world.env_name}")
    try:
        t = 0
        while done_count < episodes:
            world.step()
            t += 1
            bar.set_postfix_str(f"{int(successes[finished_mask].sum())} successes, env step {t}", refresh=False)
            bar.update(0)  # the step shows while the envs of a batch run together
            if frames is not None:
                pixels = np.asarray(world.infos[keys.PIXELS])
                for i in np.flatnonzero(slot >= 0):
                    frames[i].append(pixels[i, -1].copy())
            finished = np.flatnonzero((world.terminateds | world.truncateds) & (slot >= 0))
            if len(finished) == 0:
                continue
            for env in finished:
                ep = slot[env]
                successes[ep] = bool(world.terminateds[env])
                finished_mask[ep] = True
                lengths[ep] = int(np.asarray(world.infos[keys.STEP_IDX])[env, -1])
                for k in eval_keys:
                    collected[k][ep] = np.asarray(world.infos[k][env, -1]).copy()
                if frames is not None:
                    from ..data.video import write_mp4

                    write_mp4(Path(video) / f"episode_{ep}.mp4", frames[env])
                done_count += 1
                if dump_every > 0 and done_count % dump_every == 0:
                    _dump(world, seed, successes, seeds, finished_mask)
            bar.update(len(finished))
            restart, restart_seeds = [], []
            for env in finished:
                if next_episode < episodes:
                    slot[env] = next_episode
                    restart.append(int(env))
                    restart_seeds.append(seeds[next_episode])
                    next_episode += 1
                else:
                    slot[env] = -1
            if restart:
                world.reset_envs(restart, seeds=restart_seeds, options=options)
                if frames is not None:
                    pixels = np.asarray(world.infos[keys.PIXELS])
                    for env in restart:
                        frames[env] = [pixels[env, -1].copy()]
    finally:
        bar.close()
    results: dict[str, Any] = {
        "success_rate": float(successes.mean() * 100.0),
        "episode_successes": successes,
        "seeds": np.asarray(seeds, np.int64),
        "episode_lengths": lengths,
        "episode_count": int(episodes),  # 0.0.3's key: finished episodes counted
    }
    for k in eval_keys:
        results[k] = np.stack(collected[k])
    assert len(set(seeds)) == len(seeds), "evaluation seeds must be unique"
    return results


def _dump(world: World, seed, successes, seeds, finished) -> None:
    """Write the finished episodes so far (seed and success of each) as JSON, atomically."""
    from ..data import get_cache_dir

    path = get_cache_dir() / "evaluations" / f"{world.env_name.replace('/', '_')}_{seed}.json"
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_suffix(".json.tmp")
    done = np.flatnonzero(finished)
    payload = {
        "env": world.env_name,
        "episodes_done": len(done),
        "episodes_total": len(seeds),
        "seeds": [int(seeds[k]) for k in done],
        "successes": [bool(successes[k]) for k in done],
    }
    tmp.write_text(json.dumps(payload))
    tmp.replace(path)
    logger.info("evaluation progress written to %s", path)

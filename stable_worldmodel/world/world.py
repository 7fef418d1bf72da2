"""World: many copies of one env, a policy, and the loops of research (step, evaluate, record)."""

from __future__ import annotations

import logging
import os
from collections.abc import Callable, Sequence
from functools import partial
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np

from .._compat import world_compat_args
from ..envs._registry import check_env_id, make_env
from ..errors import ConfigError, check_int
from ..wrapper import MegaWrapper
from ..wrapper._image import check_shape
from ..wrapper.mega import GOAL_IF_ANY
from .checks import check_env_kwargs, check_reset_options, check_seed, check_seeds
from .evaluate import evaluate as _evaluate
from .vector import VecEnv

logger = logging.getLogger(__name__)


def make_world_env(
    env_name: str,
    image_shape: tuple[int, int],
    max_episode_steps: int,
    history_size: int,
    frame_skip: int,
    image_transform: Callable | None,
    goal_transform: Callable | None,
    goal_conditioned: bool,
    extra_wrappers: Sequence[Callable] | None,
    env_kwargs: dict[str, Any],
    goal_shape: tuple[int, int] | None = None,
    pre_wrappers: Sequence[Callable] | None = None,
    add_pixels: bool = True,
) -> gym.Env:
    """One env as World uses it: ``gym.make`` + ``pre_wrappers`` + :class:`MegaWrapper` + ``extra_wrappers``.

    As in 0.0.3 (and 0.1.1), ``extra_wrappers`` wrap the standardised env (after MegaWrapper);
    0.1.1's ``pre_wrappers`` wrap the raw env, before it.
    """
    kwargs = dict(env_kwargs)
    if add_pixels:
        kwargs.setdefault("render_mode", "rgb_array")
    env = make_env(env_name, max_episode_steps=max_episode_steps, disable_env_checker=True, **kwargs)
    for wrapper in pre_wrappers or ():
        env = wrapper(env)
    env = MegaWrapper(
        env,
        image_shape=image_shape,
        pixels_transform=image_transform,
        goal_transform=goal_transform,
        separate_goal=GOAL_IF_ANY if goal_conditioned else False,  # goal-less envs work, as in 0.0.3
        history_size=history_size,
        frame_skip=frame_skip,
        goal_shape=goal_shape,
        add_pixels=add_pixels,
    )
    for wrapper in extra_wrappers or ():
        env = wrapper(env)
    return env


def _positive_int(name: str, value: Any) -> int:
    return check_int("World", name, value)


class World:
    """High-level manager of ``num_envs`` synchronized copies of a Gymnasium env.

    Every entry of :attr:`infos` is batched as ``(B, T, ...)`` (B envs, T = ``history_size``);
    images are ``(B, T, H, W, 3)`` uint8 with (H, W) = ``image_shape``. Autoreset is disabled:
    an env is reset only by :meth:`reset` / :meth:`reset_envs` (the loops below do it).

    Extra keyword arguments go to the env constructor, except ``vectorization_mode``:
    ``"auto"`` (default: worker processes when there are enough envs and cores, and from 2 envs
    on for the render-bound MuJoCo envs, whose GL contexts are then made in the workers), ``"sync"``
    (all envs in this process) or ``"async"``; both give identical results for the same seeds.
    ``frame_skip`` spaces the stacked history frames; each :meth:`step` is one env step.
    ``goal_shape`` (seed 000's argument) draws ``goal`` images at another (H, W).
    """

    def __init__(
        self,
        env_name: str,
        num_envs: int,
        image_shape: tuple[int, int] | None = None,
        goal_transform: Callable[[Any], Any] | None = None,
        image_transform: Callable[[Any], Any] | None = None,
        seed: int = 2349867,
        history_size: int = 1,
        frame_skip: int = 1,
        max_episode_steps: int = 100,
        verbose: int = 1,
        extra_wrappers: list[Callable] | None = None,
        goal_conditioned: bool = True,
        **kwargs: Any,
    ):
        check_env_id(env_name)
        self.env_name = env_name
        n = _positive_int("num_envs", num_envs)
        compat = world_compat_args(kwargs)  # the older releases' arguments, never passed to the env
        add_pixels = compat.add_pixels
        if image_shape is None and add_pixels:
            raise ConfigError("World requires image_shape=(H, W) for the pixels it adds (or add_pixels=False)")
        self.image_shape = check_shape("World image_shape", image_shape if image_shape is not None else (1, 1))
        self.history_size = _positive_int("history_size", history_size)
        self.frame_skip = _positive_int("frame_skip", frame_skip)
        self.max_episode_steps = _positive_int("max_episode_steps", max_episode_steps)
        self.seed = check_seed("World", seed)
        self.verbose = verbose
        self.goal_conditioned = goal_conditioned
        mode, pre_wrappers, goal_shape = compat.vectorization_mode, compat.pre_wrappers, compat.goal_shape
        if compat.image_resample is not None:
            logger.info(
                "World(image_resample=%r): images are resized with OpenCV's area/linear filters", compat.image_resample
            )
        goal_shape = check_shape("World goal_shape", goal_shape) if goal_shape is not None else None
        check_env_kwargs(env_name, kwargs)
        factory = partial(
            make_world_env,
            env_name,
            self.image_shape,
            self.max_episode_steps,
            self.history_size,
            self.frame_skip,
            image_transform,
            goal_transform,
            goal_conditioned,
            list(extra_wrappers or []),
            kwargs,
            goal_shape,
            pre_wrappers,
            add_pixels,
        )
        if mode == "auto" and render_bound(env_name) and n >= 2 and (os.cpu_count() or 1) >= 2:
            mode = "async"  # rendering dominates a step (~50 ms): worker processes pay from 2 envs on
        self._vec = VecEnv(factory, n, mode=mode)
        self.envs = self._vec
        self._rng = np.random.default_rng(seed)
        self.policy = None
        self.states: Any = None
        self.rewards = np.zeros(n, np.float64)
        self.terminateds = np.zeros(n, bool)
        self.truncateds = np.zeros(n, bool)
        self.infos: dict[str, np.ndarray] = {}
        self._has_reset = False

    # -- properties ------------------------------------------------------------------------
    @property
    def num_envs(self) -> int:
        return self._vec.num_envs

    @property
    def observation_space(self) -> gym.Space:
        return self._vec.observation_space

    @property
    def action_space(self) -> gym.Space:
        return self._vec.action_space

    @property
    def single_observation_space(self) -> gym.Space:
        return self._vec.single_observation_space

    @property
    def single_action_space(self) -> gym.Space:
        return self._vec.single_action_space

    @property
    def variation_space(self) -> gym.Space | None:
        return self._vec.variation_space

    @property
    def single_variation_space(self) -> gym.Space | None:
        return self._vec.single_variation_space

    # -- seeds and options ---------------------------------------------------------------
    def draw_seeds(self, n: int) -> list[int]:
        """``n`` fresh seeds from the world's generator (seeded by ``seed``)."""
        return [int(s) for s in self._rng.integers(0, 2**31 - 1, size=n)]

    def _seeds(self, seed: int | Sequence[int] | None, n: int) -> list[int]:
        seed = check_seeds("World.reset", seed, n)
        if seed is None:
            return self.draw_seeds(n)
        if isinstance(seed, int):
            return [seed + i for i in range(n)]
        return seed

    def _options(self, options: dict | Sequence[dict | None] | None, n: int) -> list[dict | None]:
        return check_reset_options(options, n, self.single_observation_space)

    # -- env API ---------------------------------------------------------------------------
    def reset(self, seed: int | list[int] | None = None, options: dict | list[dict] | None = None) -> None:
        """Reset every env. ``seed``: None (fresh seeds from the world's generator), an int
        (env i gets ``seed + i``) or one seed per env; ``options``: one dict for all or one per env."""
        self.reset_envs(range(self.num_envs), seeds=self._seeds(seed, self.num_envs), options=options)

    def reset_envs(self, env_ids: Sequence[int], seeds: Sequence[int | None] | None = None, options=None) -> None:
        """Reset only ``env_ids`` (with aligned ``seeds`` / ``options`` lists) and refresh their rows."""
        from .batching import set_rows

        ids = self._vec.check_ids(list(env_ids))
        if seeds is None:
            seeds = self.draw_seeds(len(ids))
        elif isinstance(seeds, (Sequence, np.ndarray)) and not isinstance(seeds, str):
            seeds = [check_seed("World.reset_envs", s) for s in seeds]
        else:
            raise ConfigError(f"World.reset_envs requires one seed per env id ({len(ids)}) or None, got {seeds!r}")
        if len(seeds) != len(ids):
            raise ConfigError(f"World.reset_envs requires one seed per env id ({len(ids)}), got {len(seeds)}")
        opts = self._options(options, len(ids))
        obs, infos = self._vec.reset_envs(ids, seeds, opts)
        n = self.num_envs
        if not self._has_reset and len(ids) != n:
            raise ConfigError("World.reset_envs on a subset requires a full World.reset() first")
        self.infos = set_rows(self.infos, ids, infos, n)
        self.states = (
            set_rows(self.states, ids, obs, n) if isinstance(obs, dict) else _set_array_rows(self.states, ids, obs, n)
        )
        self.rewards = self.rewards.copy()
        self.terminateds = self.terminateds.copy()
        self.truncateds = self.truncateds.copy()
        self.rewards[ids] = 0.0
        self.terminateds[ids] = False
        self.truncateds[ids] = False
        self._has_reset = True

    def step(self) -> None:
        """Ask the policy for actions on :attr:`infos` and step every env once."""
        if self.policy is None:
            raise RuntimeError("World.step requires a policy: call world.set_policy(policy) first")
        if not self._has_reset:
            raise RuntimeError("World.step requires a reset first: call world.reset()")
        actions = self.policy.get_action(self.infos)
        self.states, self.rewards, self.terminateds, self.truncateds, self.infos = self._vec.step(np.asarray(actions))

    def set_policy(self, policy: Any) -> None:
        """Attach ``policy``: it gets the batched env through ``set_env`` (and its ``seed`` through ``set_seed``)."""
        self.policy = policy
        policy.set_env(self.envs)
        seed = getattr(policy, "seed", None)
        if seed is not None and callable(getattr(policy, "set_seed", None)):
            policy.set_seed(seed)

    def close(self, **kwargs: Any) -> None:
        """Close every env (and the worker processes)."""
        self._vec.close(**kwargs)

    def __enter__(self) -> World:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def describe(self) -> str:
        """A human summary of the spaces (the library never prints it by itself)."""
        lines = [
            f"World {self.env_name!r}: {self.num_envs} envs ({self._vec.mode}), images {self.image_shape}, "
            f"history {self.history_size}, frame_skip {self.frame_skip}, max {self.max_episode_steps} steps",
            f"  observation: {self.single_observation_space}",
            f"  action: {self.single_action_space}",
        ]
        space = self.single_variation_space
        if space is not None and hasattr(space, "describe"):
            lines.append("  variation:\n" + "\n".join("    " + line for line in space.describe().splitlines()))
        return "\n".join(lines)

    # -- loops -----------------------------------------------------------------------------
    def evaluate(
        self,
        episodes: int | None = 10,
        eval_keys: list[str] | None = None,
        seed: int | None = None,
        options: dict | None = None,
        dump_every: int = -1,
        *,
        video: str | Path | None = None,
        reset_mode: str | None = None,
        dataset: Any = None,
        episodes_idx: Sequence[int] | None = None,
        start_steps: Sequence[int] | None = None,
        goal_offset: int | None = None,
        eval_budget: int | None = None,
        callables: list[dict] | None = None,
    ) -> dict:
        """Run the policy for ``episodes`` episodes; success = ``terminated``, truncation = failure.

        Returns ``success_rate`` (percent), ``episode_count``, ``episode_successes`` (bool, one per episode in seed
        order), ``seeds`` (unique; ``seed + k`` for episode k when ``seed`` is given), and for
        each of ``eval_keys`` the value of ``infos[key]`` (last history frame) at the end of each
        episode. ``dump_every > 0`` writes the results so far as JSON to
        ``<cache>/evaluations/<env>_<seed>.json`` every ``dump_every`` finished episodes;
        ``video`` writes ``episode_<k>.mp4`` per episode into that folder.

        Upstream 0.1.1's dataset-driven form: ``evaluate(dataset=..., episodes_idx=...,
        start_steps=..., goal_offset=..., eval_budget=..., callables=...)`` is
        :meth:`evaluate_from_dataset`. ``reset_mode`` (``"auto"``, or ``"wait"`` where each env
        plays at most one episode) is accepted as 0.1.1 names it.
        """
        if dataset is not None:
            missing = [
                k
                for k, v in (
                    ("episodes_idx", episodes_idx),
                    ("start_steps", start_steps),
                    ("goal_offset", goal_offset),
                    ("eval_budget", eval_budget),
                )
                if v is None
            ]
            if missing:
                raise ConfigError(f"World.evaluate(dataset=...) requires {', '.join(missing)} too")
            return self.evaluate_from_dataset(
                dataset,
                episodes_idx,
                start_steps,
                goal_offset,
                eval_budget,
                callables=callables,
                save_video=video is not None,
                video_path=video if video is not None else "./",
            )
        if reset_mode not in (None, "auto", "wait"):
            raise ConfigError(f"World.evaluate requires reset_mode 'auto', 'wait' or None, got {reset_mode!r}")
        if episodes is None:
            episodes = self.num_envs
        if reset_mode == "wait" and isinstance(episodes, int) and episodes > self.num_envs:
            raise ConfigError(
                "World.evaluate(reset_mode='wait') plays one episode per env: "
                f"episodes <= num_envs ({self.num_envs}), got {episodes}"
            )
        return _evaluate(
            self, episodes=episodes, eval_keys=eval_keys, seed=seed, options=options, dump_every=dump_every, video=video
        )

    def record_dataset(
        self,
        dataset_name: str,
        episodes: int = 10,
        seed: int | None = None,
        cache_dir=None,
        options: dict | None = None,
    ) -> Path:
        """Record ``episodes`` complete episodes into ``<cache_dir>/<dataset_name>.h5`` (see :mod:`.recording`)."""
        from .recording import record_dataset

        return record_dataset(self, dataset_name, episodes=episodes, seed=seed, cache_dir=cache_dir, options=options)

    def collect(
        self,
        path=None,
        episodes: int = 0,
        seed: int | None = None,
        options: dict | None = None,
        format: str | None = None,
        writer: Any = None,
        progress: bool = True,
    ) -> None:  # noqa: A002
        """Upstream 0.1.1's recorder: ``episodes`` more episodes to ``path`` (any registered format) or ``writer``
        (see :func:`.recording.collect`)."""
        from .recording import collect

        collect(
            self, path, episodes=episodes, seed=seed, options=options, format=format, writer=writer, progress=progress
        )

    def record_video(
        self,
        video_path,
        max_steps: int = 500,
        fps: int = 30,
        viewname: str | list[str] = "pixels",
        seed: int | None = None,
        options: dict | None = None,
    ):
        """One MP4 per env of a rollout under the current policy (observation above goal)."""
        from .recording import record_video

        return record_video(
            self, video_path, max_steps=max_steps, fps=fps, viewname=viewname, seed=seed, options=options
        )

    def record_video_from_dataset(
        self,
        video_path,
        dataset_name,
        episode_idx,
        max_steps: int = 500,
        fps: int = 30,
        num_proc: int = 4,
        viewname: str | list[str] = "pixels",
        cache_dir=None,
    ):
        """Replay recorded episodes of ``dataset_name`` as MP4 videos."""
        from .recording import record_video_from_dataset

        return record_video_from_dataset(
            self,
            video_path,
            dataset_name,
            episode_idx,
            max_steps=max_steps,
            fps=fps,
            num_proc=num_proc,
            viewname=viewname,
            cache_dir=cache_dir,
        )

    def evaluate_from_dataset(
        self,
        dataset: Any,
        episodes_idx: Sequence[int],
        start_steps: Sequence[int],
        goal_offset_steps: int,
        eval_budget: int,
        callables: list[dict] | None = None,
        save_video: bool = True,
        video_path: str | Path = "./",
    ) -> dict:
        """Start each env from a recorded state, with the state ``goal_offset_steps`` later as goal."""
        from .recording import evaluate_from_dataset

        return evaluate_from_dataset(
            self,
            dataset,
            episodes_idx,
            start_steps,
            goal_offset_steps,
            eval_budget,
            callables=callables,
            save_video=save_video,
            video_path=video_path,
        )


def render_bound(env_name: str) -> bool:
    """True for envs whose step is dominated by rendering (the MuJoCo envs: tag ``mujoco``)."""
    from ..envs._registry import _ENTRIES

    entry = _ENTRIES.get(env_name)
    return entry is not None and "mujoco" in entry.tags


def _set_array_rows(current, ids, value, n):
    if current is None or len(ids) == n:
        return value
    out = current.copy()
    out[ids] = value
    return out


def _apply_callables(env: Any, callables: Sequence[Any], init_state: dict) -> None:
    """Call ``env.<method>(**args)`` for each spec of ``callables`` on one env (upstream 0.1.1's
    private helper, which research code calls directly; the World itself goes through
    :func:`~stable_worldmodel.world.recording._apply_callables`, batched over its envs).

    A spec is ``{"method": name, "args": {arg: {"value": key, "in_dataset": True}}}``: an
    ``in_dataset`` argument is a copy of ``init_state[key]`` (left out when the key is missing),
    otherwise ``value`` itself. A method ``env`` lacks is skipped, as upstream's.
    """
    from copy import deepcopy

    for spec in callables or ():
        method = spec["method"]
        if not hasattr(env, method):
            continue
        kwargs = {}
        for arg, data in spec.get("args", {}).items():
            if data.get("in_dataset", True):
                key = data.get("value")
                if key in init_state:
                    kwargs[arg] = deepcopy(init_state[key])
            else:
                kwargs[arg] = data.get("value")
        getattr(env, method)(**kwargs)

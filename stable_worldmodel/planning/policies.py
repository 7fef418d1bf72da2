"""Policies and worlds by name, as the ``swm`` commands, the Ray tasks and the benchmarks build
them: checking an env id, a policy name (``random``, ``expert``, ``wm:<run>``, ``gc:<run>``) and
factor names, building a :class:`~stable_worldmodel.World`, and evaluating a policy in it.

Heavy modules (the World, its envs, torch) are imported inside the functions.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

from .. import keys
from ..envs._registry import make_env
from ..errors import unknown_name

if TYPE_CHECKING:
    from ..world import World

POLICIES = ("random", "expert", "weak")
#: ``WeakPolicy``'s default square half-side around the block (upstream's ``dist_constraint``)
WEAK_DIST_CONSTRAINT = 100.0
#: episode limit of envs registered without one
DEFAULT_MAX_STEPS = 100


def resolve_env(env_id: str) -> str:
    """``env_id`` when it is a registered ``swm/...`` (or Gymnasium) id, else a "did you mean" error."""
    import gymnasium as gym

    from ..envs import list_envs

    if env_id in list_envs() or env_id in gym.registry:
        return env_id
    if f"swm/{env_id}" in list_envs():  # upstream 0.1.1 accepts `swm fovs PushT-v1`
        return f"swm/{env_id}"
    raise unknown_name("environment", env_id, list_envs())


#: prefix of a learned world model policy: ``wm:<run>`` plans with checkpoint ``<run>``
WM_PREFIX = "wm:"
#: prefix of a goal-conditioned policy: ``gc:<run>`` acts with checkpoint ``<run>`` (gcbc, gcivl, gciql)
GC_PREFIX = "gc:"
#: what ``--policy`` accepts
POLICY_CHOICES = (*POLICIES, f"{WM_PREFIX}<run>", f"{GC_PREFIX}<run>")


def checkpoint_run(name: str) -> str | None:
    """The run of a ``wm:<run>`` / ``gc:<run>`` policy name (None for the others)."""
    for prefix in (WM_PREFIX, GC_PREFIX):
        if name.startswith(prefix):
            return name[len(prefix) :]
    return None


def check_policy(name: str) -> str:
    """``name`` when it is one of :data:`POLICIES`, ``wm:<run>`` or ``gc:<run>`` (a checkpoint that exists)."""
    run = checkpoint_run(name)
    if run is not None:
        from ..wm.run import Run

        if not run:
            raise unknown_name("policy", name, POLICY_CHOICES)
        Run.open(name)  # FileNotFoundError naming where it looked, with "did you mean"; opened once per command
        return name
    if name not in POLICY_CHOICES:
        raise unknown_name("policy", name, POLICY_CHOICES)
    return name


def policy_history(name: str) -> int:
    """Frames of history the policy ``name`` acts on: a ``gc:<run>``'s recorded ``history_size``
    (``protocol.json``, else the model's in ``config.json``), else 1."""
    if not name.startswith(GC_PREFIX):
        return 1
    import json

    from ..wm.run import Run
    from ..wm.utils import CONFIG_NAME

    run = Run.open(name)
    history = run.protocol.history_size
    if history is None and (run.folder / CONFIG_NAME).is_file():
        try:
            history = json.loads((run.folder / CONFIG_NAME).read_text()).get("history_size")
        except (ValueError, AttributeError):  # an unreadable config fails later, with its own message
            history = None
    return int(history or 1)


#: action noise of an expert recording a dataset (``swm collect``), for experts that take
#: ``noise``, in units of the env's action bound: world models learn what actions do only from
#: actions that vary
COLLECT_NOISE = 1.0


def expert_takes_noise(env_id: str) -> bool:
    """Whether the scripted expert of ``env_id`` takes a ``noise`` argument (Gaussian action noise)."""
    import inspect

    from ..envs import get_entry, load_object

    expert = get_entry(env_id).expert
    return expert is not None and "noise" in inspect.signature(load_object(expert)).parameters


def recording_noise(policy: str, env_id: str, noise: float | None) -> float | None:
    """The expert action noise of a recording: ``noise`` when given, else :data:`COLLECT_NOISE`
    times the env's largest action bound (1.0 for actions in [-1, 1], 0.2 for
    ``swm/SimplePointMaze-v0``'s) for an expert that takes noise; ``None`` (no noise) otherwise
    or when ``noise`` is 0."""
    if noise is None and policy == "expert" and expert_takes_noise(env_id):
        noise = COLLECT_NOISE * _action_bound(env_id)
    return noise or None


def _action_bound(env_id: str) -> float:
    """The largest finite ``|high|`` of the env's Box action space (1.0 when it has none)."""
    import gymnasium as gym
    import numpy as np

    env = make_env(env_id, disable_env_checker=True)
    try:
        space = env.action_space
        if isinstance(space, gym.spaces.Box):
            bound = np.abs(np.concatenate([space.low.ravel(), space.high.ravel()]))
            bound = bound[np.isfinite(bound)]
            if bound.size:
                return float(bound.max())
        return 1.0
    finally:
        env.close()


def make_policy(
    name: str,
    env_id: str,
    seed: int | None = None,
    plan: Any = None,
    device: str = "auto",
    noise: float | None = None,
    repeat_prob: float | None = None,
    dist_constraint: float | None = None,
) -> Any:
    """A fresh batched policy: ``random`` (seeded with ``seed``), the env's scripted ``expert``
    (with Gaussian action ``noise`` of that std, seeded, when given), ``weak`` (PushT's
    block-centred random collector, ``WeakPolicy(dist_constraint)``, upstream's Push-T data),
    ``wm:<run>`` planning with checkpoint ``<run>`` (``plan``: a
    :class:`~stable_worldmodel.planning.learned.PlanSettings`), or ``gc:<run>`` acting with the
    goal-conditioned policy of checkpoint ``<run>``. ``repeat_prob``: each env repeats its
    previous action with that probability (:class:`~stable_worldmodel.policy.RepeatActionPolicy`)."""
    from ..errors import ConfigError

    name = check_policy(name)
    if noise is not None and (name != "expert" or not expert_takes_noise(env_id)):
        raise ConfigError(
            f"--noise requires the expert policy of an env whose expert takes action noise, "
            f"got policy {name!r} on {env_id}"
        )
    if dist_constraint is not None and name != "weak":
        raise ConfigError(f"--dist-constraint requires --policy weak, got policy {name!r}")
    if name == "weak" and "PushT" not in env_id:
        raise ConfigError(f"--policy weak requires a PushT environment (swm/PushT-v1, ...), got {env_id}")
    if repeat_prob and checkpoint_run(name) is not None:
        raise ConfigError(f"--repeat-prob requires a collection policy (random, expert, weak), got {name!r}")
    policy = _base_policy(name, env_id, seed, plan, device, noise, dist_constraint)
    if repeat_prob:
        from ..policy import RepeatActionPolicy

        policy = RepeatActionPolicy(policy, repeat_prob, seed=seed)
    return policy


def _base_policy(
    name: str, env_id: str, seed: int | None, plan: Any, device: str, noise: float | None, dist_constraint: float | None
) -> Any:
    from ..envs import expert_policy
    from ..policy import RandomPolicy

    if name.startswith(WM_PREFIX):
        from ..planning.learned import PlanSettings, world_model_policy

        settings = plan or PlanSettings(seed=seed or 0)
        return world_model_policy(name[len(WM_PREFIX) :], settings, device=device)[0]
    if name.startswith(GC_PREFIX):
        from ..planning.goal_policy import goal_conditioned_policy

        return goal_conditioned_policy(name[len(GC_PREFIX) :], device=device)[0]
    if name == "random":
        return RandomPolicy(seed=seed)
    if name == "weak":
        from ..envs.pusht.weak import WeakPolicy

        return WeakPolicy(WEAK_DIST_CONSTRAINT if dist_constraint is None else dist_constraint, seed=seed)
    return expert_policy(env_id) if noise is None else expert_policy(env_id, noise=noise, seed=seed)


#: side of the square images of a command with no checkpoint policy to take it from
DEFAULT_IMAGE_SIZE = 64


def run_image_size(policies: Sequence[str]) -> int:
    """The side of the frames the first ``wm:`` / ``gc:`` run of ``policies`` was trained on
    (:data:`DEFAULT_IMAGE_SIZE` when there is none, or it does not record one)."""
    from ..planning.run_fit import run_facts

    for name in policies:
        run = checkpoint_run(name)
        if run is not None:
            frame = run_facts(run)[0].frame_size
            if frame is not None:
                return int(frame[0])
    return DEFAULT_IMAGE_SIZE


def env_action_dim(env_id: str) -> int | None:
    """Numbers in one action of ``env_id`` (1 for a ``Discrete`` space; None when the space has no shape)."""
    import numpy as np

    env = make_env(env_id, disable_env_checker=True)
    try:
        shape = env.action_space.shape
        return None if shape is None else int(np.prod(shape))
    finally:
        env.close()


def check_factors(world: World, factors: Sequence[str]) -> list[str]:
    """``factors`` (``"all"``, a factor name or a group such as ``agent``)
    checked against the world's variation space."""
    factors = list(factors)
    if not factors:
        return factors
    space = world.single_variation_space
    names = list(space.names()) if space is not None else []
    for name in factors:
        if name != "all" and name not in names and not any(n.startswith(name + ".") for n in names):
            raise unknown_name(f"factor of variation of {world.env_name}", name, ["all", *names])
    return factors


def reset_options(factors: Sequence[str]) -> dict | None:
    """The reset options that resample ``factors`` every episode (None when there are none)."""
    return {keys.VARIATION: list(factors)} if factors else None


def episode_limit(env_id: str, max_steps: int | None = None) -> int:
    """``max_steps`` when given, else the env's registered episode limit, else the tools' limit
    registered for it (``EnvEntry.tool_steps``), else :data:`DEFAULT_MAX_STEPS`."""
    from ..envs import get_entry

    if max_steps is not None:
        return int(max_steps)
    entry = get_entry(env_id)
    return int(entry.max_episode_steps or entry.tool_steps or DEFAULT_MAX_STEPS)


def make_world(
    env_id: str,
    num_envs: int = 1,
    image_size: int = 64,
    max_steps: int | None = None,
    seed: int | None = None,
    verbose: int | None = None,
    **kwargs: Any,
) -> World:
    """A World of ``num_envs`` copies of ``env_id`` with square ``image_size`` images and
    episodes cut after :func:`episode_limit` steps.

    ``verbose`` (progress of recording and evaluation) defaults to 1: a bar in a terminal, and
    otherwise a plain line every 30 s (:mod:`stable_worldmodel.world.progress`), so logs and pipes
    get no carriage-return spam and a long job is never silent.
    """
    from ..world import World

    if verbose is None:
        verbose = 1
    if seed is not None:
        kwargs["seed"] = seed
    limit = episode_limit(env_id, max_steps)
    return World(env_id, num_envs, (image_size, image_size), max_episode_steps=limit, verbose=verbose, **kwargs)


def evaluate_policy(
    world: World,
    policy_name: str,
    episodes: int,
    seed: int | None,
    factors: Sequence[str] = (),
    plan: Any = None,
    device: str = "auto",
) -> dict[str, Any]:
    """Set a fresh ``policy_name`` policy on ``world`` and run ``World.evaluate``.

    Episode ``k`` uses seed ``seed + k``, so two policies evaluated with the same ``seed``
    face the same start and goal configurations.
    """
    world.set_policy(make_policy(policy_name, world.env_name, seed=seed, plan=plan, device=device))
    return world.evaluate(episodes=episodes, seed=seed, options=reset_options(check_factors(world, factors)))


def variation_space_of(env_id: str) -> Any:
    """The variation space of a freshly made ``env_id`` (None when the env has none)."""

    env = make_env(resolve_env(env_id), disable_env_checker=True)
    try:
        return getattr(env.unwrapped, "variation_space", None)
    finally:
        env.close()

"""The environment registry: every ``swm/...`` id, its entry point, tags and expert.

Entry points are strings, so registering imports nothing heavy. Adding an env family
is one line in :data:`BUILTIN` (or a call to :func:`register_env` from user code).
"""

from __future__ import annotations

import importlib
import warnings
from dataclasses import dataclass, field
from typing import Any

from ..errors import UnknownNameError, did_you_mean


@dataclass(frozen=True)
class EnvEntry:
    """What the registry knows about one environment id."""

    env_id: str
    entry_point: str
    tags: tuple[str, ...] = ()
    expert: str | None = None  # "module:Class" of a batched expert policy
    kwargs: dict[str, Any] = field(default_factory=dict)
    max_episode_steps: int | None = None  # Gymnasium's TimeLimit (None: the env sets its own end, as upstream)
    tool_steps: int | None = None  # the swm tools' default episode limit where max_episode_steps is None


_ENTRIES: dict[str, EnvEntry] = {}
WORLDS: set[str] = set()  # 0.0.3's name: every id registered through us (kept in step with _ENTRIES)

_P = "stable_worldmodel.envs"
#: ids whose older version is a supported design of its own (upstream's), not an outdated one
SIDE_BY_SIDE = r"swm/(PushT(-Discrete)?-v1|TwoRoom-v[01]|SimplePointMaze-v0)"
#: DMControl domains with a scripted expert (:mod:`stable_worldmodel.envs.dmcontrol.expert`)
DMC_EXPERTS = ("cartpole", "pendulum", "reacher")
BUILTIN: tuple[EnvEntry, ...] = (
    EnvEntry(
        "swm/Toy-v0", f"{_P}.toy.env:ToyEnv", ("toy", "continuous"), f"{_P}.toy.env:ToyExpert", max_episode_steps=100
    ),
    EnvEntry(
        "swm/PushT-v1",
        f"{_P}.pusht.v1:PushTV1",
        ("paper", "continuous", "pymunk"),
        f"{_P}.pusht.v1_expert:PushTV1Expert",
        max_episode_steps=300,
    ),
    EnvEntry(
        "swm/PushT-Discrete-v1",
        f"{_P}.pusht.v1:PushTDiscreteV1",
        ("discrete", "pymunk"),
        f"{_P}.pusht.v1_expert:PushTDiscreteV1Expert",
        max_episode_steps=300,
    ),
    EnvEntry(
        "swm/PushT-v2",
        f"{_P}.pusht.env:PushT",
        ("continuous", "pymunk"),
        f"{_P}.pusht.expert:PushTExpert",
        max_episode_steps=300,
    ),
    EnvEntry(
        "swm/PushT-Discrete-v2",
        f"{_P}.pusht.env:PushTDiscrete",
        ("discrete", "pymunk"),
        f"{_P}.pusht.expert:PushTDiscreteExpert",
        max_episode_steps=300,
    ),
    # upstream 0.1.1's TwoRoom: no episode limit of its own, as upstream (swm tools cut at 100 steps)
    EnvEntry(
        "swm/TwoRoom-v1",
        f"{_P}.two_room.v1:TwoRoomV1Env",
        ("paper", "continuous"),
        f"{_P}.two_room.v1_expert:TwoRoomV1Expert",
    ),
    EnvEntry(
        "swm/TwoRoom-v2",
        f"{_P}.two_room.env:TwoRoomEnv",
        ("continuous",),
        f"{_P}.two_room.expert:TwoRoomExpert",
        max_episode_steps=100,
    ),
    EnvEntry(
        "swm/TwoRoom-v0",
        f"{_P}.two_room.v0:TwoRoomV0Env",
        ("continuous", "pymunk"),
        f"{_P}.two_room.v0_expert:TwoRoomV0Expert",
    ),
    EnvEntry(
        "swm/SimplePointMaze-v0",
        f"{_P}.simple_point_maze.v0:SimplePointMazeV0Env",
        ("continuous",),
        f"{_P}.simple_point_maze.v0_expert:SimplePointMazeV0Expert",
    ),
    EnvEntry(
        "swm/SimplePointMaze-v1",
        f"{_P}.simple_point_maze.env:SimplePointMazeEnv",
        ("continuous",),
        f"{_P}.simple_point_maze.expert:SimplePointMazeExpert",
        max_episode_steps=150,
    ),
    EnvEntry(
        "swm/ImagePositioning-v1",
        f"{_P}.image_positioning.env:ImagePositioningEnv",
        ("continuous",),
        f"{_P}.image_positioning.expert:ImagePositioningExpert",
        max_episode_steps=100,
    ),
    EnvEntry(
        "swm/VoidRun-v0",
        f"{_P}.voidrun.env:VoidRunEnv",
        ("discrete",),
        f"{_P}.voidrun.expert:VoidRunExpert",
        max_episode_steps=100,
    ),
    # release 0.0.3's MiniGrid maze (extra "minigrid"): no TimeLimit of its own, as 0.0.3 (the tools cut at
    # MiniGrid's 100 steps)
    EnvEntry(
        "swm/SimpleNavigation-v0",
        f"{_P}.simple_nav.env:SimpleNavigationEnv",
        ("discrete", "minigrid"),
        f"{_P}.simple_nav.expert:SimpleNavigationExpert",
        tool_steps=100,
    ),
    # MuJoCo (extra "mujoco"): no TimeLimit of their own, as upstream; the tools cut at OGBench's /
    # dm_control's episode lengths
    EnvEntry(
        "swm/OGBCube-v0",
        f"{_P}.ogbench.cube_env:CubeEnv",
        ("paper", "continuous", "mujoco"),
        f"{_P}.ogbench.expert:OGBenchExpert",
        tool_steps=200,
    ),
    EnvEntry(
        "swm/OGBScene-v0",
        f"{_P}.ogbench.scene_env:SceneEnv",
        ("continuous", "mujoco"),
        f"{_P}.ogbench.expert:OGBenchExpert",
        tool_steps=750,
    ),
    *(
        EnvEntry(
            f"swm/{name}DMControl-v0",
            f"{_P}.dmcontrol.{module}:{name}DMControlWrapper",
            ("continuous", "mujoco", "dmcontrol"),
            f"{_P}.dmcontrol.expert:DMControlExpert" if module in DMC_EXPERTS else None,
            tool_steps=1000,
        )
        for name, module in (
            ("Humanoid", "humanoid"),
            ("Cheetah", "cheetah"),
            ("Hopper", "hopper"),
            ("Reacher", "reacher"),
            ("Walker", "walker"),
            ("Acrobot", "acrobot"),
            ("Pendulum", "pendulum"),
            ("Cartpole", "cartpole"),
            ("BallInCup", "ball_in_cup"),
            ("Finger", "finger"),
            ("Manipulator", "manipulator"),
            ("Quadruped", "quadruped"),
        )
    ),
    # -- the families of upstream's main (issue 31); each family inserts its block right below this line --
    # PyFlyt's rocket landing (extra "pyflyt"): the env truncates after max_duration_seconds (30 s: 1200 steps)
    EnvEntry(
        "swm/PFRocketLanding-v0",
        f"{_P}.rocket_landing.pyflyt_rocketlanding:RocketLandingEnv",
        ("continuous", "pyflyt"),
        f"{_P}.rocket_landing.expert:RocketLandingExpert",
        tool_steps=1200,
    ),
    # upstream's Piecewise: no episode limit of its own, as upstream (swm tools cut at 100 steps)
    EnvEntry(
        "swm/Piecewise-v0",
        f"{_P}.piecewise.piecewise_env:PiecewiseEnv",
        ("continuous",),
        f"{_P}.piecewise.expert:PiecewiseExpert",
    ),
    # Craftax (extra "craftax"): craftax's own time limits (100000 / Classic 10000 steps) truncate; the tools cut
    # at 1000 steps; no expert (an open-ended game)
    *(
        EnvEntry(
            f"swm/{name}-v1",
            f"{_P}.craftax.craftax:{name}Wrapper",
            ("discrete", "craftax"),
            tool_steps=1000,
        )
        for name in ("CraftaxPixels", "CraftaxSymbolic", "CraftaxClassicPixels", "CraftaxClassicSymbolic")
    ),
    # OGBench's locomotion mazes (extra "mujoco"): no TimeLimit of their own, as upstream; the tools cut at
    # OGBench's 1000 steps (point / ant mazes)
    EnvEntry(
        "swm/OGBMaze-v0",
        f"{_P}.ogbench.maze_env:MazeEnv",
        ("continuous", "mujoco"),
        f"{_P}.ogbench.maze_expert:OGBMazeExpert",
        tool_steps=1000,
    ),
    # ALE (extra "ale"): ale-py's own ALE/<Game>-v5 ids (no factors, no goal) are registered with Gymnasium
    # only, lazily (no ale_py import), by register_all: stable_worldmodel.envs.ale.registration
    # Gymnasium-Robotics Fetch (extra "robotics"): Gymnasium-Robotics' 50 steps; never terminated, as upstream
    # (success: info["is_success"], eval_state). Slide has no scripted expert (see fetch/expert.py)
    *(
        EnvEntry(
            f"swm/Fetch{task}{variant}-v3",
            f"{_P}.fetch.env:FetchEnv",
            ("continuous", "robotics"),
            None if task == "Slide" else f"{_P}.fetch.expert:FetchExpert",
            {"env_id": f"Fetch{task}{'Dense' if variant == 'Dense' else ''}-v4"}
            | ({"flatten": False} if variant == "Dict" else {}),
            max_episode_steps=50,
        )
        for task in ("Reach", "Push", "Slide", "PickAndPlace")
        for variant in ("", "Dense", "Dict")
    ),
    # Gymnasium's classic control with factors (no extra: Gymnasium only); Gymnasium's episode limits
    *(
        EnvEntry(
            f"swm/{name}",
            f"{_P}.classic_control.{module}",
            ("classic_control", kind),
            f"{_P}.classic_control.expert:ClassicControlExpert",
            max_episode_steps=steps,
        )
        for name, module, kind, steps in (
            ("CartPoleControl-v1", "cartpole:CartPoleControlEnv", "discrete", 500),
            ("MountainCarControl-v0", "mountain_car:MountainCarControlEnv", "discrete", 200),
            ("MountainCarContinuousControl-v0", "mountain_car:MountainCarContinuousControlEnv", "continuous", 999),
            ("AcrobotControl-v1", "acrobot:AcrobotControlEnv", "discrete", 500),
            ("PendulumControl-v1", "pendulum:PendulumControlEnv", "continuous", 200),
        )
    ),
)


def register_env(
    env_id: str,
    entry_point: str,
    *,
    tags: tuple[str, ...] = (),
    expert: str | None = None,
    kwargs: dict[str, Any] | None = None,
    max_episode_steps: int | None = None,
    tool_steps: int | None = None,
) -> None:
    """Register ``env_id`` with Gymnasium and with our registry (idempotent)."""
    import gymnasium as gym

    entry = EnvEntry(env_id, entry_point, tuple(tags), expert, dict(kwargs or {}), max_episode_steps, tool_steps)
    _ENTRIES[env_id] = entry
    WORLDS.add(env_id)
    if env_id not in gym.registry:
        gym.register(id=env_id, entry_point=entry_point, kwargs=entry.kwargs, max_episode_steps=max_episode_steps)


def register_all() -> None:
    for entry in BUILTIN:
        register_env(
            entry.env_id,
            entry.entry_point,
            tags=entry.tags,
            expert=entry.expert,
            kwargs=entry.kwargs,
            max_episode_steps=entry.max_episode_steps,
            tool_steps=entry.tool_steps,
        )
    importlib.import_module(f"{_P}.ale.registration").register_ale_ids()


def make_env(env_id: str, **kwargs: Any) -> Any:
    """``gymnasium.make(env_id, **kwargs)`` without Gymnasium's "out of date" notice for the ids we
    support side by side (swm/PushT-v1 is upstream 0.1.1's PushT and v2 our design, TwoRoom-v0 is
    0.0.3's, v1 0.1.1's and v2 ours, SimplePointMaze-v0 0.1.1's and v1 ours): silenced here, for this
    call only (importing the package installs no warnings filter)."""
    import gymnasium as gym

    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", rf".*The environment {SIDE_BY_SIDE} is out of date", DeprecationWarning)
        return gym.make(env_id, **kwargs)


#: (tag, label) of the families an unknown-id message shows as one entry (``swm envs`` lists them)
_GROUPED = (
    ("classic_control", "swm/<Name>Control-v*"),
    ("dmcontrol", "swm/<Name>DMControl-v0"),
    ("robotics", "swm/Fetch<Task>[Dense|Dict]-v3"),
    ("craftax", "swm/Craftax[Classic]<Pixels|Symbolic>-v1"),
)


def list_envs(tag: str | None = None) -> list[str]:
    """Registered ``swm/...`` ids, optionally only those carrying ``tag``."""
    return sorted(e.env_id for e in _ENTRIES.values() if tag is None or tag in e.tags)


def get_entry(env_id: str) -> EnvEntry:
    """The registry entry of ``env_id``; unknown ids raise with a suggestion."""
    if env_id in _ENTRIES:
        return _ENTRIES[env_id]
    import gymnasium as gym

    if env_id in gym.registry:  # registered by someone else: still usable
        spec = gym.registry[env_id]
        ep = spec.entry_point if isinstance(spec.entry_point, str) else ""
        return EnvEntry(env_id, ep, (), None, dict(spec.kwargs), spec.max_episode_steps)
    ours = sorted(_ENTRIES)
    hint = did_you_mean(env_id, ours) or did_you_mean(env_id, [k for k in gym.registry if k not in _ENTRIES])
    shown, grouped = [], set()
    for tag, label in _GROUPED:  # families of many ids: one line each
        members = [e for e in ours if tag in _ENTRIES[e].tags]
        if members:
            shown.append(f"{label} ({len(members)})")
            grouped.update(members)
    shown = [e for e in ours if e not in grouped] + shown
    raise UnknownNameError(
        f"Unknown environment id {env_id!r}.{hint} Our worlds: {', '.join(shown)} "
        "(`swm envs` lists them all; any registered Gymnasium id works too)"
    )


def check_env_id(env_id: str) -> None:
    """Raise :class:`~stable_worldmodel.errors.UnknownNameError` when ``env_id`` is not registered."""
    get_entry(env_id)


def load_object(path: str) -> Any:
    """Import ``"package.module:Name"`` and return the attribute."""
    module, _, name = path.partition(":")
    return getattr(importlib.import_module(module), name)


def register(id: str, entry_point: str | Any) -> None:  # noqa: A002 - 0.0.3's signature
    """0.0.3's ``swm.envs.register(id, entry_point)``: :func:`register_env` with no tags or expert."""
    if isinstance(entry_point, str):
        register_env(id, entry_point)
        return
    import gymnasium as gym  # a class or factory: Gymnasium takes it as it is

    _ENTRIES[id] = EnvEntry(id, f"{entry_point.__module__}:{entry_point.__qualname__}")
    WORLDS.add(id)
    if id not in gym.registry:
        gym.register(id=id, entry_point=entry_point)

"""MegaWrapper: the standard pre-processing pipeline of World."""

from __future__ import annotations

from collections.abc import Callable, Iterable

import gymnasium as gym

from .. import keys
from .checks import EnsureGoalInfoWrapper, EnsureInfoKeysWrapper
from .goal import ResizeGoalWrapper
from .info import EverythingToInfoWrapper
from .pixels import AddPixelsWrapper
from .stack import StackedWrapper

PIXELS_PATTERN = rf"^{keys.PIXELS}(?:\..*)?$"


class _GoalIfAny:
    """Default of ``separate_goal``: true (a goal is resized when the env gives one) but not
    required, so goal-less envs work with the defaults. Prints as ``True``, the seed default;
    an explicit ``separate_goal=True`` requires the goal."""

    def __bool__(self) -> bool:
        return True

    def __repr__(self) -> str:
        return "True"

    def __reduce__(self) -> str:
        return "GOAL_IF_ANY"  # pickle/copy keep the singleton


GOAL_IF_ANY = _GoalIfAny()


class MegaWrapper(gym.Wrapper):
    """AddPixels -> EverythingToInfo -> EnsureInfoKeys -> [EnsureGoalInfo] -> ResizeGoal -> Stacked.

    - ``image_shape``: (H, W) of ``pixels`` and ``goal``.
    - ``pixels_transform`` / ``goal_transform``: callables on (H, W, 3) uint8 images.
    - ``required_keys``: extra regexes that must match info keys (``^pixels(?:\\..*)?$`` is always added).
    - ``separate_goal``: ``True`` requires ``info["goal"]`` after reset (goal-conditioned
      envs; ``World(goal_conditioned=True)`` passes it); the default (shown as ``True``)
      resizes the goal when the env gives one and accepts goal-less envs; ``False`` never checks.
    - ``history_size`` / ``frame_skip``: every info entry gets a history axis ``(T, ...)`` of the
      last ``history_size`` values spaced ``frame_skip`` steps apart.
    - ``goal_shape``: (H, W) of ``goal`` when it should differ from ``image_shape``.
    """

    def __init__(
        self,
        env: gym.Env,
        image_shape: tuple[int, int] = (84, 84),
        pixels_transform: Callable | None = None,
        goal_transform: Callable | None = None,
        required_keys: Iterable | None = None,
        separate_goal: Iterable | bool | None = GOAL_IF_ANY,
        history_size: int = 1,
        frame_skip: int = 1,
        goal_shape: tuple[int, int] | None = None,
        add_pixels: bool = True,
    ):
        required = [PIXELS_PATTERN, *(required_keys or [])] if add_pixels else list(required_keys or [])
        if add_pixels:  # False: envs without pixels (upstream 0.1.1's World(add_pixels=False))
            env = AddPixelsWrapper(env, image_shape, pixels_transform)
        env = EverythingToInfoWrapper(env)
        env = EnsureInfoKeysWrapper(env, required)
        if separate_goal is not GOAL_IF_ANY:
            env = EnsureGoalInfoWrapper(env, check_reset=bool(separate_goal), check_step=False)
        env = ResizeGoalWrapper(env, goal_shape or image_shape, goal_transform)
        env = StackedWrapper(env, None, history_size=history_size, frameskip=frame_skip)
        super().__init__(env)
        self.image_shape = tuple(image_shape)
        self.history_size = history_size
        self.frame_skip = frame_skip

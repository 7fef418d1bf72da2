"""Gymnasium's classic-control tasks with factors of variation and goals (upstream's ``gymnasium_control``).

``swm/CartPoleControl-v1``, ``swm/MountainCarControl-v0``, ``swm/MountainCarContinuousControl-v0``,
``swm/AcrobotControl-v1`` and ``swm/PendulumControl-v1``: Gymnasium's dynamics (written out so that
every constant is a factor), upstream's factors, a goal state, success by ``eval_state`` (ending
the episode with ``terminated``), frames drawn headless at the requested size, and scripted
experts (:mod:`.expert`). Each env module lists its rules; the shared behaviour:

- **Observation**: Gymnasium's vector (float32); ``info["state"]`` = ``info["proprio"]`` = it (as
  upstream's ``state``), ``info["goal_state"]`` / ``["goal_proprio"]`` the goal's, ``info["goal"]``
  the goal drawn like the frames, ``info["env_name"]`` the Gymnasium id (upstream's).
- **Reset**: as upstream, every factor is resampled (seeded with the reset seed) unless
  ``options["variation"]`` names the ones to resample (``[]``: none, the defaults);
  ``options["variation_values"]`` sets factors; ``options["state"]`` / ``["goal_state"]`` (in the
  observation layout) set the start and the goal. The start otherwise is Gymnasium's draw for the
  seed.
- **Episode limits** (registry): Gymnasium's, 500 / 200 / 999 / 500 / 200 steps.

The classes are resolved lazily so that importing this package draws in nothing heavy.
"""

from __future__ import annotations

from ..._lazy import lazy_getattr

__all__ = [
    "AcrobotControlEnv",
    "CartPoleControlEnv",
    "ClassicControlExpert",
    "MountainCarContinuousControlEnv",
    "MountainCarControlEnv",
    "PendulumControlEnv",
]
_WHERE = {
    "AcrobotControlEnv": ".acrobot",
    "CartPoleControlEnv": ".cartpole",
    "ClassicControlExpert": ".expert",
    "MountainCarContinuousControlEnv": ".mountain_car",
    "MountainCarControlEnv": ".mountain_car",
    "PendulumControlEnv": ".pendulum",
}

__getattr__ = lazy_getattr(__name__, _WHERE)

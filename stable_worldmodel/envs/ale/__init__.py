"""The Arcade Learning Environment through ale-py (extra ``ale``): the ``ALE/<Game>-v5`` ids.

``import stable_worldmodel`` registers ale-py's ``ALE/<Game>-v5`` ids with Gymnasium without
importing ale-py (:mod:`.registration`, the game list is data), so ``gym.make("ALE/Pong-v5")``
and ``swm.World("ALE/Pong-v5", ...)`` work as they would after ``import ale_py``: the first one
made imports ale-py, whose own registration then takes over (same entry point, same defaults).
Without ale-py, making one says ``pip install "stable-worldmodel[ale]"``.

These are ale-py's envs as they are, as upstream's main exposes them: no factors of variation,
no goal (``World`` runs them as goal-less envs), no scripted expert. :mod:`.atari_wrappers` has
upstream's Atari-100k protocol (:func:`make_atari_env`: no-op starts, FIRE on reset, a lost life
ends the episode, rewards clipped to their sign).
"""

from __future__ import annotations

from ..._lazy import lazy_getattr

__all__ = ["ClipRewardEnv", "EpisodicLifeEnv", "FireResetEnv", "NoopResetEnv", "make_atari_env"]

__getattr__ = lazy_getattr(
    __name__,
    {
        "ClipRewardEnv": ".atari_wrappers",
        "EpisodicLifeEnv": ".atari_wrappers",
        "FireResetEnv": ".atari_wrappers",
        "NoopResetEnv": ".atari_wrappers",
        "make_atari_env": ".atari_wrappers",
    },
)

"""The Atari-100k evaluation protocol (upstream's ``make_atari_env``), as Gymnasium wrappers.

- :class:`NoopResetEnv`: after a reset, 1 to ``max_noop`` NOOP actions (drawn from the env's
  seeded generator), so episodes start in different frames.
- :class:`FireResetEnv`: presses FIRE after a reset (games that wait for it: Breakout...).
- :class:`EpisodicLifeEnv`: losing a life ends the episode (``terminated``).
- :class:`ClipRewardEnv`: rewards become their sign (-1, 0, 1).
- :func:`make_atari_env`: ``gym.make`` of an ``ALE/<Game>-v5`` id with the full 18-action set,
  mode and difficulty 0, sticky actions (0.25), 4-frame skip, at most 27,000 steps, then those
  wrappers (each optional), and a first ``reset(seed=seed)``; ``img_size`` also resizes the
  frames to ``img_size x img_size`` (upstream's latest version returns 64x64 frames).
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np

from ...errors import ConfigError, check_int


class NoopResetEnv(gym.Wrapper):
    """Perform 1 to ``max_noop`` NOOP actions after each reset (the env's seeded generator draws the number)."""

    def __init__(self, env: gym.Env, max_noop: int = 30):
        super().__init__(env)
        self.max_noop = check_int("NoopResetEnv", "max_noop", max_noop)
        meanings = env.unwrapped.get_action_meanings()
        if meanings[0] != "NOOP":
            raise ConfigError(f"NoopResetEnv requires action 0 to be NOOP, got the actions {meanings}")

    def reset(self, **kwargs: Any):
        obs, info = self.env.reset(**kwargs)
        for _ in range(int(self.env.unwrapped.np_random.integers(1, self.max_noop + 1))):
            obs, _, terminated, truncated, info = self.env.step(0)
            if terminated or truncated:
                kwargs.pop("seed", None)
                obs, info = self.env.reset(**kwargs)
                break
        return obs, info


class FireResetEnv(gym.Wrapper):
    """Press FIRE after each reset, for the games that wait for it."""

    def __init__(self, env: gym.Env):
        super().__init__(env)
        meanings = env.unwrapped.get_action_meanings()
        if len(meanings) < 2 or meanings[1] != "FIRE":
            raise ConfigError(f"FireResetEnv requires action 1 to be FIRE, got the actions {meanings}")

    def reset(self, **kwargs: Any):
        obs, info = self.env.reset(**kwargs)
        obs, _, terminated, truncated, info = self.env.step(1)
        if terminated or truncated:
            kwargs.pop("seed", None)
            obs, info = self.env.reset(**kwargs)
        return obs, info


class EpisodicLifeEnv(gym.Wrapper):
    """End the episode (``terminated``) when a life is lost; a reset restarts the game."""

    def __init__(self, env: gym.Env):
        super().__init__(env)
        self.lives = 0

    def step(self, action):
        obs, reward, terminated, truncated, info = self.env.step(action)
        lives = self.env.unwrapped.ale.lives()
        if 0 < lives < self.lives:
            terminated = True
        self.lives = lives
        return obs, reward, terminated, truncated, info

    def reset(self, **kwargs: Any):
        obs, info = self.env.reset(**kwargs)
        self.lives = self.env.unwrapped.ale.lives()
        return obs, info


class ClipRewardEnv(gym.RewardWrapper):
    """Rewards clipped to their sign: -1, 0 or 1."""

    def reward(self, reward):
        return float(np.sign(reward))


def make_atari_env(
    env_name: str,
    seed: int = 0,
    frameskip: int = 4,
    max_episode_steps: int = 27000,
    clip_reward: bool = True,
    episodic_life: bool = True,
    noop_max: int = 30,
    fire_reset: bool = True,
    repeat_action_probability: float = 0.25,
    img_size: int | None = None,
) -> gym.Env:
    """An Atari env under the Atari-100k protocol (module docstring), reset once with ``seed``.

    ``env_name``: an ``ALE/<Game>-v5`` id (``"ALE/Breakout-v5"``).
    """
    frameskip = check_int("make_atari_env", "frameskip", frameskip)
    max_episode_steps = check_int("make_atari_env", "max_episode_steps", max_episode_steps)
    noop_max = check_int("make_atari_env", "noop_max", noop_max, minimum=0)
    if not 0.0 <= repeat_action_probability <= 1.0:
        raise ConfigError(
            f"make_atari_env requires repeat_action_probability in [0, 1], got {repeat_action_probability!r}"
        )
    env = gym.make(
        env_name,
        obs_type="rgb",
        frameskip=frameskip,
        mode=0,
        difficulty=0,
        repeat_action_probability=repeat_action_probability,
        full_action_space=True,
        max_episode_steps=max_episode_steps,
    )
    if noop_max > 0:
        env = NoopResetEnv(env, max_noop=noop_max)
    if fire_reset:
        env = FireResetEnv(env)
    if episodic_life:
        env = EpisodicLifeEnv(env)
    if clip_reward:
        env = ClipRewardEnv(env)
    if img_size is not None:
        size = check_int("make_atari_env", "img_size", img_size)
        env = gym.wrappers.ResizeObservation(env, (size, size))
    env.reset(seed=seed)
    return env


__all__ = ["ClipRewardEnv", "EpisodicLifeEnv", "FireResetEnv", "NoopResetEnv", "make_atari_env"]

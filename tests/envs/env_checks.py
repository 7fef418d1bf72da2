"""Checks shared by the env tests (imported by them; pytest collects nothing here)."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from stable_worldmodel import keys


def run_actions(env, seed: int, actions, options=None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Reset with ``seed``/``options``, play ``actions``: frames (T+1, H, W, 3), states (T+1, D), goal image."""
    obs, info = env.reset(seed=seed, options=options)
    frames, states = [env.render()], [_state(obs)]
    for a in actions:
        obs, *_ = env.step(a)
        frames.append(env.render())
        states.append(_state(obs))
    return np.stack(frames), np.stack(states), info[keys.GOAL]


def _state(obs) -> np.ndarray:
    """``obs[state]`` of a dict observation; a flat observation (``swm/SimplePointMaze-v0``) is the state."""
    return obs[keys.STATE] if isinstance(obs, dict) else np.asarray(obs)


def factor_value(env, name: str) -> np.ndarray:
    """The current value of the dotted factor ``name`` of ``env.variation_space``."""
    v = env.variation_space.value
    for part in name.split("."):
        v = v[part]
    return np.asarray(v)


def assert_factor_changes_episode(env, name: str, rollout: Callable, seed: int = 3, tries: int = 10) -> None:
    """Setting factor ``name`` away from its default changes what ``rollout(env, seed, options)`` returns.

    The new value is the farthest from the default among ``tries`` resamples, so that a draw
    too close to the default cannot hide a factor that works.
    """
    ref = rollout(env, seed, None)
    env.reset(seed=seed)
    default = factor_value(env, name).astype(np.float64)
    values = []
    for s in range(tries):
        env.reset(seed=s, options={keys.VARIATION: [name]})
        values.append(factor_value(env, name))
    value = max(values, key=lambda v: np.abs(v.astype(np.float64) - default).sum())
    out = rollout(env, seed, {keys.VARIATION_VALUES: {name: value}})
    same = all(np.array_equal(a, b) for a, b in zip(ref, out, strict=False))
    assert not same, f"factor {name} = {value} (default {default}) changed nothing"


def assert_render_size(env, size: tuple[int, int]) -> None:
    """``env`` made with ``render_size=size`` draws frames and goal images of that size, then follows
    :meth:`set_render_size`."""
    _, info = env.reset(seed=0)
    frame = env.render()
    assert frame.shape == (*size, 3) and frame.dtype == np.uint8
    assert info[keys.GOAL].shape == (*size, 3) and info[keys.GOAL].dtype == np.uint8
    env.set_render_size((32, 40))
    _, info = env.reset(seed=0)
    assert env.render().shape == (32, 40, 3) and info[keys.GOAL].shape == (32, 40, 3)


def count_draws(env) -> list:
    """Wrap ``env._draw`` so that every call appends to the returned list."""
    draws: list = []
    draw = env._draw
    env._draw = lambda *args: draws.append(1) or draw(*args)
    return draws


def assert_expert_solves_in_world(env_id: str, num_envs: int, episodes: int, max_episode_steps: int) -> dict:
    """The registered expert solves every episode of ``World(env_id, num_envs).evaluate``; returns the infos."""
    import stable_worldmodel as swm

    world = swm.World(
        env_id,
        num_envs=num_envs,
        image_shape=(64, 64),
        max_episode_steps=max_episode_steps,
        verbose=0,
        vectorization_mode="sync",
    )
    world.set_policy(swm.envs.expert_policy(env_id))
    result = world.evaluate(episodes=episodes, seed=0)
    assert result["success_rate"] == 100.0, result
    assert world.infos[keys.PIXELS].shape == (num_envs, 1, 64, 64, 3)
    assert world.infos[keys.GOAL].shape == (num_envs, 1, 64, 64, 3)
    return world.infos

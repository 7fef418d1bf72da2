"""Analytic cost models with known minima and a configure helper, shared by the solver tests."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import torch

from stable_worldmodel.policy import PlanConfig


class Bowl:
    """``sum (a - target)^2`` over horizon and action dims; ``info["target"]: (B, S, A)``."""

    def __init__(self):
        self.calls = []

    def get_cost(self, info, candidates):
        self.calls.append((dict(info), candidates.shape))
        return ((candidates - info["target"].unsqueeze(2)) ** 2).sum(dim=(2, 3))


class DoubleWell:
    """``sum (a^2 - 1)^2 + 0.3 (a - s)^2`` with ``s = info["target"] in {-1, 1}``: minimum at ``a = s``,
    a worse local minimum at ``-s``."""

    def get_cost(self, info, candidates):
        s = info["target"].unsqueeze(2)
        return ((candidates**2 - 1) ** 2 + 0.3 * (candidates - s) ** 2).sum(dim=(2, 3))


def configure(solver, n_envs=3, shape=(2,), low=-1.0, high=1.0, horizon=1, receding_horizon=1, action_block=1):
    space = gym.spaces.Box(low, high, (n_envs, *shape), np.float32)
    solver.configure(
        action_space=space, n_envs=n_envs, config=PlanConfig(horizon, receding_horizon, action_block=action_block)
    )
    return solver


def targets(rows):
    return {"target": torch.tensor(rows, dtype=torch.float32)}

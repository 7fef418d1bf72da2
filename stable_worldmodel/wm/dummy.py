"""``DummyWorldModel`` (seed 000's ``stable_worldmodel.wm.dummy``): two linear layers over
flattened images, for tests and examples. It follows the world-model contract with
``(B, S, H, A)`` candidates."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
import torch
from torch import nn

from .. import keys
from ..errors import SpaceError, UnknownNameError
from .jepa import goal_distance

__all__ = ["DummyWorldModel"]


class DummyWorldModel(nn.Module):
    """``encoder = Linear(prod(image_shape), 10)``, ``predictor = Linear(10 + action_dim, 10)``.

    - ``encode(obs)`` adds ``embedding`` (and ``emb``) ``(..., 10)`` from ``obs["pixels"]``
      ``(..., *image_shape)`` (numpy arrays are converted).
    - ``predict(obs, actions)``: one step for a tensor ``(N, A)``, several for a list of them.
    - ``rollout(info, candidates (B, S, H, A))`` adds ``predicted_emb (B, S, H + 1, 10)``;
      ``get_cost`` is the squared distance of the last one (``goal_cost="final"``) or of the
      closest one (``"min"``) to the goal embedding ``(B, S)``.
    - ``loss(batch)``: next-embedding MSE on ``pixels (B, T, ...)`` / ``action (B, T, A)``.
    """

    def __init__(self, image_shape: Sequence[int], action_dim: int):
        super().__init__()
        self.image_shape, self.action_dim = tuple(int(v) for v in image_shape), int(action_dim)
        self.encoder = nn.Linear(int(np.prod(self.image_shape)), 10)
        self.predictor = nn.Linear(10 + self.action_dim, 10)
        self.goal_cost = "final"  # or "min" (see stable_worldmodel.wm.config.GOAL_COSTS); set by planning

    def _embed(self, pixels: Any) -> torch.Tensor:
        if isinstance(pixels, np.ndarray):
            pixels = torch.from_numpy(pixels)
        n = len(self.image_shape)
        flat = pixels.reshape(*pixels.shape[: pixels.ndim - n], -1).to(self.encoder.weight.dtype)
        return self.encoder(flat)

    def encode(self, obs: dict) -> dict:
        if keys.PIXELS not in obs:
            raise UnknownNameError(f"DummyWorldModel.encode requires obs['pixels'], got keys {sorted(obs)}")
        obs["embedding"] = obs["emb"] = self._embed(obs[keys.PIXELS])
        return obs

    def predict(self, obs: dict, actions: Any, timestep: int | None = None) -> torch.Tensor:
        """Next embedding from ``obs["embedding"] (N, 10)`` and ``actions (N, A)`` (or a list: rolled out)."""
        z = obs["embedding"]
        steps = [actions] if torch.is_tensor(actions) else list(actions)
        for a in steps:
            z = self.predictor(torch.cat([z, a.to(z.dtype)], dim=-1))
        return z

    def rollout(self, info: dict, candidates: torch.Tensor) -> dict:
        """Add ``predicted_emb (B, S, H + 1, 10)`` for ``candidates (B, S, H, A)`` (``(B, H + 1, 10)``
        for ``(B, H, A)``), starting from the last context frame's embedding."""
        single = candidates.ndim == 3
        if single:
            candidates = candidates.unsqueeze(1)
        if candidates.ndim != 4:
            raise SpaceError(
                "DummyWorldModel.rollout requires candidates (B, S, H, A) or (B, H, A), "
                f"got shape {tuple(candidates.shape)}"
            )
        b, s, h, _ = candidates.shape
        z = info.get("emb")
        if z is None:
            pixels = info[keys.PIXELS]
            pixels = pixels[:, 0] if pixels.ndim == len(self.image_shape) + 3 else pixels  # drop S
            z = info["emb"] = self._embed(pixels)  # (B, T, 10)
        if z.ndim == 3:
            z = z[:, -1]  # last context frame (B, 10)
        z = z.unsqueeze(1).expand(b, s, -1)
        out = [z]
        for k in range(h):
            z = self.predictor(torch.cat([z, candidates[:, :, k].to(z.dtype)], dim=-1))
            out.append(z)
        predicted = torch.stack(out, dim=2)
        info["predicted_emb"] = predicted[:, 0] if single else predicted
        return info

    def get_cost(self, info: dict, candidates: torch.Tensor) -> torch.Tensor:
        if "goal_emb" not in info:
            goal = info[keys.GOAL]
            goal = goal[:, 0] if goal.ndim == len(self.image_shape) + 3 else goal
            info["goal_emb"] = self._embed(goal)[:, -1]
        self.rollout(info, candidates)
        pred = info["predicted_emb"]  # (B, S, H + 1, 10) or (B, H + 1, 10): one context embedding
        goal = info["goal_emb"] if pred.ndim == 3 else info["goal_emb"].unsqueeze(1)
        return goal_distance(pred, goal, self.goal_cost, context=1)

    def loss(self, batch: dict) -> dict:
        emb = self._embed(batch[keys.PIXELS])  # (B, T, 10)
        action = torch.nan_to_num(batch[keys.ACTION], 0.0).to(emb.dtype)
        pred = self.predictor(torch.cat([emb[:, :-1], action[:, :-1]], dim=-1))
        loss = (
            (pred - emb[:, 1:]).square().mean()
        )  # no stop-gradient: with one, AdamW makes the embeddings (and the loss) grow
        return {"loss": loss, "pred_loss": loss, "emb": emb}

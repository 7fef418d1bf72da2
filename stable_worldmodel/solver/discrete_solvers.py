"""Solvers for discrete action spaces."""

from __future__ import annotations

import math
from typing import Any

import gymnasium as gym
import numpy as np
import torch
from gymnasium.vector.utils import batch_space

from ..errors import ConfigError, SpaceError
from ._registry import register_solver
from .base import PlanKnobs
from .gd import GradientSolver


def project_simplex(v: torch.Tensor) -> torch.Tensor:
    """Euclidean projection of every vector ``(..., n)`` onto the probability simplex."""
    n = v.shape[-1]
    u = torch.sort(v, dim=-1, descending=True).values
    css = u.cumsum(dim=-1) - 1
    k = torch.arange(1, n + 1, device=v.device, dtype=v.dtype)
    rho = (u - css / k > 0).sum(dim=-1, keepdim=True)
    theta = css.gather(-1, rho - 1) / rho.to(v.dtype)
    return (v - theta).clamp_min(0)


class DiscreteActions:
    """Mixin of the discrete solvers (:class:`PGDSolver`, ``CategoricalCEMSolver``): the action
    space is a single ``Discrete(n)`` (batched here to ``MultiDiscrete([n] * n_envs)``) or the
    batched ``MultiDiscrete`` of B envs of ``Discrete(n)`` / of a ``MultiDiscrete`` with equal
    ``nvec``; candidates are one-hot (or simplex) points ``(B, S, H, A * n)``."""

    #: plans discrete actions only (a Box env needs another solver)
    discrete_actions = True

    def configure(self, *, action_space: gym.Space, n_envs: int, config: Any) -> None:
        """Like :meth:`BaseSolver.configure`; a single ``Discrete(n)`` is batched to ``n_envs`` envs."""
        if isinstance(action_space, gym.spaces.Discrete):
            self._check_positive(n_envs=n_envs)
            action_space = batch_space(action_space, int(n_envs))
        super().configure(action_space=action_space, n_envs=n_envs, config=config)

    def _check_space(self, action_space: gym.Space) -> None:
        nvec = np.asarray(getattr(action_space, "nvec", []))
        if not isinstance(action_space, gym.spaces.MultiDiscrete) or nvec.size == 0 or (nvec != nvec.flat[0]).any():
            raise SpaceError(
                f"{type(self).__name__} requires a discrete action space (Action space must be discrete): "
                f"Discrete(n), or the batched MultiDiscrete with equal nvec, got {action_space!r}"
            )
        if (np.asarray(action_space.start) != 0).any():
            raise SpaceError(f"{type(self).__name__} requires actions starting at 0, got start={action_space.start}")

    @property
    def n_choices(self) -> int | None:
        """Choices per discrete action (n); None before :meth:`configure`."""
        return None if self._space is None else int(np.asarray(self._space.nvec).flat[0])

    @property
    def action_simplex_dim(self) -> int | None:
        """Width of the relaxed candidates given to ``get_cost``: ``action_dim * n``."""
        return None if self._space is None else self.action_dim * self.n_choices


@register_solver("pgd")
class PGDSolver(DiscreteActions, GradientSolver):
    """Projected gradient descent on the simplex relaxation of discrete actions.

    The action space is a single ``Discrete(n)`` (seed 000's form, batched here to
    ``MultiDiscrete([n] * n_envs)``) or the batched ``MultiDiscrete`` of B envs of
    ``Discrete(n)`` / of a ``MultiDiscrete`` with equal ``nvec``. Each of the
    ``A = action_dim`` integer actions of a block is relaxed to a point of the
    ``n``-simplex: ``get_cost`` receives candidates ``(B, S, H, A * n)`` (soft one-hots,
    :attr:`action_simplex_dim` = ``A * n``), projected back onto the simplex after every
    optimizer step. The answer is the argmax of the cheapest sample (re-scored as hard
    one-hots): ``actions: (B, H, A)`` of dtype int64, and ``costs: (B,)``.

    Warm start (``init_action`` of :meth:`solve`): simplex points ``(B, k <= H, A * n)``, or
    integer actions ``(B, k, A)`` with ``from_scalar=True`` (integer tensors, and arrays of
    width A, are read as actions anyway). Blocks after the k given start at the uniform
    point, as do all plans without warm start; ``var_scale`` noise is added to every sample
    but the warm start itself.
    """

    knobs = PlanKnobs(
        samples=None, fixed=(("num_samples", 1),), summary="projected gradient descent (discrete actions)"
    )

    # -- warm start --------------------------------------------------------------------------
    def solve(self, info_dict: dict, init_action: Any = None, from_scalar: bool = False) -> dict:
        """Plan for every env (see the class docstring for the two forms of ``init_action``)."""
        self._require_configured()
        return super().solve(info_dict, init_action=self._as_points(init_action, from_scalar))

    def __call__(self, info_dict: dict, init_action: Any = None, from_scalar: bool = False) -> dict:
        return self.solve(info_dict, init_action=init_action, from_scalar=from_scalar)

    def init_action(self, actions: Any = None, from_scalar: bool = False) -> None:
        """Draw the starting plans of the next :meth:`solve` into :attr:`init`: ``(B, S, H, A * n)``.

        ``actions`` as the warm start of :meth:`solve`; the random stream is not advanced.
        """
        self._require_configured()
        self.init = self._draw_start(self._pad_init(self._as_points(actions, from_scalar))).flatten(-2)

    def _as_points(self, init_action: Any, from_scalar: bool) -> torch.Tensor | None:
        """A warm start in either form -> simplex points ``(B, k, A, n)`` on the device."""
        if init_action is None:
            return None
        x = torch.as_tensor(init_action, device=self.device)
        b, h, a, n = self.n_envs, self.horizon, self.action_dim, self.n_choices
        scalar = bool(from_scalar) or not x.is_floating_point() or (n > 1 and x.ndim == 3 and x.shape[-1] == a)
        width = a if scalar else a * n
        if x.ndim != 3 or x.shape[0] != b or x.shape[1] > h or x.shape[2] != width:
            form = f"integer actions ({b}, k <= {h}, {a})"
            if not scalar:
                form = f"simplex points ({b}, k <= {h}, {a * n}) or " + form
            raise ConfigError(f"PGDSolver requires init_action as {form}, got shape {tuple(x.shape)}")
        if not scalar:
            return project_simplex(x.to(self.dtype).reshape(b, x.shape[1], a, n))
        index = (x.round() if x.is_floating_point() else x).long()
        if index.numel() and (index.min() < 0 or index.max() >= n):
            raise ConfigError(
                f"PGDSolver requires integer actions in [0, {n}), got values in "
                f"[{int(index.min())}, {int(index.max())}]"
            )
        return torch.nn.functional.one_hot(index, n).to(self.dtype)

    def _pad_init(self, points: torch.Tensor | None) -> torch.Tensor | None:
        """Simplex points ``(B, k, A, n)`` -> ``(B, H, A, n)``; the missing blocks are uniform."""
        if points is None or points.shape[1] == self.horizon:
            return points
        b, k = points.shape[:2]
        pad = points.new_full((b, self.horizon - k, self.action_dim, self.n_choices), 1.0 / self.n_choices)
        return torch.cat([points, pad], dim=1)

    # -- the relaxation ------------------------------------------------------------------------
    def _init_variable(self, init_action: torch.Tensor | None) -> torch.Tensor:
        b = self._rows[1] - self._rows[0]
        shape = (b, self.num_samples, self.horizon, self.action_dim, self.n_choices)
        noise = self.var_scale / math.sqrt(self.n_choices) * self._randn(*shape[1:])
        if init_action is None:
            start = torch.full(shape, 1.0 / self.n_choices, device=self.device, dtype=self.dtype)
        else:
            start = init_action.unsqueeze(1).expand(shape).clone()
            noise[:, 0] = 0
        return self._project(start + noise)

    def _project(self, x: torch.Tensor) -> torch.Tensor:
        return project_simplex(x)

    def _candidates(self, x: torch.Tensor) -> torch.Tensor:
        return x.flatten(-2)

    def _decode(self, x: torch.Tensor) -> torch.Tensor:
        return x.argmax(dim=-1)

    def _encode(self, plans: torch.Tensor) -> torch.Tensor:
        one_hot = torch.nn.functional.one_hot(plans.long(), self.n_choices)
        return one_hot.to(self.dtype).flatten(-2)

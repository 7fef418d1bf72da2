"""The starting distribution of the Gaussian sampling solvers (CEM, iCEM, MPPI), as a public method.

Seed 000 exposed it as ``init_action_distrib(actions=None) -> (mean, var)``; upstream 0.1.1 as
``init_action_distrib(n_envs, actions=None)``. Both call forms are accepted.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import torch

from ..errors import ArgumentTypeError, ConfigError

__all__ = ["GaussianStart"]


class GaussianStart:
    """Mixin for :class:`~stable_worldmodel.solver.base.BaseSolver` subclasses that sample around a mean."""

    def init_action_distrib(
        self, *args: Any, actions: Any = None, n_envs: int | None = None
    ) -> tuple[torch.Tensor, torch.Tensor]:
        """The Gaussian a solve starts from: ``mean: (B, H, A)`` and ``var: (B, H, A)``.

        ``mean`` is the warm start ``actions: (B, k <= H, A)`` padded with zeros, or zeros,
        clamped into the Box bounds exactly as :meth:`solve` does. ``var`` is ``var_scale``
        everywhere; like the ``var`` that :meth:`solve` returns, it is a standard deviation.
        Both are on the solver's device.

        Call forms: ``init_action_distrib(actions)`` (seed 000) and
        ``init_action_distrib(n_envs, actions)`` (upstream 0.1.1; ``n_envs`` must be the
        configured number of envs).
        """
        name = type(self).__name__
        if args and isinstance(args[0], (int, np.integer)) and not isinstance(args[0], (bool, np.bool_)):
            if n_envs is not None:
                raise ArgumentTypeError(f"{name}.init_action_distrib got n_envs twice")
            n_envs, args = int(args[0]), args[1:]
        if len(args) > 1 or (args and actions is not None):
            raise ArgumentTypeError(
                f"{name}.init_action_distrib takes (actions=None) or (n_envs, actions=None), got {len(args)} "
                "positional arguments" + (" and actions=" if actions is not None else "")
            )
        if args:
            actions = args[0]
        self._require_configured()
        if n_envs is not None and n_envs != self.n_envs:
            raise ConfigError(
                f"{name}.init_action_distrib requires n_envs equal to the configured n_envs={self.n_envs}, "
                f"got {n_envs}; call configure(...) with the new number of envs first"
            )
        mean = self._pad_init(actions)
        if mean is None:
            zeros = torch.zeros(self.n_envs, self.horizon, self.action_dim, device=self.device, dtype=self.dtype)
            mean = self._clamp(zeros, (0, self.n_envs))
        return mean, torch.full_like(mean, self.var_scale)

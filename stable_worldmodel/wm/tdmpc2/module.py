"""Building blocks and maths of TD-MPC2, with upstream 0.1.1's class names and ``state_dict``
layout (``NormedLinear.ln``, ``RunningScale.value``, ``mlp`` as a 3-layer ``Sequential``).

- :func:`symlog` / :func:`symexp` and :func:`two_hot` / :func:`two_hot_inv`: scalars (rewards,
  values) as a distribution over ``num_bins`` evenly spaced bins of ``symlog`` space
  ``[vmin, vmax]``; a scalar is split between its two neighbouring bins, so decoding the
  encoding gives it back (inside the range).
- :class:`SimNorm`: a softmax over each group of ``simplex_dim`` numbers of the latent.
- :class:`NormedLinear`: Linear -> (Dropout) -> LayerNorm -> activation (Mish by default).
- :class:`RunningScale`: an EMA of the 5-95 percentile range of the policy's Q values.
- :func:`log_std`, :func:`gaussian_logprob`, :func:`squash`: the tanh-Gaussian policy.
"""

from __future__ import annotations

import math

import torch
import torch.nn.functional as F
from torch import nn

from ...errors import ConfigError

__all__ = [
    "NormedLinear",
    "RunningScale",
    "SimNorm",
    "gaussian_logprob",
    "log_std",
    "mlp",
    "squash",
    "symexp",
    "symlog",
    "two_hot",
    "two_hot_inv",
    "weight_init",
]

_LOG_SQRT_2PI = 0.5 * math.log(2 * math.pi)


# -- scalars as bins --------------------------------------------------------------------------
def symlog(x: torch.Tensor) -> torch.Tensor:
    """``sign(x) * log(1 + |x|)``: compresses large magnitudes, keeps small ones."""
    return torch.sign(x) * torch.log1p(x.abs())


def symexp(x: torch.Tensor) -> torch.Tensor:
    """The inverse of :func:`symlog`."""
    return torch.sign(x) * torch.expm1(x.abs())


def _bins(num_bins: int, vmin: float, vmax: float, like: torch.Tensor) -> torch.Tensor:
    return torch.linspace(vmin, vmax, num_bins, device=like.device, dtype=like.dtype)


def two_hot(x: torch.Tensor, num_bins: int, vmin: float, vmax: float) -> torch.Tensor:
    """``x (...)`` -> ``(..., num_bins)`` probabilities: ``symlog(x)`` (clamped to
    ``[vmin, vmax]``) split linearly between its two neighbouring bins."""
    if num_bins < 2:
        raise ConfigError(f"two_hot requires num_bins >= 2, got {num_bins}")
    y = symlog(x).clamp(vmin, vmax)
    pos = (y - vmin) / ((vmax - vmin) / (num_bins - 1))
    low = pos.floor().long().clamp(0, num_bins - 2)
    frac = (pos - low).unsqueeze(-1)
    out = torch.zeros(*x.shape, num_bins, device=x.device, dtype=x.dtype)
    out.scatter_(-1, low.unsqueeze(-1), 1 - frac)
    out.scatter_add_(-1, low.unsqueeze(-1) + 1, frac)
    return out


def two_hot_inv(logits: torch.Tensor, vmin: float, vmax: float) -> torch.Tensor:
    """``(..., num_bins)`` logits -> ``(...)`` scalars: ``symexp`` of the expected bin."""
    probs = logits.softmax(-1)
    return symexp((probs * _bins(logits.shape[-1], vmin, vmax, probs)).sum(-1))


# -- the tanh-Gaussian policy -------------------------------------------------------------------
def log_std(x: torch.Tensor, low: float = -10.0, dif: float = 12.0) -> torch.Tensor:
    """Squash raw outputs into log-stds in ``[low, low + dif]``."""
    return low + 0.5 * dif * (torch.tanh(x) + 1)


def gaussian_logprob(eps: torch.Tensor, log_std: torch.Tensor) -> torch.Tensor:
    """Log-density ``(..., 1)`` of the standard-normal draws ``eps`` scaled by ``exp(log_std)``."""
    return (-0.5 * eps.square() - log_std - _LOG_SQRT_2PI).sum(-1, keepdim=True)


def squash(mu: torch.Tensor, pi: torch.Tensor, log_pi: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
    """``tanh`` of the mean and of the sample, and the sample's log-density after the tanh."""
    mu, pi = torch.tanh(mu), torch.tanh(pi)
    log_pi = log_pi - torch.log(F.relu(1 - pi.square()) + 1e-6).sum(-1, keepdim=True)
    return mu, pi, log_pi


# -- layers ---------------------------------------------------------------------------------------
class SimNorm(nn.Module):
    """Simplicial normalization: ``(..., L) -> (..., L)``, a softmax over each of the ``L / simplex_dim``
    consecutive groups (each group sums to 1)."""

    def __init__(self, simplex_dim: int = 8):
        super().__init__()
        if isinstance(simplex_dim, bool) or not isinstance(simplex_dim, int) or simplex_dim < 1:
            raise ConfigError(f"SimNorm requires simplex_dim to be a positive int, got {simplex_dim!r}")
        self.simplex_dim = simplex_dim

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        if x.shape[-1] % self.simplex_dim:
            raise ConfigError(
                f"SimNorm requires a last dim divisible by simplex_dim={self.simplex_dim}, got {tuple(x.shape)}"
            )
        return x.unflatten(-1, (-1, self.simplex_dim)).softmax(-1).flatten(-2)


class NormedLinear(nn.Linear):
    """``Linear -> Dropout (if dropout) -> LayerNorm (ln) -> act`` (Mish unless given)."""

    def __init__(
        self, in_features: int, out_features: int, bias: bool = True, dropout: float = 0.0, act: nn.Module | None = None
    ):
        super().__init__(in_features, out_features, bias=bias)
        self.ln = nn.LayerNorm(out_features)
        self.act = act if act is not None else nn.Mish()
        self.dropout = nn.Dropout(dropout) if dropout else None

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        x = super().forward(x)
        if self.dropout is not None:
            x = self.dropout(x)
        return self.act(self.ln(x))


class RunningScale(nn.Module):
    """Scale of the policy's Q values: buffer ``value`` (starts at 10) moves by ``tau`` towards
    the 5-95 percentile range of each update; ``forward(x)`` divides by it."""

    def __init__(self, tau: float = 0.01):
        super().__init__()
        self.tau = tau
        self.register_buffer("value", torch.full((1,), 10.0))

    @torch.no_grad()
    def update(self, x: torch.Tensor) -> None:
        q = torch.quantile(x.detach().float().flatten(), torch.tensor([0.05, 0.95], device=x.device))
        self.value.lerp_((q[1] - q[0]).clamp_min(1e-4).reshape(1).to(self.value.dtype), self.tau)

    def forward(self, x: torch.Tensor, update: bool = False) -> torch.Tensor:
        if update:
            self.update(x)
        return x / self.value


def mlp(in_dim: int, mlp_dim: int, out_dim: int, act: nn.Module | None = None, dropout: float = 0.0) -> nn.Sequential:
    """Two :class:`NormedLinear` of width ``mlp_dim`` (dropout after the first), then a Linear to
    ``out_dim`` (a :class:`NormedLinear` with activation ``act`` when given)."""
    last = NormedLinear(mlp_dim, out_dim, act=act) if act is not None else nn.Linear(mlp_dim, out_dim)
    return nn.Sequential(NormedLinear(in_dim, mlp_dim, dropout=dropout), NormedLinear(mlp_dim, mlp_dim), last)


def weight_init(m: nn.Module) -> None:
    """Truncated-normal (std 0.02) weights and zero biases for every Linear."""
    if isinstance(m, nn.Linear):
        nn.init.trunc_normal_(m.weight, std=0.02)
        if m.bias is not None:
            nn.init.zeros_(m.bias)

"""The recurrent state-space model (RSSM) of Dreamer: a GRU deterministic state ``h`` and a
diagonal Gaussian stochastic state ``z``, with a prior ``p(z | h)`` and a posterior
``q(z | h, e)`` given the embedding ``e`` of the frame."""

from __future__ import annotations

import torch
import torch.nn.functional as F
from torch import nn

from ...errors import ConfigError

__all__ = ["RSSM", "gaussian_kl"]


def gaussian_kl(mean_a: torch.Tensor, std_a: torch.Tensor, mean_b: torch.Tensor, std_b: torch.Tensor) -> torch.Tensor:
    """``KL(N(mean_a, std_a) || N(mean_b, std_b))`` of diagonal Gaussians, summed over the last axis."""
    var_a, var_b = std_a.square(), std_b.square()
    kl = torch.log(std_b / std_a) + (var_a + (mean_a - mean_b).square()) / (2 * var_b) - 0.5
    return kl.sum(-1)


def _mlp(d_in: int, hidden: int, d_out: int) -> nn.Sequential:
    return nn.Sequential(nn.Linear(d_in, hidden), nn.LayerNorm(hidden), nn.SiLU(), nn.Linear(hidden, d_out))


class RSSM(nn.Module):
    """``RSSM(embed_dim, action_dim, deter_dim, stoch_dim, hidden, min_std)``.

    A state is ``(h (N, deter_dim), z (N, stoch_dim))``; its features are ``[h, z]``.
    :meth:`img_step` moves a state by an action with the prior, :meth:`obs_step` also corrects
    it with the posterior given a frame embedding. Distributions are ``(mean, std)`` pairs with
    ``std = softplus(.) + min_std``. ``z`` is sampled in training mode and is the mean in eval mode.
    """

    def __init__(
        self,
        embed_dim: int,
        action_dim: int,
        deter_dim: int = 64,
        stoch_dim: int = 16,
        hidden: int = 64,
        min_std: float = 0.1,
    ):
        super().__init__()
        for name, value in (
            ("embed_dim", embed_dim),
            ("action_dim", action_dim),
            ("deter_dim", deter_dim),
            ("stoch_dim", stoch_dim),
            ("hidden", hidden),
        ):
            if isinstance(value, bool) or not isinstance(value, int) or value < 1:
                raise ConfigError(f"RSSM requires {name} to be a positive int, got {value!r}")
        self.embed_dim, self.action_dim, self.deter_dim, self.stoch_dim = embed_dim, action_dim, deter_dim, stoch_dim
        self.min_std = float(min_std)
        self.img_in = nn.Sequential(nn.Linear(stoch_dim + action_dim, hidden), nn.LayerNorm(hidden), nn.SiLU())
        self.gru = nn.GRUCell(hidden, deter_dim)
        self.prior_net = _mlp(deter_dim, hidden, 2 * stoch_dim)
        self.post_net = _mlp(deter_dim + embed_dim, hidden, 2 * stoch_dim)

    @property
    def feat_dim(self) -> int:
        return self.deter_dim + self.stoch_dim

    def initial(self, n: int, like: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        """The zero state of ``n`` sequences (dtype and device of ``like``)."""
        return like.new_zeros(n, self.deter_dim), like.new_zeros(n, self.stoch_dim)

    def _dist(self, out: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        mean, raw = out.chunk(2, dim=-1)
        return mean, F.softplus(raw) + self.min_std

    def _draw(self, mean: torch.Tensor, std: torch.Tensor) -> torch.Tensor:
        return mean + std * torch.randn_like(std) if self.training else mean

    def img_step(self, h: torch.Tensor, z: torch.Tensor, action: torch.Tensor):
        """``(h, z)`` and ``action (N, A)`` -> ``(h', z', (prior mean, prior std))``."""
        h = self.gru(self.img_in(torch.cat([z, action], -1)), h)
        prior = self._dist(self.prior_net(h))
        return h, self._draw(*prior), prior

    def obs_step(self, h: torch.Tensor, z: torch.Tensor, action: torch.Tensor, embed: torch.Tensor):
        """:meth:`img_step` then the posterior given ``embed (N, E)``: ``(h', z', prior, post)``."""
        h, _, prior = self.img_step(h, z, action)
        post = self._dist(self.post_net(torch.cat([h, embed], -1)))
        return h, self._draw(*post), prior, post

    def observe(self, embed: torch.Tensor, action: torch.Tensor):
        """Filter ``embed (N, T, E)`` from the zero state; ``action[:, t]`` leads from frame ``t`` to
        ``t + 1`` (the first step takes a zero action). Returns features ``(N, T, F)`` and the prior
        and posterior ``(mean, std)`` of each step, ``(N, T, stoch_dim)`` each."""
        n, t = embed.shape[:2]
        h, z = self.initial(n, embed)
        prev = action.new_zeros(n, action.shape[-1])
        feats, priors, posts = [], [], []
        for k in range(t):
            h, z, prior, post = self.obs_step(h, z, prev, embed[:, k])
            feats.append(torch.cat([h, z], -1))
            priors.append(prior)
            posts.append(post)
            prev = action[:, k]
        stack = lambda pairs, i: torch.stack([p[i] for p in pairs], 1)  # noqa: E731
        return (torch.stack(feats, 1), (stack(priors, 0), stack(priors, 1)), (stack(posts, 0), stack(posts, 1)))

    def imagine(self, feat: torch.Tensor, actions: torch.Tensor) -> torch.Tensor:
        """From the state of features ``feat (N, F)``, the prior's features after each of
        ``actions (N, H, A)``: ``(N, H, F)``."""
        h, z = feat[..., : self.deter_dim], feat[..., self.deter_dim :]
        out = []
        for k in range(actions.shape[1]):
            h, z, _ = self.img_step(h, z, actions[:, k])
            out.append(torch.cat([h, z], -1))
        return torch.stack(out, 1) if out else feat.new_zeros(feat.shape[0], 0, feat.shape[-1])

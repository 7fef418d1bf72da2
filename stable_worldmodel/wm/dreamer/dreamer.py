"""Dreamer: an RSSM world model that plans on the distance of the frame embedding it predicts to
the goal frame's.

Follows the contract of :mod:`stable_worldmodel.wm.jepa`. ``emb`` of a context are the
posterior features ``[h, z]`` of each frame, filtered from the zero state with the context's
``action`` (zeros when the info has none); :meth:`Dreamer.rollout` imagines with the prior from
the last context state. The goal is compared in the space of the image encoder's frame
embeddings: ``embed_head`` learns to predict a frame's embedding from the prior's features of
that step (what imagination produces), and the goal frame is simply encoded. A state's
features are not comparable with a lone goal frame's posterior: its deterministic part carries
the history, which a single frame does not have.
"""

from __future__ import annotations

from typing import Any

import torch
import torch.nn.functional as F
from torch import nn

from ... import keys
from ...errors import ConfigError, SpaceError, UnknownNameError
from ..jepa import EMB, GOAL_EMB, PREDICTED_EMB, goal_distance
from .module import RSSM, gaussian_kl

__all__ = ["Dreamer"]


def _require(info: dict, key: str, who: str) -> Any:
    if key not in info:
        raise UnknownNameError(f"{who} requires info[{key!r}], got keys {sorted(info)}")
    return info[key]


class Dreamer(nn.Module):
    """``Dreamer(encoder, decoder, rssm, action_dim, history_size, kl_dyn, kl_rep, free_bits,
    recon_coef, reward_head, reward_coef, embed_coef)``; see :class:`~stable_worldmodel.wm.dreamer.DreamerConfig`."""

    #: :meth:`decode` turns features (predicted ones included) into frames: ``swm eval --video``
    #: shows them without a frame decoder run
    decodes_frames = True

    def __init__(
        self,
        encoder: nn.Module,
        decoder: nn.Module,
        rssm: RSSM,
        action_dim: int,
        history_size: int = 4,
        kl_dyn: float = 0.5,
        kl_rep: float = 0.1,
        free_bits: float = 1.0,
        recon_coef: float = 1.0,
        reward_head: bool = False,
        reward_coef: float = 1.0,
        embed_coef: float = 1.0,
    ):
        super().__init__()
        if int(action_dim) != rssm.action_dim:
            raise ConfigError(f"Dreamer requires action_dim == rssm.action_dim, got {action_dim} and {rssm.action_dim}")
        self.encoder, self.decoder, self.rssm = encoder, decoder, rssm
        self.action_dim, self._history_size = int(action_dim), int(history_size)
        self.kl_dyn, self.kl_rep, self.free_bits = float(kl_dyn), float(kl_rep), float(free_bits)
        self.recon_coef, self.reward_coef, self.embed_coef = float(recon_coef), float(reward_coef), float(embed_coef)
        f = rssm.feat_dim
        self.embed_head = nn.Sequential(nn.Linear(f, f), nn.LayerNorm(f), nn.SiLU(), nn.Linear(f, rssm.embed_dim))
        self.reward = nn.Sequential(nn.Linear(f, f), nn.SiLU(), nn.Linear(f, 1)) if reward_head else None
        self.goal_cost = "final"  # see GOAL_COSTS; set by planning, not saved
        size = getattr(decoder, "image_size", None)
        if not isinstance(size, int):
            raise ConfigError(
                f"Dreamer requires a decoder with an int image_size (a FrameDecoder), got {type(decoder).__name__}"
            )
        # the training frames' mean (fit_to_frames): the decoder learns what differs from it
        self.register_buffer("frame_mean", torch.zeros(int(getattr(decoder, "channels", 3)), size, size))

    @property
    def history_size(self) -> int:
        return self._history_size

    def _dtype(self) -> torch.dtype:
        return next(self.rssm.parameters()).dtype

    def subgoal_keys(self) -> tuple[str | None, str]:
        """Info keys of the context (None: it filters its context itself, with the actions between
        frames) and goal embeddings a subgoal waypoint replaces."""
        return None, GOAL_EMB

    # -- verbs --------------------------------------------------------------------------------
    def encode_pixels(self, pixels: torch.Tensor) -> torch.Tensor:
        """``(..., C, h, w)`` float images -> frame embeddings ``(..., E)`` (the posterior's input)."""
        if pixels.ndim < 4:
            raise SpaceError(f"{type(self).__name__} requires images (..., C, h, w), got shape {tuple(pixels.shape)}")
        lead = pixels.shape[:-3]
        out = self.encoder(pixels.reshape(-1, *pixels.shape[-3:]).to(self._dtype()), interpolate_pos_encoding=True)
        hidden = out.last_hidden_state if hasattr(out, "last_hidden_state") else out["last_hidden_state"]
        return hidden[:, 0].reshape(*lead, -1)

    def _actions(self, action: torch.Tensor | None, like: torch.Tensor) -> torch.Tensor:
        n, t = like.shape[:2]
        if action is None:
            return like.new_zeros(n, t, self.action_dim)
        if action.shape[-1] != self.action_dim or action.shape[:-1] != (n, t):
            raise SpaceError(
                f"{type(self).__name__} requires actions of shape ({n}, {t}, {self.action_dim}), "
                f"got {tuple(action.shape)}"
            )
        return torch.nan_to_num(action.to(like.dtype), 0.0)

    def observe(self, pixels: torch.Tensor, action: torch.Tensor | None = None):
        """Filter ``pixels (B, T, C, h, w)`` with ``action (B, T, A)``: features, prior, posterior."""
        if pixels.ndim != 5:
            raise SpaceError(f"{type(self).__name__} requires pixels (B, T, C, h, w), got shape {tuple(pixels.shape)}")
        embed = self.encode_pixels(pixels)
        return self.rssm.observe(embed, self._actions(action, embed))

    def encode(self, info: dict) -> dict:
        """Add ``emb (B, T, F)``: the posterior features of ``pixels (B, T, C, h, w)`` (with
        ``action (B, T, A)`` between frames when present). Returns the same dict."""
        pixels = _require(info, keys.PIXELS, f"{type(self).__name__}.encode")
        info[EMB] = self.observe(pixels, info.get(keys.ACTION))[0]
        return info

    def encode_goal(self, pixels: torch.Tensor) -> torch.Tensor:
        """``(..., C, h, w)`` -> ``(..., E)``: the goal frames' embeddings (:meth:`encode_pixels`),
        which :meth:`predict_embedding` of the imagined states is compared with."""
        return self.encode_pixels(pixels)

    def predict_embedding(self, feats: torch.Tensor) -> torch.Tensor:
        """Features ``(..., F)`` -> the embedding ``(..., E)`` of the frame the state would show."""
        return self.embed_head(feats)

    def decode(self, emb: torch.Tensor) -> torch.Tensor:
        """Features ``(..., F)`` -> images ``(..., C, h, w)`` (normalized pixel space): the
        decoder's output added to the training frames' mean (:meth:`fit_to_frames`)."""
        return self.decoder(emb) + self.frame_mean

    @torch.no_grad()
    def fit_to_frames(self, pixels: torch.Tensor) -> None:
        """Keep the mean of preprocessed training frames ``(N, C, h, w)`` (called by
        :func:`~stable_worldmodel.train.train` before the first step): the static background is
        then reconstructed from the start, and the latent spends its capacity on what moves."""
        if pixels.ndim != 4 or pixels.shape[0] < 1 or tuple(pixels.shape[1:]) != tuple(self.frame_mean.shape):
            raise SpaceError(
                f"{type(self).__name__}.fit_to_frames "
                f"requires frames (N, {', '.join(map(str, self.frame_mean.shape))}), "
                f"got shape {tuple(pixels.shape)}"
            )
        self.frame_mean.copy_(pixels.to(self.frame_mean).mean(0))

    # -- planning -------------------------------------------------------------------------------
    def _cached(self, info: dict, cache: str, b: int, s: int | None, compute) -> torch.Tensor:
        if cache in info:
            emb = info[cache]
            return emb[:, 0] if s is not None and emb.ndim == 4 else emb
        emb = compute()
        info[cache] = emb.unsqueeze(1).expand(b, s, *emb.shape[1:]) if s is not None else emb
        return emb

    def _context(self, info: dict, b: int, s: int | None) -> torch.Tensor:
        def compute() -> torch.Tensor:
            pixels = _require(info, keys.PIXELS, f"{type(self).__name__}.rollout")
            action = info.get(keys.ACTION)
            if s is not None and pixels.ndim == 6:
                pixels = pixels[:, 0]  # the S copies of an env's info are views of one tensor
                if action is not None and action.ndim == 4:
                    action = action[:, 0]
            if action is not None and (action.shape[-1] != self.action_dim or action.shape[:2] != pixels.shape[:2]):
                action = None  # not the model's action blocks: filter with zero actions
            return self.observe(pixels, action)[0]

        return self._cached(info, EMB, b, s, compute)

    def rollout(self, info: dict, action_sequence: torch.Tensor) -> dict:
        """Imagine over candidate action blocks ``(B, S, H, A)`` (or ``(B, H, A)``), ``H >= T``:
        the first ``T - 1`` blocks belong to the context, the last ``H - T + 1`` are imagined
        with the prior from the last context state. Adds ``predicted_emb (B, S, H + 1, F)``:
        the ``T`` context features then ``H - T + 1`` imagined ones."""
        if action_sequence.ndim not in (3, 4) or action_sequence.shape[-1] != self.action_dim:
            raise SpaceError(
                f"{type(self).__name__}.rollout requires candidates (B, S, H, {self.action_dim}), "
                f"got shape {tuple(action_sequence.shape)}"
            )
        squeeze = action_sequence.ndim == 3
        cand = action_sequence.unsqueeze(1) if squeeze else action_sequence
        b, s, h, _ = cand.shape
        ctx = self._context(info, b, None if squeeze else s)  # (B, T, F)
        t, f = ctx.shape[1], ctx.shape[2]
        if h < t:
            raise ConfigError(
                f"{type(self).__name__}.rollout requires at least {t} actions (one per context frame), got {h}"
            )
        n = b * s
        start = ctx[:, -1].unsqueeze(1).expand(b, s, f).reshape(n, f)
        imagined = self.rssm.imagine(start, cand.reshape(n, h, -1)[:, t - 1 :].to(ctx.dtype))
        out = torch.cat([ctx.unsqueeze(1).expand(b, s, t, f).reshape(n, t, f), imagined], 1)
        info[PREDICTED_EMB] = out.reshape(b, h + 1, f) if squeeze else out.reshape(b, s, h + 1, f)
        return info

    def get_cost(self, info: dict, action_candidates: torch.Tensor) -> torch.Tensor:
        """Squared distance of the frame embeddings predicted along the imagined states to the goal's
        (last goal frame): ``(B, S)``."""
        squeeze = action_candidates.ndim == 3
        b, s = action_candidates.shape[0], None if squeeze else action_candidates.shape[1]

        def compute() -> torch.Tensor:
            goal = _require(info, keys.GOAL, f"{type(self).__name__}.get_cost")
            if s is not None and goal.ndim == 6:
                goal = goal[:, 0]
            return self.encode_goal(goal)

        goal = self._cached(info, GOAL_EMB, b, s, compute)  # (B, Tg, E)
        self.rollout(info, action_candidates)
        target = goal[:, -1] if squeeze else goal[:, -1].unsqueeze(1)
        predicted = self.predict_embedding(info[PREDICTED_EMB])
        return goal_distance(predicted, target, self.goal_cost, context=info[EMB].shape[-2])

    # -- training -------------------------------------------------------------------------------
    def kl_terms(self, prior: tuple, post: tuple) -> dict[str, torch.Tensor]:
        """KL balancing: ``kl`` (raw, mean over steps), ``dyn_loss = mean max(free_bits, KL(sg(post) || prior))``
        and ``rep_loss = mean max(free_bits, KL(post || sg(prior)))``."""
        (pm, ps), (qm, qs) = prior, post
        dyn = gaussian_kl(qm.detach(), qs.detach(), pm, ps)
        rep = gaussian_kl(qm, qs, pm.detach(), ps.detach())
        return {
            "kl": dyn.detach().mean(),
            "dyn_loss": dyn.clamp_min(self.free_bits).mean(),
            "rep_loss": rep.clamp_min(self.free_bits).mean(),
        }

    def loss(self, batch: dict) -> dict:
        """``batch``: ``pixels (B, T, C, h, w)``, ``action (B, T, A)`` (and ``reward (B, T)`` with a
        reward head). Returns ``loss``, ``recon_loss`` (squared error summed over each frame),
        ``kl``, ``dyn_loss``, ``rep_loss``, ``embed_loss`` (MSE of ``embed_head`` on the prior's
        features of frames 1.. against their detached embeddings) (and ``reward_loss``)."""
        who = f"{type(self).__name__}.loss"
        pixels = _require(batch, keys.PIXELS, who)
        action = _require(batch, keys.ACTION, who)
        if pixels.ndim != 5 or pixels.shape[1] < 2:
            raise SpaceError(f"{who} requires pixels (B, T >= 2, C, h, w), got shape {tuple(pixels.shape)}")
        embed = self.encode_pixels(pixels)
        feats, prior, post = self.rssm.observe(embed, self._actions(action, embed))
        # a unit-variance Gaussian's log-likelihood: squared errors summed over each frame's values
        recon = (self.decode(feats) - pixels.to(feats.dtype)).square().flatten(2).sum(-1).mean()
        out = {"recon_loss": recon, **self.kl_terms(prior, post)}
        # what imagination gives: h and the prior's mean (frame 0's prior knows nothing yet)
        prior_feats = torch.cat([feats[:, 1:, : self.rssm.deter_dim], prior[0][:, 1:]], -1)
        out["embed_loss"] = F.mse_loss(self.predict_embedding(prior_feats), embed[:, 1:].detach())
        total = (
            self.recon_coef * recon
            + self.kl_dyn * out["dyn_loss"]
            + self.kl_rep * out["rep_loss"]
            + self.embed_coef * out["embed_loss"]
        )
        if self.reward is not None:
            reward = _require(batch, keys.REWARD, who).to(feats.dtype)
            pred = self.reward(feats[:, 1:]).squeeze(-1)  # reward[:, k] is earned by the block leading to frame k + 1
            out["reward_loss"] = F.mse_loss(pred, torch.nan_to_num(reward[:, :-1], 0.0))
            total = total + self.reward_coef * out["reward_loss"]
        out["loss"] = total
        return out

"""PreJEPA (DINO-WM): a frozen patch-token encoder, per-frame action / proprioception
embeddings concatenated to every patch token (the "split latent"), and a frame-causal ViT
predictor over ``T * P`` tokens (upstream 0.1.1's ``stable_worldmodel.wm.prejepa.PreJEPA``).

Shapes (legend of :mod:`stable_worldmodel.wm.jepa`, plus ``P`` patches per frame, ``Dv`` the
encoder's token width and ``d = Dv + sum of the extra embedding widths``)::

    encode(info)               -> info + pixels_emb (B, T, P, Dv), <key>_emb (B, T, E) per extra
                                  input present (proprio, action), emb (B, T, P, d)
    predict(emb)               -> (B, T, P, d), frame t predicts frame t + 1
    rollout(info, candidates)  -> info + predicted_emb (B, S, H + 1, P, d) and its parts
                                  predicted_pixels_emb (B, S, H + 1, P, Dv), predicted_<key>_emb (B, S, H + 1, E)
    get_cost(info, candidates) -> (B, S): MSE of the last prediction's pixels and proprio
                                  parts to the goal's, each averaged, summed over the parts
    loss(batch)                -> {"loss", "pixels_loss", "<key>_loss" per non-action extra, "emb"}

The extra inputs are named by the keys of ``extra_encoders`` (``"proprio"``, ``"action"``);
their embeddings are laid out after the pixel features in that order. Without a
``"proprio"`` encoder the model works from pixels only. The context (``pixels_emb`` and
the non-action extras) and the goal (``goal_emb``, ``pixels_goal_emb``,
``<key>_goal_emb``) are encoded once per info dict: a solver's later calls with the same
dict reuse them, and only the action part changes from candidate to candidate.
"""

from __future__ import annotations

from typing import Any

import torch
import torch.nn.functional as F
from torch import nn

from ... import keys
from ...errors import ConfigError, SpaceError, UnknownNameError, unknown_name
from ..config import GOAL_COSTS

__all__ = ["PreJEPA"]

PIXELS_EMB, EMB, GOAL_EMB, PREDICTED_EMB = "pixels_emb", "emb", "goal_emb", "predicted_emb"


def _require(info: dict, key: str, who: str) -> Any:
    if key not in info:
        raise UnknownNameError(f"{who} requires info[{key!r}], got keys {sorted(info)}")
    return info[key]


class PreJEPA(nn.Module):
    """DINO-WM: ``PreJEPA(encoder, predictor, extra_encoders=None, decoder=None,
    history_size=3, num_pred=1, interpolate_pos_encoding=True)``.

    Submodules are upstream's (``backbone``, ``predictor``, ``extra_encoders``, ``decoder``),
    so its ``state_dict`` keys match. ``encoder`` is called as ``encoder(pixels (N, C, h, w)
    [, interpolate_pos_encoding=True])``; its ``last_hidden_state[:, 1:]`` (the patch tokens)
    or, for a classifier such as a ResNet, its ``logits`` (one token) are the frame features.
    The encoder is never trained: it runs under ``torch.no_grad`` (wrap it in
    :class:`~stable_worldmodel.wm.gcrl.module.EvalOnly`, as the configs do, to also keep
    it in eval mode and out of the optimizer). ``history_size`` frames are seen by the
    predictor; the loss predicts ``num_pred`` frames ahead.
    """

    def __init__(
        self,
        encoder: nn.Module,
        predictor: nn.Module,
        extra_encoders: dict[str, nn.Module] | nn.ModuleDict | None = None,
        decoder: nn.Module | None = None,
        history_size: int = 3,
        num_pred: int = 1,
        interpolate_pos_encoding: bool = True,
    ):
        super().__init__()
        for key, value in (("history_size", history_size), ("num_pred", num_pred)):
            if isinstance(value, bool) or not isinstance(value, int) or value < 1:
                raise ConfigError(f"PreJEPA requires {key} to be a positive int, got {value!r}")
        extra = (
            extra_encoders if isinstance(extra_encoders, nn.ModuleDict) else nn.ModuleDict(dict(extra_encoders or {}))
        )
        for key, module in extra.items():
            if not isinstance(getattr(module, "emb_dim", None), int):
                raise ConfigError(
                    "PreJEPA requires every extra encoder to have an int emb_dim, "
                    f"got {type(module).__name__} for {key!r}"
                )
        self.backbone = encoder
        self.predictor = predictor
        self.extra_encoders = extra
        self.decoder = decoder
        self.history_size, self.num_pred = history_size, num_pred
        self.interpolate_pos_encoding = bool(interpolate_pos_encoding)
        self.goal_cost = "final"  # see GOAL_COSTS; set by planning, not saved

    def frozen_encoder(self) -> nn.Module:
        """The frozen image encoder, whose features :mod:`stable_worldmodel.train.features` caches."""
        return self.backbone

    # -- layout -------------------------------------------------------------------------------
    @property
    def state_keys(self) -> list[str]:
        """The extra inputs that are part of the state (compared with the goal): all but ``action``."""
        return [k for k in self.extra_encoders if k != keys.ACTION]

    def _slices(self, width: int, present: list[str]) -> dict[str, slice]:
        """Where ``pixels`` and each extra of ``present`` sit in an embedding of ``width`` features."""
        dims = {k: self.extra_encoders[k].emb_dim for k in self.extra_encoders if k in present}
        start = width - sum(dims.values())
        out = {keys.PIXELS: slice(0, start)}
        for key, dim in dims.items():
            out[key] = slice(start, start + dim)
            start += dim
        return out

    def subgoal_keys(self) -> tuple[str | None, str]:
        """Info keys of the context and goal embeddings a subgoal waypoint replaces: its patch
        features, when it plans on them alone (no proprio: the state part has no waypoint)."""
        if self.state_keys:
            raise ConfigError(f"subgoals='graph' requires a PreJEPA without proprio, got one reading {self.state_keys}")
        return PIXELS_EMB, f"pixels_{GOAL_EMB}"

    # -- verbs --------------------------------------------------------------------------------
    def encode_pixels(self, pixels: torch.Tensor) -> torch.Tensor:
        """``(..., C, h, w)`` float images -> frozen features ``(..., P, Dv)``."""
        lead = pixels.shape[:-3]
        flat = pixels.reshape(-1, *pixels.shape[-3:]).float()
        kwargs = {"interpolate_pos_encoding": True} if self.interpolate_pos_encoding else {}
        with torch.no_grad():
            out = self.backbone(flat, **kwargs)
        hidden = getattr(out, "last_hidden_state", None)
        tokens = hidden[:, 1:] if hidden is not None else out.logits.unsqueeze(1)
        return tokens.detach().reshape(*lead, *tokens.shape[1:])

    def embed(self, key: str, values: torch.Tensor) -> torch.Tensor:
        """``(..., T, in_chans)`` values of extra input ``key`` -> ``(..., T, emb_dim)``."""
        if key not in self.extra_encoders:
            raise unknown_name("PreJEPA extra encoder", key, self.extra_encoders)
        lead = values.shape[:-2]
        flat = torch.nan_to_num(values.reshape(-1, *values.shape[-2:]).float(), 0.0)
        out = self.extra_encoders[key](flat)
        return out.reshape(*lead, *out.shape[1:])

    @staticmethod
    def _tile(emb: torch.Tensor, patches: int) -> torch.Tensor:
        """``(..., T, E)`` -> ``(..., T, P, E)``, the same vector on every patch."""
        return emb.unsqueeze(-2).expand(*emb.shape[:-1], patches, emb.shape[-1])

    def encode(
        self,
        info: dict,
        pixels_key: str = keys.PIXELS,
        emb_keys: Any = None,
        prefix: str | None = None,
        target: str = EMB,
        is_video: bool = False,
    ) -> dict:
        """Add ``pixels_<target>``, ``<key>_<target>`` per extra input and ``<target>`` (their
        concatenation, ``(B, T, P, d)``) from ``info[pixels_key]: (B, T, C, h, w)`` and
        ``info[prefix + key]: (B, T, in_chans)``. ``emb_keys`` (default: every extra encoder;
        ``action`` only when the info has it) picks the extras. Returns the same dict."""
        if is_video:
            raise ConfigError(
                "PreJEPA.encode(is_video=True) requires a video encoder, which is not supported; use an image backbone"
            )
        who, prefix = f"{type(self).__name__}.encode", prefix or ""
        if emb_keys is None:
            emb_keys = [k for k in self.extra_encoders if k != keys.ACTION or f"{prefix}{k}" in info]
        cached = info.get(f"pixels_{target}")
        if cached is not None and pixels_key not in info:  # features from the training cache
            pixels_emb = cached
        else:
            pixels_emb = self.encode_pixels(_require(info, pixels_key, who))
        info[f"pixels_{target}"] = pixels_emb
        parts = [pixels_emb]
        for key in emb_keys:
            extra = self.embed(key, _require(info, f"{prefix}{key}", who))
            info[f"{key}_{target}"] = extra
            parts.append(self._tile(extra, pixels_emb.shape[-2]))
        info[target] = torch.cat(parts, dim=-1)
        return info

    def predict(self, embedding: torch.Tensor) -> torch.Tensor:
        """``(B, T, P, d)`` -> predicted next frames ``(B, T, P, d)``."""
        b, t, p, d = embedding.shape
        return self.predictor(embedding.reshape(b, t * p, d)).reshape(b, t, p, -1)

    def decode(self, info: dict) -> dict:
        """Add ``reconstructed_pixels (B, T, C, h, w)`` and ``reconstruction_diff`` from ``pixels_emb``
        (needs a decoder)."""
        if self.decoder is None:
            raise ConfigError("PreJEPA.decode requires a model built with a decoder, got decoder=None")
        emb = _require(info, PIXELS_EMB, f"{type(self).__name__}.decode")
        pixels, diff = self.decoder(emb)
        info["reconstructed_pixels"] = pixels.reshape(emb.shape[0], emb.shape[1], *pixels.shape[1:])
        info["reconstruction_diff"] = diff
        return info

    def split_embedding(self, embedding: torch.Tensor, extra_dims: list[int] | None = None) -> dict[str, torch.Tensor]:
        """``(..., P, d)`` -> ``{"pixels_emb": (..., P, Dv), "<key>_emb": (..., E)}`` for every
        extra encoder (``extra_dims``, their widths, are checked against the encoders')."""
        present = list(self.extra_encoders)
        if extra_dims is not None and list(extra_dims) != [self.extra_encoders[k].emb_dim for k in present]:
            raise ConfigError(f"PreJEPA.split_embedding requires the extra encoders' widths, got {list(extra_dims)}")
        out = {}
        for key, where in self._slices(embedding.shape[-1], present).items():
            part = embedding[..., where]
            out[f"{key}_emb"] = part if key == keys.PIXELS else part[..., 0, :]  # every patch holds the same vector
        return out

    def replace_action_in_embedding(self, embedding: torch.Tensor, act: torch.Tensor) -> torch.Tensor:
        """``embedding (..., T, P, d)`` with its action part replaced by the embedding of ``act (..., T, A)``."""
        if keys.ACTION not in self.extra_encoders:
            raise ConfigError("PreJEPA requires an 'action' extra encoder to roll out actions, got none")
        where = self._slices(embedding.shape[-1], list(self.extra_encoders))[keys.ACTION]
        tiled = self._tile(self.embed(keys.ACTION, act), embedding.shape[-2])
        return torch.cat(
            [embedding[..., : where.start], tiled.to(embedding.dtype), embedding[..., where.stop :]], dim=-1
        )

    # -- planning -------------------------------------------------------------------------------
    def _state(
        self, info: dict, pixels_key: str, prefix: str, target: str, b: int, s: int | None
    ) -> dict[str, torch.Tensor]:
        """Per-env embeddings of the state parts (``pixels`` and the non-action extras):
        ``{"pixels": (B, T, P, Dv), key: (B, T, E)}``, cached in ``info`` as ``pixels_<target>``
        / ``<key>_<target>`` (expanded over the S candidates when there are some)."""
        who = f"{type(self).__name__}.get_cost"
        out = {}
        for key, per_env_ndim in ((keys.PIXELS, 4), *((k, 3) for k in self.state_keys)):
            cache = f"{key}_{target}"
            if cache in info:
                emb = info[cache]
                out[key] = emb[:, 0] if emb.ndim == per_env_ndim + 1 else emb  # cached with the S axis
                continue
            raw = _require(info, pixels_key if key == keys.PIXELS else f"{prefix}{key}", who)
            if s is not None and raw.ndim == per_env_ndim + (2 if key == keys.PIXELS else 1):
                raw = raw[:, 0]  # the S copies of an env's info are views of one tensor
            emb = self.encode_pixels(raw) if key == keys.PIXELS else self.embed(key, raw)
            info[cache] = emb.unsqueeze(1).expand(b, s, *emb.shape[1:]) if s is not None else emb
            out[key] = emb
        return out

    def rollout(self, info: dict, action_sequence: torch.Tensor) -> dict:
        """Roll the predictor out over candidate action blocks.

        ``info["pixels"]: (B, S, T, C, h, w)`` (plus ``info["proprio"]: (B, S, T, dp)`` with a
        proprio encoder) and ``action_sequence: (B, S, H, A)`` with ``H >= T``: the first T
        actions pair with the T context frames, the others with the predicted frames; the
        predictor sees the last ``history_size`` frames. Adds ``predicted_emb (B, S, H + 1, P, d)``
        (the T context frames then ``H - T + 1`` predictions) and its parts (module docstring).
        3-D candidates ``(B, H, A)`` with ``(B, T, ...)`` infos work too (no S axis).
        """
        if keys.ACTION not in self.extra_encoders:
            raise ConfigError("PreJEPA.rollout requires an 'action' extra encoder, got none")
        squeeze = action_sequence.ndim == 3
        cand = action_sequence.unsqueeze(1) if squeeze else action_sequence
        if cand.ndim != 4:
            raise SpaceError(
                f"PreJEPA.rollout requires actions (B, S, H, A) or (B, H, A), got {tuple(action_sequence.shape)}"
            )
        b, s, h, _ = cand.shape
        state = self._state(info, keys.PIXELS, "", EMB, b, None if squeeze else s)
        t, p = state[keys.PIXELS].shape[1:3]
        if h < t:
            raise ConfigError(
                f"{type(self).__name__}.rollout requires at least {t} actions (one per context frame), got {h}"
            )
        n = b * s
        act = cand.reshape(n, h, -1)
        ctx_pixels = state[keys.PIXELS]
        parts = [ctx_pixels]
        for key, module in self.extra_encoders.items():  # the action part is a placeholder, filled per candidate below
            parts.append(
                self._tile(state[key], p) if key != keys.ACTION else ctx_pixels.new_zeros(b, t, p, module.emb_dim)
            )
        ctx = torch.cat(parts, dim=-1)  # (B, T, P, d)
        z = ctx.unsqueeze(1).expand(b, s, *ctx.shape[1:]).reshape(n, *ctx.shape[1:])
        z = self.replace_action_in_embedding(z, act[:, :t])
        frames = list(z.unbind(1))
        for k in range(t, h + 1):
            window = torch.stack(frames[-self.history_size :], dim=1)
            nxt = self.predict(window)[:, -1]  # (N, P, d)
            if k < h:
                nxt = self.replace_action_in_embedding(nxt.unsqueeze(1), act[:, k : k + 1])[:, 0]
            frames.append(nxt)
        pred = torch.stack(frames, dim=1)  # (N, H + 1, P, d)
        pred = pred.reshape(b, h + 1, *pred.shape[2:]) if squeeze else pred.reshape(b, s, h + 1, *pred.shape[2:])
        info[PREDICTED_EMB] = info["predicted_embedding"] = pred  # upstream's name too
        info.update({f"predicted_{k}": v for k, v in self.split_embedding(pred).items()})
        return info

    def criterion(self, info: dict, action_candidates: torch.Tensor | None = None) -> torch.Tensor:
        """Sum over the state parts (pixels, proprio) of the mean squared error between the last
        predicted frame (``goal_cost="final"``, upstream's; ``"min"``: the closest predicted
        frame) and the goal frames: ``(B, S)`` (``(B, 1)`` for 3-D candidates)."""
        if self.goal_cost not in GOAL_COSTS:
            raise unknown_name("goal cost", self.goal_cost, GOAL_COSTS)
        context = info[PIXELS_EMB].shape[-3]
        cost = 0.0
        for key in (*self.state_keys, keys.PIXELS):
            pred, goal = info[f"predicted_{key}_emb"], info[f"{key}_{GOAL_EMB}"]
            extra = 2 if key == keys.PIXELS else 1  # feature dims after the frame axis
            if pred.ndim == 2 + extra:  # 3-D candidates: no S axis
                pred, goal = pred.unsqueeze(1), goal.unsqueeze(1)
            goal = goal[:, :, -1:]  # the last goal frame
            if self.goal_cost == "final":
                cost = cost + (pred[:, :, -1:] - goal).square().flatten(2).mean(-1)
            else:
                per_frame = (pred[:, :, context:] - goal).square().flatten(3).mean(-1)  # (B, S, H + 1 - T)
                cost = cost + per_frame
        return cost.amin(-1) if self.goal_cost == "min" else cost

    def get_cost(self, info_dict: dict, action_candidates: torch.Tensor) -> torch.Tensor:
        """Cost of ``action_candidates: (B, S, H, A)`` (normalized action blocks) to reach
        ``info["goal"]`` (and ``info["goal_proprio"]`` with a proprio encoder): ``(B, S)``."""
        squeeze = action_candidates.ndim == 3
        b = action_candidates.shape[0]
        s = None if squeeze else action_candidates.shape[1]
        goal = self._state(info_dict, keys.GOAL, f"{keys.GOAL}_", GOAL_EMB, b, s)
        if GOAL_EMB not in info_dict:
            p = goal[keys.PIXELS].shape[-2]
            emb = torch.cat([goal[keys.PIXELS], *(self._tile(goal[k], p) for k in self.state_keys)], dim=-1)
            info_dict[GOAL_EMB] = emb.unsqueeze(1).expand(b, s, *emb.shape[1:]) if s is not None else emb
        self.rollout(info_dict, action_candidates)
        cost = self.criterion(info_dict, action_candidates)
        return cost[:, 0] if squeeze else cost

    # -- training -------------------------------------------------------------------------------
    def loss(self, batch: dict) -> dict:
        """Teacher-forced next-frame prediction on ``batch``: ``pixels (B, T, C, h, w)`` (or
        their cached frozen features ``pixels_emb (B, T, P, Dv)``), ``action (B, T, A)`` and,
        with a proprio encoder, ``proprio (B, T, dp)``.

        ``loss`` is the MSE between the predicted and the target features of the frames
        ``num_pred`` ahead of the first ``history`` ones over the pixel and proprio parts
        (the action part is not predicted); ``pixels_loss`` and ``<key>_loss`` are the
        per-part MSEs; ``emb`` the encoded batch ``(B, T, P, d)``.
        """
        who = f"{type(self).__name__}.loss"
        if PIXELS_EMB in batch and keys.PIXELS not in batch:  # cached frozen features (train.features)
            info = {PIXELS_EMB: batch[PIXELS_EMB]}
        else:
            info = {keys.PIXELS: _require(batch, keys.PIXELS, who)}
        total = next(iter(info.values())).shape[1]
        history = min(self.history_size, total - self.num_pred)
        if history < 1:
            raise ConfigError(
                f"{who} requires more than num_pred={self.num_pred} frames per sample, "
                f"got {total} frames (history {history})"
            )
        for key in self.extra_encoders:
            info[key] = _require(batch, key, who)
        out = self.encode(info)
        emb = out[EMB]
        pred = self.predict(emb[:, :history])
        target = emb[:, self.num_pred : self.num_pred + history].detach()
        where = self._slices(emb.shape[-1], list(self.extra_encoders))
        result: dict[str, torch.Tensor] = {}
        state = [k for k in where if k != keys.ACTION]
        for key in state:
            result[f"{key}_loss"] = F.mse_loss(pred[..., where[key]], target[..., where[key]])
        keep = torch.cat([torch.arange(where[k].start, where[k].stop, device=emb.device) for k in state])
        result["loss"] = F.mse_loss(pred.index_select(-1, keep), target.index_select(-1, keep))
        result["emb"] = emb
        return result

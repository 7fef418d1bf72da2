"""The shared body of the JEPA world models (LeWM, PLDM): encode, predict, rollout, cost.

Contract (every world model of :mod:`stable_worldmodel.wm` follows it; shapes use the
legend ``B`` envs/batch, ``S`` candidates, ``T`` history frames, ``H`` horizon, ``A``
action dim (an action *block*: ``frameskip`` env actions concatenated), ``D`` embedding,
``C, h, w`` image)::

    encode(info)               -> info + emb (B, T, D) [+ act_emb (B, T, D) when info has action]
    predict(emb, act_emb)      -> (B, T, D), output t predicts frame t + 1
    rollout(info, candidates)  -> info + predicted_emb (B, S, T + H - T' , D)   (see rollout)
    get_cost(info, candidates) -> (B, S), lower is better
    loss(batch)                -> {"loss": scalar, named terms...}

``info["pixels"]`` / ``info["goal"]`` hold preprocessed float images ``(B, T, C, h, w)``
(``(B, S, T, C, h, w)`` inside a solver, which expands each env's info over its
candidates). The context and the goal are encoded once per plan: :meth:`JEPA.get_cost`
stores ``emb`` and ``goal_emb`` in the info dict it is given and reuses them on the next
call with the same dict (a solver keeps one dict per plan).
"""

from __future__ import annotations

from typing import Any

import torch
from torch import nn

from .. import keys
from ..errors import ConfigError, UnknownNameError
from .config import GOAL_COSTS

__all__ = ["JEPA", "EMB", "ACT_EMB", "GOAL_EMB", "PREDICTED_EMB", "goal_distance"]

EMB, ACT_EMB, GOAL_EMB, PREDICTED_EMB = "emb", "act_emb", "goal_emb", "predicted_emb"


def goal_distance(pred: torch.Tensor, goal: torch.Tensor, goal_cost: str, context: int) -> torch.Tensor:
    """Squared distance to ``goal (..., D)`` of a rollout ``pred (..., T + H, D)`` whose first
    ``context`` embeddings are the context: of its last embedding (``goal_cost="final"``,
    upstream's) or of its closest prediction (``"min"``). Returns ``(...)``."""
    if goal_cost == "final":
        return (pred[..., -1, :] - goal).square().sum(-1)
    if goal_cost != "min":
        from ..errors import unknown_name

        raise unknown_name("goal cost", goal_cost, GOAL_COSTS)
    return (pred[..., context:, :] - goal.unsqueeze(-2)).square().sum(-1).amin(-1)


def _require(info: dict, key: str, who: str) -> Any:
    if key not in info:
        raise UnknownNameError(f"{who} requires info[{key!r}], got keys {sorted(info)}")
    return info[key]


class JEPA(nn.Module):
    """Encoder + action encoder + autoregressive predictor in a joint embedding space.

    Submodule names are upstream's (``encoder``, ``predictor``, ``action_encoder``,
    ``projector``, ``pred_proj``), so their ``state_dict`` keys match. The encoder is called
    as ``encoder(pixels, interpolate_pos_encoding=True)`` and its ``last_hidden_state[:, 0]``
    (the CLS token of a ViT; the only token of :class:`~stable_worldmodel.wm.encoders.ConvEncoder`)
    goes through ``projector``.

    ``obs_key`` (keyword, default ``"pixels"``): the info key the model observes. Another key
    (``"state"``, ``"proprio"``: vectors ``(..., S)``, normalized as in training) makes a
    state-input model, with an encoder such as :class:`~stable_worldmodel.wm.encoders.StateEncoder`;
    its goal is then ``goal_<obs_key>`` instead of the goal image ``goal``.
    """

    def __init__(
        self,
        encoder: nn.Module,
        predictor: nn.Module,
        action_encoder: nn.Module,
        projector: nn.Module | None = None,
        pred_proj: nn.Module | None = None,
        *,
        obs_key: str = keys.PIXELS,
        **kwargs: Any,
    ):
        super().__init__()
        self.obs_key = str(obs_key)
        self.encoder = encoder
        self.predictor = predictor
        self.action_encoder = action_encoder
        self.projector = projector or nn.Identity()
        self.pred_proj = pred_proj or nn.Identity()
        self.extra_config = dict(kwargs)
        self.goal_cost = "final"  # see GOAL_COSTS; set by planning, not saved

    def __setstate__(self, state: dict) -> None:
        """A model that upstream 0.1.1 pickled (``*_object.ckpt``) lacks our plain attributes:
        they get their defaults (its sub-modules' own ``__setstate__`` fill theirs)."""
        super().__setstate__(state)
        self.__dict__.setdefault("extra_config", {})
        self.__dict__.setdefault("goal_cost", "final")
        self.__dict__.setdefault("obs_key", keys.PIXELS)
        self.__dict__.setdefault("rollout_steps", 0)  # LeWM's and PLDM's training knob (ours; upstream has none)

    # -- sizes --------------------------------------------------------------------------------
    @property
    def history_size(self) -> int:
        """Frames the predictor attends to (``predictor.num_frames``, default 3)."""
        return int(getattr(self.predictor, "num_frames", 3))

    def _dtype(self) -> torch.dtype:
        for p in self.encoder.parameters():
            return p.dtype
        return torch.float32

    def subgoal_keys(self) -> tuple[str | None, str]:
        """Info keys of the context and goal embeddings a subgoal waypoint replaces
        (:mod:`stable_worldmodel.wm.base`)."""
        return EMB, GOAL_EMB

    # -- verbs --------------------------------------------------------------------------------
    def encode_pixels(self, pixels: torch.Tensor) -> torch.Tensor:
        """``(..., C, h, w)`` float images -> ``(..., D)`` embeddings."""
        flat = pixels.reshape(-1, *pixels.shape[-3:]).to(self._dtype())
        return self._project(self.encoder(flat, interpolate_pos_encoding=True), pixels.shape[:-3])

    def _project(self, out: Any, lead: torch.Size) -> torch.Tensor:
        """The encoder output's first token (``last_hidden_state[:, 0]``) through ``projector``, as ``(*lead, D)``."""
        hidden = out.last_hidden_state if hasattr(out, "last_hidden_state") else out["last_hidden_state"]
        return self.projector(hidden[:, 0]).reshape(*lead, -1)

    @property
    def goal_key(self) -> str:
        """The info key of the goal observation: ``goal`` (an image) or ``goal_<obs_key>``."""
        return keys.GOAL if self.obs_key == keys.PIXELS else keys.goal_key(self.obs_key)

    def encode_obs(self, obs: torch.Tensor) -> torch.Tensor:
        """Observations ``(..., C, h, w)`` (images) or ``(..., S)`` (``obs_key`` a state) -> ``(..., D)``."""
        if self.obs_key == keys.PIXELS:
            return self.encode_pixels(obs)
        return self._project(self.encoder(obs.reshape(-1, obs.shape[-1]).to(self._dtype())), obs.shape[:-1])

    def _obs_rank(self) -> int:
        return 3 if self.obs_key == keys.PIXELS else 1

    def encode(self, info: dict) -> dict:
        """Add ``emb: (B, T, D)`` from ``pixels: (B, T, C, h, w)`` (or ``info[obs_key]: (B, T, S)``),
        and ``act_emb: (B, T, D)`` from ``action: (B, T, A)`` when present. Returns the same dict."""
        info[EMB] = self.encode_obs(_require(info, self.obs_key, f"{type(self).__name__}.encode"))
        if keys.ACTION in info:
            info[ACT_EMB] = self.action_encoder(info[keys.ACTION])
        return info

    def predict(self, emb: torch.Tensor, act_emb: torch.Tensor) -> torch.Tensor:
        """``emb, act_emb: (B, T, D)`` -> predicted next embeddings ``(B, T, D)``."""
        preds = self.predictor(emb, act_emb)
        b, t, d = preds.shape
        return self.pred_proj(preds.reshape(b * t, d)).reshape(b, t, -1)

    def _predict_last(self, emb: torch.Tensor, act_emb: torch.Tensor) -> torch.Tensor:
        """Only the last output of :meth:`predict`: ``(N, D)`` (pred_proj acts per token)."""
        return self.pred_proj(self.predictor(emb, act_emb)[:, -1])

    # -- planning -------------------------------------------------------------------------------
    def _context(self, info: dict, key: str, cache: str, b: int, s: int | None) -> torch.Tensor:
        """Embeddings ``(B, T, D)`` of ``info[key]`` (one copy per env), cached in ``info[cache]``."""
        if cache in info:
            emb = info[cache]
            return emb[:, 0] if s is not None and emb.ndim == 4 else emb
        obs = _require(info, key, f"{type(self).__name__}.get_cost")
        if s is not None and obs.ndim == 3 + self._obs_rank():
            obs = obs[:, 0]  # the S copies of an env's info are views of one tensor
        emb = self.encode_obs(obs)
        info[cache] = emb.unsqueeze(1).expand(b, s, *emb.shape[1:]) if s is not None else emb
        return emb

    def rollout(self, info: dict, action_sequence: torch.Tensor, history_size: int | None = None) -> dict:
        """Roll the predictor out over candidate action blocks.

        ``info["pixels"]: (B, S, T, C, h, w)`` (or ``info["emb"]`` already there) and
        ``action_sequence: (B, S, H, A)`` with ``H >= T``: as in upstream, the first T
        actions pair with the T context frames and the rest are future actions; the
        predictor sees at most ``history_size`` frames (default ``predictor.num_frames``).
        Adds ``predicted_emb: (B, S, H + 1, D)``: the T context embeddings followed by
        ``H - T + 1`` predictions (the last one after all H actions). 3-D inputs
        ``(B, H, A)`` with ``(B, T, ...)`` infos work too (no S axis).
        """
        squeeze = action_sequence.ndim == 3
        cand = action_sequence.unsqueeze(1) if squeeze else action_sequence
        b, s, h, _ = cand.shape
        ctx = self._context(info, self.obs_key, EMB, b, None if squeeze else s)  # (B, T, D)
        t = ctx.shape[1]
        if h < t:
            raise ConfigError(
                f"{type(self).__name__}.rollout requires at least {t} actions (one per context frame), got {h}"
            )
        hs = int(history_size or self.history_size)
        n = b * s
        act_emb = self.action_encoder(cand.reshape(n, h, -1))  # (BS, H, D)
        d = ctx.shape[-1]
        out = self._open_loop(ctx.unsqueeze(1).expand(b, s, t, d).reshape(n, t, d), act_emb, hs, h + 1)
        info[PREDICTED_EMB] = out.reshape(b, h + 1, d) if squeeze else out.reshape(b, s, h + 1, d)
        return info

    def _open_loop(self, context: torch.Tensor, act_emb: torch.Tensor, window: int, length: int) -> torch.Tensor:
        """``context (N, t, D)`` followed by predictions up to ``length`` frames ``(N, length, D)``: frame ``k``
        predicted from the (at most ``window``) frames before it, true or predicted, and their actions ``act_emb``."""
        frames = list(context.unbind(1))
        act_emb = act_emb[:, : length - 1]
        predictor = self.predictor
        # LeWM's / PLDM's predictor with windows of several frames: each action's AdaLN modulation
        # once, not once per window it sits in, and only the last token through the last block
        mods = predictor.condition(act_emb) if window > 1 and hasattr(predictor, "forward_last") else None
        for k in range(len(frames), length):
            lo = max(0, k - window)
            x = torch.stack(frames[lo:k], 1)
            if mods is None:
                frames.append(self._predict_last(x, act_emb[:, lo:k]))
            else:
                frames.append(self.pred_proj(predictor.forward_last(x, [m[:, lo:k] for m in mods])))
        return torch.stack(frames, 1)

    def criterion(self, info: dict) -> torch.Tensor:
        """Squared distance to the last goal embedding of the last predicted embedding
        (``goal_cost == "final"``, upstream's) or of the closest predicted one (``"min"``): ``(B, S)``."""
        goal = info[GOAL_EMB]
        goal = goal[:, :, -1] if goal.ndim == 4 else goal[:, -1].unsqueeze(1)  # (B, S or 1, D)
        return goal_distance(info[PREDICTED_EMB], goal, self.goal_cost, context=info[EMB].shape[-2])

    def get_cost(self, info: dict, action_candidates: torch.Tensor) -> torch.Tensor:
        """Cost of ``action_candidates: (B, S, H, A)`` (normalized action blocks)
        to reach ``info["goal"]``: ``(B, S)``."""
        b, s = action_candidates.shape[:2]
        self._context(info, self.goal_key, GOAL_EMB, b, s)
        self.rollout(info, action_candidates)
        return self.criterion(info)

    # -- training -------------------------------------------------------------------------------
    def _teacher_forcing(
        self, batch: dict, history: int | None, num_preds: int, rollout_steps: int = 0
    ) -> tuple[dict, torch.Tensor]:
        """Encode ``batch`` (``pixels (B, T, C, h, w)``, ``action (B, T, A)``) and predict the
        frames ``num_preds`` ahead of the first ``history`` ones; returns (encoded, pred_loss).

        With ``rollout_steps = K > 0`` also ``out["rollout_loss"]``: the predictor rolled out
        open loop from the first frame over the next K actions, as planning rolls it out (one
        context frame; each prediction fed back as context, in a window of at most ``history``
        frames), and the mean squared error of its K predictions to the embeddings of frames
        ``1 .. K``. Its gradient reaches the predictor and the action encoder only: the embeddings
        enter it detached (through them the encoder would shrink what is hard to predict several
        steps ahead; on Push-T, the pushed block, which planning must see)."""
        who = f"{type(self).__name__}.loss"
        obs = _require(batch, self.obs_key, who)
        action = torch.nan_to_num(_require(batch, keys.ACTION, who), 0.0)
        total = obs.shape[1]
        history = int(history or min(self.history_size, total - num_preds))
        if history < 1 or history + num_preds > total or rollout_steps + 1 > total:
            raise ConfigError(
                f"{who} requires history + num_preds and 1 + rollout_steps <= frames per sample, got "
                f"history={history}, num_preds={num_preds}, rollout_steps={rollout_steps} and {total} frames"
            )
        out = self.encode({self.obs_key: obs, keys.ACTION: action})
        emb, act_emb = out[EMB], out[ACT_EMB]
        pred = self.predict(emb[:, :history], act_emb[:, :history])
        target = emb[:, num_preds : num_preds + history]
        out["pred_loss"] = (pred - target).square().mean()
        if rollout_steps > 0:
            out["rollout_loss"] = self._rollout_error(emb, act_emb, history, rollout_steps)
        out[keys.ACTION] = action
        return out, out["pred_loss"]

    def _rollout_error(self, emb: torch.Tensor, act_emb: torch.Tensor, window: int, steps: int) -> torch.Tensor:
        """Mean squared error of ``steps`` open-loop predictions from ``emb[:, 0]`` (contexts of at most ``window``)."""
        emb = emb.detach()
        pred = self._open_loop(emb[:, :1], act_emb, window, steps + 1)[:, 1:]
        return (pred - emb[:, 1 : steps + 1]).square().mean()

    def loss(self, batch: dict) -> dict:  # pragma: no cover - abstract
        raise NotImplementedError("loss(batch) -> {'loss': scalar, ...named terms}")

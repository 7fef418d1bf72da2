"""GCRL: goal-conditioned policies (GCBC, GCIVL, GCIQL) on an image encoder (upstream 0.1.1's
``stable_worldmodel.wm.gcrl.GCRL``).

Shapes: ``B`` batch/envs, ``T`` frames, ``P`` tokens per frame, ``d`` token width, ``A`` action
block (``frameskip`` env actions)::

    encode(info)                     -> info + embed (B, T, P, d), pixels_embed [, <key>_embed]
    predict_actions(emb, goal_emb)   -> means (B, T, A), stds (A,)
    predict_values(emb, goal_emb)    -> (B, T, 1)
    get_action(info)                 -> (B, A)   from info["pixels"] (B, T, C, h, w), info["goal"] (B, 1, C, h, w)
    loss(batch)                      -> {"loss": scalar, named terms...}   (see .algorithms)
"""

from __future__ import annotations

from collections.abc import Mapping

import torch
from torch import nn

from ... import keys
from ...errors import ConfigError, unknown_name
from .algorithms import ALGORITHMS, LOSSES
from .encoding import GoalImageEncoding, require

__all__ = ["GCRL"]


def _out_features(head: nn.Module) -> int:
    last = head[-1] if isinstance(head, nn.Sequential) else head
    if not isinstance(last, nn.Linear):
        raise ConfigError(
            "GCRL requires action_predictor.out_proj to be a Linear (or a Sequential ending with one), "
            f"got {type(head).__name__}"
        )
    return last.out_features


class GCRL(GoalImageEncoding, nn.Module):
    """``GCRL(encoder, action_predictor, value_predictor=None, critic_predictor=None,
    extra_encoders=None, history_size=3, interpolate_pos_encoding=True, log_std_min=-5.0,
    log_std_max=2.0)``: upstream's constructor, attributes and ``state_dict`` keys
    (``encoder``, ``action_predictor``, ``value_predictor``, ``critic_predictor``,
    ``extra_encoders``, ``log_stds``: the state-independent log-stds of the Gaussian policy).

    The encoder is called as ``encoder(pixels (N, C, h, w), interpolate_pos_encoding=True)``;
    an output with ``last_hidden_state`` is read as a ViT's (its first, CLS token dropped:
    ``P`` patches), otherwise ``.logits (N, d)`` is one token.

    Training knobs (keyword-only, not in the state dict): ``algorithm`` (``gcbc``, ``gcivl``
    or ``gciql``; default: ``gciql`` with a critic, ``gcivl`` with a value head, else
    ``gcbc``), ``discount`` (0.99), ``expectile`` (0.7 for gcivl, 0.9 for gciql),
    ``awr_alpha`` (10), ``awr_max_weight`` (100) and ``actor_encoder_grad`` (False: the
    actor term of gcivl / gciql does not train the encoder, as upstream). A value or critic head wrapped in
    :class:`~stable_worldmodel.wm.gcrl.module.TeacherStudentWrapper` gives the TD targets
    from its EMA teacher, updated at the start of every training ``loss`` call.
    """

    head_prefix = "action_predictor."
    other_family = (
        "predictor.",
        "release 0.0.3's GCBC (one action per window); load it with stable_worldmodel.wm.gcbc.GCBC (swm.wm.GCBC)",
    )

    def __init__(
        self,
        encoder: nn.Module,
        action_predictor: nn.Module,
        value_predictor: nn.Module | None = None,
        critic_predictor: nn.Module | None = None,
        extra_encoders: Mapping[str, nn.Module] | None = None,
        history_size: int = 3,
        interpolate_pos_encoding: bool = True,
        log_std_min: float = -5.0,
        log_std_max: float = 2.0,
        *,
        algorithm: str | None = None,
        discount: float = 0.99,
        expectile: float | None = None,
        awr_alpha: float = 10.0,
        awr_max_weight: float = 100.0,
        actor_encoder_grad: bool = False,
    ):
        super().__init__()
        self.encoder = encoder
        self.value_predictor = value_predictor
        self.action_predictor = action_predictor
        self.critic_predictor = critic_predictor
        self.extra_encoders = nn.ModuleDict(dict(extra_encoders or {}))
        self.history_size = int(history_size)
        self.interpolate_pos_encoding = interpolate_pos_encoding
        self.log_std_min, self.log_std_max = float(log_std_min), float(log_std_max)
        self.log_stds = nn.Parameter(torch.zeros(_out_features(action_predictor.out_proj)))
        if algorithm is None:
            algorithm = "gciql" if critic_predictor is not None else "gcivl" if value_predictor is not None else "gcbc"
        if algorithm not in ALGORITHMS:
            raise unknown_name("GCRL algorithm", algorithm, ALGORITHMS)
        needs = {"gcivl": ("value_predictor",), "gciql": ("value_predictor", "critic_predictor")}.get(algorithm, ())
        missing = [name for name in needs if getattr(self, name) is None]
        if missing:
            raise ConfigError(f"GCRL(algorithm={algorithm!r}) requires {' and '.join(missing)}, got None")
        if not 0.0 <= discount <= 1.0 or awr_alpha < 0 or awr_max_weight <= 0:
            raise ConfigError(
                "GCRL requires 0 <= discount <= 1, awr_alpha >= 0 and awr_max_weight > 0, "
                f"got {discount}, {awr_alpha}, {awr_max_weight}"
            )
        self.algorithm, self.discount = algorithm, float(discount)
        self.expectile = float(expectile if expectile is not None else (0.9 if algorithm == "gciql" else 0.7))
        self.awr_alpha, self.awr_max_weight = float(awr_alpha), float(awr_max_weight)
        self.actor_encoder_grad = bool(actor_encoder_grad)

    def _image_encoder(self) -> nn.Module:
        return self.encoder

    # -- heads ------------------------------------------------------------------------------
    def _clamped_log_stds(self) -> torch.Tensor:
        return self.log_stds.clamp(self.log_std_min, self.log_std_max)

    def predict_actions(
        self, embedding: torch.Tensor, embedding_goal: torch.Tensor, temperature: float = 1.0
    ) -> tuple[torch.Tensor, torch.Tensor]:
        """``embedding (B, T, P, d)``, ``embedding_goal (B, 1, P, d)`` -> means ``(B, T, A)``,
        stds ``(A,)`` (times ``temperature``)."""
        means = self.action_predictor(embedding.flatten(1, 2), embedding_goal.flatten(1, 2))
        return means, self._clamped_log_stds().exp() * temperature

    def predict_values(self, embedding: torch.Tensor, embedding_goal: torch.Tensor) -> torch.Tensor:
        """``V(s, g)`` per frame: ``(B, T, 1)`` (the EMA teacher of a wrapped value head)."""
        if self.value_predictor is None:
            raise ConfigError(
                f"{type(self).__name__}.predict_values requires a value_predictor, got None ({self.algorithm} model)"
            )
        return self.value_predictor(embedding.flatten(1, 2), embedding_goal.flatten(1, 2))

    # -- acting -----------------------------------------------------------------------------
    def get_action(self, info: dict, sample: bool = False, temperature: float = 1.0) -> torch.Tensor:
        """The action of the last frame ``(B, A)`` for ``info["pixels"] (B, T, C, h, w)`` and
        ``info["goal"] (B, 1, C, h, w)`` (preprocessed; extra encoders read ``<key>`` /
        ``goal_<key>``): the mean, or a Gaussian sample when ``sample``. Only the last
        ``history_size`` frames (and the last goal frame) are used. Adds the embeddings to ``info``."""
        who = f"{type(self).__name__}.get_action"
        for key in (keys.PIXELS, *self.extra_encoders.keys()):
            value = require(info, key, who)
            if torch.is_tensor(value) and value.ndim >= 3 and value.shape[1] > self.history_size:
                info[key] = value[:, -self.history_size :]
        goal = require(info, keys.GOAL, who)
        if torch.is_tensor(goal) and goal.ndim == 5 and goal.shape[1] > 1:  # one goal per history frame: the last one
            info[keys.GOAL] = goal[:, -1:]
        info = self.encode(info, pixels_key=keys.PIXELS, target="embed")
        info = self.encode(info, pixels_key=keys.GOAL, prefix=keys.goal_key(""), target="goal_embed")
        means, stds = self.predict_actions(info["embed"], info["goal_embed"], temperature=temperature)
        means = means[:, -1]
        return means + stds * torch.randn_like(means) if sample else means

    # -- training ---------------------------------------------------------------------------
    def loss(self, batch: dict) -> dict:
        """The loss of ``self.algorithm`` on ``batch`` (see :mod:`stable_worldmodel.wm.gcrl.algorithms`)."""
        return LOSSES[self.algorithm](self, batch)

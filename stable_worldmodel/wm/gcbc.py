"""GCBC as release 0.0.3 names it (``stable_worldmodel.wm.gcbc``): ``GCBC``, its ``Predictor``
(one aggregated action per window) and ``Embedder``. Same constructors and ``state_dict`` keys
as 0.0.3, so its checkpoints load. The registry's ``gcbc`` (``make("gcbc")``, ``swm train gcbc``)
is the newer :class:`~stable_worldmodel.wm.gcrl.GCRL` (upstream 0.1.1), which predicts an action
per frame; loading one's weights into the other raises CheckpointError naming the right class.

Shapes (``B`` batch, ``T`` frames, ``P`` tokens per frame, ``d`` width, ``A`` action)::

    encode(info)                 -> info + embed (B, T, P, d)   (gradient stopped at the backbone)
    predict(emb, goal_emb)       -> (B, 1, A)
    get_action(info)             -> (B, A)
    loss(batch)                  -> {"loss", "action_loss"}: MSE to the action of the last history frame
"""

from __future__ import annotations

from collections.abc import Mapping

import torch
import torch.nn.functional as F
from torch import nn

from .. import keys
from ..errors import ConfigError
from .gcrl.algorithms import GOAL_PIXELS
from .gcrl.encoding import GoalImageEncoding, require
from .gcrl.module import Embedder, Transformer, _Positional

__all__ = ["GCBC", "Embedder", "Predictor"]


class Predictor(_Positional):
    """0.0.3's goal-conditioned action head: ``forward(x (B, T*P, dim), g (B, P, dim)) -> (B, 1, action_dim)``.

    Non-causal self-attention and goal cross-attention layers, the last layer one learned
    query (``out_token``) over every token, then ``action_proj``.
    """

    def __init__(
        self,
        *,
        num_patches: int,
        num_frames: int,
        dim: int,
        depth: int,
        heads: int,
        mlp_dim: int,
        action_dim: int,
        dim_head: int = 64,
        dropout: float = 0.0,
        emb_dropout: float = 0.0,
    ):
        super().__init__(num_patches, num_frames, dim, emb_dropout)
        self.transformer = Transformer(
            dim, depth, heads, dim_head, mlp_dim, dropout, num_patches, num_frames, causal=False, pool_type="token"
        )
        self.action_proj = nn.Linear(dim, action_dim)

    def forward(self, x: torch.Tensor, g: torch.Tensor) -> torch.Tensor:
        x, g = self._place(x, g)
        return self.action_proj(self.transformer(x, g))


class GCBC(GoalImageEncoding, nn.Module):
    """``GCBC(encoder, predictor, extra_encoders=None, history_size=3, num_pred=1,
    interpolate_pos_encoding=True)``: 0.0.3's attributes (``backbone``, ``predictor``,
    ``extra_encoders``) and keys. The backbone's embeddings are detached (0.0.3 trains the
    predictor on a frozen encoder)."""

    detach_embeddings = True
    head_prefix = "predictor."
    other_family = (
        "action_predictor.",
        "a GCRL (what swm.wm.make('gcbc') and `swm train gcbc` build, upstream 0.1.1's gcbc: an action per "
        "frame); load it with swm.wm.load_pretrained(...) or swm.wm.GCRL",
    )

    def __init__(
        self,
        encoder: nn.Module,
        predictor: nn.Module,
        extra_encoders: Mapping[str, nn.Module] | None = None,
        history_size: int = 3,
        num_pred: int = 1,
        interpolate_pos_encoding: bool = True,
    ):
        super().__init__()
        self.backbone = encoder
        self.predictor = predictor
        self.extra_encoders = nn.ModuleDict(dict(extra_encoders or {}))
        self.history_size, self.num_pred = int(history_size), int(num_pred)
        self.interpolate_pos_encoding = interpolate_pos_encoding

    def _image_encoder(self) -> nn.Module:
        return self.backbone

    def predict(self, embedding: torch.Tensor, embedding_goal: torch.Tensor) -> torch.Tensor:
        """``embedding (B, T, P, d)``, ``embedding_goal (B, 1, P, d)`` -> ``(B, 1, A)``."""
        return self.predictor(embedding.flatten(1, 2), embedding_goal.flatten(1, 2))

    def get_action(self, info: dict) -> torch.Tensor:
        """``(B, A)`` for ``info["pixels"] (B, T, C, h, w)`` and ``info["goal"] (B, 1, C, h, w)``
        (extra encoders read ``<key>`` / ``goal_<key>``). Adds the embeddings to ``info``."""
        require(info, keys.GOAL, f"{type(self).__name__}.get_action")
        info = self.encode(info, pixels_key=keys.PIXELS, target="embed")
        info = self.encode(info, pixels_key=keys.GOAL, prefix=keys.goal_key(""), target="goal_embed")
        return self.predict(info["embed"], info["goal_embed"]).squeeze(1)

    def loss(self, batch: dict) -> dict:
        """MSE between :meth:`predict` and the action of frame ``history_size - 1`` (``batch``:
        ``pixels (B, T, C, h, w)`` with ``T >= history_size``, ``action (B, T, A)``,
        ``goal_pixels (B, 1, C, h, w)``)."""
        who = f"{type(self).__name__}.loss"
        pixels = require(batch, keys.PIXELS, who)
        h = self.history_size
        if pixels.ndim != 5 or pixels.shape[1] < h:
            raise ConfigError(
                f"{who} requires pixels (B, T, C, h, w) with T >= history_size = {h}, got {tuple(pixels.shape)}"
            )
        require(batch, GOAL_PIXELS, who)
        target = torch.nan_to_num(require(batch, keys.ACTION, who)[:, h - 1 : h].float(), 0.0)
        info = self.encode(dict(batch), pixels_key=keys.PIXELS, target="embed")
        info["embed"] = info["embed"][:, :h]
        info = self.encode(info, pixels_key=GOAL_PIXELS, prefix=keys.goal_key(""), target="goal_embed")
        action_loss = F.mse_loss(self.predict(info["embed"], info["goal_embed"]), target)
        return {"loss": action_loss, "action_loss": action_loss, "emb": info["pixels_embed"]}

"""Building blocks of the goal-conditioned baselines (upstream 0.1.1's ``stable_worldmodel.wm.gcrl.module``).

Same constructors and ``state_dict`` keys as upstream, so its checkpoints load. Shapes use the
legend ``B`` batch, ``T`` frames, ``P`` tokens (patches) per frame, ``d`` token width, ``A``
action (block) width::

    Predictor(x (B, T*P, d), g (B, P, d))             -> (B, T, out_dim)   one output per frame
    QPredictor(x (B, T*P, d), a (B, T, A), g (B, P, d)) -> (B, T, 1)
    MetricValuePredictor(x, g)                        -> (B, T, 1) = -||phi(x) - phi(g)||
    ExpectileLoss(tau)(preds, targets, adv=None)      -> scalar

A :class:`Transformer` alternates causal self-attention (even layers) and cross-attention to
the goal tokens (odd layers); with ``pool_type="attention"`` its last layer is a *frame
aggregation*: one learned query per frame attends to the tokens of that frame and earlier
ones (no residual), with ``"mean"`` the tokens of each frame are averaged. Note that a
depth-2 ``"attention"`` stack is ``[self, frame_agg]``: it never looks at the goal (as
upstream); goal-conditioned presets use depth >= 3.
"""

from __future__ import annotations

import copy
import math
from dataclasses import dataclass
from typing import Any

import torch
import torch.nn.functional as F
from torch import nn

from ...errors import ConfigError, SpaceError
from ..encoders import ConvEncoder
from ..lewm.module import FeedForward

__all__ = [
    "ATT_TYPES",
    "Attention",
    "ConvLogitsEncoder",
    "DoublePredictorWrapper",
    "Embedder",
    "EvalOnly",
    "ExpectileLoss",
    "FeedForward",
    "MetricValuePredictor",
    "Predictor",
    "QPredictor",
    "SelfAttentionTransformer",
    "TeacherStudentWrapper",
    "Transformer",
]

#: ``self`` / ``cross`` / ``frame_agg`` (0.1.1) and ``agg`` (0.0.3's single output token)
ATT_TYPES = ("self", "cross", "frame_agg", "agg")
POOL_TYPES = ("attention", "mean", "token")


class Embedder(nn.Module):
    """Extra-input encoder (e.g. proprio): ``(B, T, in_chans) -> (B, T / tubelet_size, emb_dim)``
    through a 1-d convolution over time (kernel = stride = ``tubelet_size``), in float32."""

    def __init__(self, num_frames: int = 1, tubelet_size: int = 1, in_chans: int = 8, emb_dim: int = 10):
        super().__init__()
        self.num_frames, self.tubelet_size, self.in_chans, self.emb_dim = num_frames, tubelet_size, in_chans, emb_dim
        self.patch_embed = nn.Conv1d(in_chans, emb_dim, kernel_size=tubelet_size, stride=tubelet_size)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        with torch.autocast(x.device.type, enabled=False):
            out = self.patch_embed(x.to(self.patch_embed.weight.dtype).transpose(1, 2))
        return out.transpose(1, 2)


@dataclass
class ImageLogits:
    """What :class:`ConvLogitsEncoder` returns: one embedding per image, ``logits (N, D)``."""

    logits: torch.Tensor


class ConvLogitsEncoder(ConvEncoder):
    """:class:`~stable_worldmodel.wm.encoders.ConvEncoder` answering ``.logits (N, D)``: the
    output GCRL reads as one token per image (a ``last_hidden_state`` is read as a ViT's,
    first token dropped)."""

    def forward(self, pixels: torch.Tensor, interpolate_pos_encoding: bool = False, **kwargs: Any) -> ImageLogits:
        return ImageLogits(super().forward(pixels).last_hidden_state[:, 0])


def _frame_of_token(num_patches: int, num_frames: int) -> torch.Tensor:
    return torch.arange(num_frames * num_patches) // num_patches


class Attention(nn.Module):
    """Pre-norm multi-head attention of kind ``att_type`` (see :data:`ATT_TYPES`).

    ``self``: tokens attend to tokens (block-causal over frames when ``causal``); ``cross``:
    tokens attend to the condition ``c`` (never masked); ``frame_agg``: ``num_frames`` learned
    queries (``frame_tokens``), query ``t`` attending to frames ``<= t`` when ``causal``;
    ``agg``: one learned query (``out_token``) attending to every token. The allowed pairs
    are the persistent buffer ``causal_mask`` (True = attend), as upstream.
    """

    def __init__(
        self,
        dim: int,
        heads: int = 8,
        dim_head: int = 64,
        dropout: float = 0.0,
        num_patches: int = 1,
        num_frames: int = 1,
        att_type: str = "self",
        causal: bool = False,
    ):
        super().__init__()
        if att_type not in ATT_TYPES:
            raise ConfigError(f"Attention requires att_type in {ATT_TYPES}, got {att_type!r}")
        self.att_type, self.num_patches, self.num_frames = att_type, num_patches, num_frames
        self.causal = bool(causal) and att_type in ("self", "frame_agg")
        inner = dim_head * heads
        self.heads, self.scale = heads, dim_head**-0.5
        self.norm = nn.LayerNorm(dim)
        if att_type == "cross":
            self.norm_c = nn.LayerNorm(dim)
        self.attend = nn.Softmax(dim=-1)
        self.dropout = nn.Dropout(dropout)
        self.to_q = nn.Linear(dim, inner, bias=False)
        self.to_kv = nn.Linear(dim, 2 * inner, bias=False)
        project = not (heads == 1 and dim_head == dim)
        self.to_out = nn.Sequential(nn.Linear(inner, dim), nn.Dropout(dropout)) if project else nn.Identity()
        if att_type == "frame_agg":
            self.frame_tokens = nn.Parameter(0.02 * torch.randn(1, num_frames, dim))
        elif att_type == "agg":
            self.out_token = nn.Parameter(0.02 * torch.randn(1, 1, dim))
        if self.causal:
            frame = _frame_of_token(num_patches, num_frames)
            rows = frame if att_type == "self" else torch.arange(num_frames)
            self.register_buffer("causal_mask", (frame[None, :] <= rows[:, None])[None, None])

    def _split(self, t: torch.Tensor) -> torch.Tensor:
        b, n, _ = t.shape
        return t.view(b, n, self.heads, -1).transpose(1, 2)

    def forward(self, x: torch.Tensor, c: torch.Tensor | None = None) -> torch.Tensor:
        """``x: (B, N, dim)`` (and ``c: (B, M, dim)`` for cross) -> ``(B, N or queries, dim)``."""
        b, n, _ = x.shape
        x = self.norm(x)
        kv, mask = x, None
        if self.att_type == "cross":
            q_in, kv = x, self.norm_c(c)
        elif self.att_type == "frame_agg":
            q_in = self.frame_tokens[:, : n // self.num_patches].expand(b, -1, -1)
        elif self.att_type == "agg":
            q_in = self.out_token.expand(b, -1, -1)
        else:
            q_in = x
        if self.causal:
            mask = self.causal_mask[:, :, : q_in.shape[1], :n]
        q = self.to_q(q_in)
        k, v = self.to_kv(kv).chunk(2, dim=-1)
        p = self.dropout.p if self.training else 0.0
        out = F.scaled_dot_product_attention(
            self._split(q), self._split(k), self._split(v), attn_mask=mask, dropout_p=p
        )
        return self.to_out(out.transpose(1, 2).reshape(b, q.shape[1], -1))


class Transformer(nn.Module):
    """Goal-conditioned stack: ``forward(x (B, T*P, dim), g (B, P', dim)) -> (B, T, dim)``
    (``(B, 1, dim)`` for 0.0.3's ``pool_type="token"``); see the module docstring."""

    def __init__(
        self,
        dim: int,
        depth: int,
        heads: int,
        dim_head: int,
        mlp_dim: int,
        dropout: float = 0.0,
        num_patches: int = 1,
        num_frames: int = 1,
        causal: bool = True,
        pool_type: str = "attention",
    ):
        super().__init__()
        if pool_type not in POOL_TYPES:
            raise ConfigError(f"{type(self).__name__} requires pool_type in {POOL_TYPES[:2]}, got {pool_type!r}")
        self.pool_type, self.num_patches, self.num_frames = pool_type, num_patches, num_frames
        self.norm = nn.LayerNorm(dim)
        self.kinds = [self._kind(i, depth) for i in range(depth)]
        self.layers = nn.ModuleList(
            nn.ModuleList(
                [
                    Attention(dim, heads, dim_head, dropout, num_patches, num_frames, kind, causal),
                    FeedForward(dim, mlp_dim, dropout),
                ]
            )
            for kind in self.kinds
        )

    def _kind(self, i: int, depth: int) -> str:
        if i == depth - 1 and self.pool_type != "mean":
            return "frame_agg" if self.pool_type == "attention" else "agg"
        return "self" if i % 2 == 0 else "cross"

    def forward(self, x: torch.Tensor, g: torch.Tensor | None = None) -> torch.Tensor:
        for kind, (attn, ff) in zip(self.kinds, self.layers, strict=True):
            if kind in ("frame_agg", "agg"):  # the pooling layer changes the token count: no residual
                x = ff(attn(x))
            else:
                x = x + (attn(x, g) if kind == "cross" else attn(x))
                x = x + ff(x)
        if self.pool_type == "mean":
            b, n, d = x.shape
            x = x.view(b, n // self.num_patches, self.num_patches, d).mean(dim=2)
        return self.norm(x)


class SelfAttentionTransformer(Transformer):
    """Self-attention only, last layer a frame aggregation: ``forward(x (B, T*P, dim)) -> (B, T, dim)``."""

    def __init__(
        self,
        dim: int,
        depth: int,
        heads: int,
        dim_head: int,
        mlp_dim: int,
        dropout: float = 0.0,
        num_patches: int = 1,
        num_frames: int = 1,
        causal: bool = True,
    ):
        super().__init__(dim, depth, heads, dim_head, mlp_dim, dropout, num_patches, num_frames, causal, "attention")

    def _kind(self, i: int, depth: int) -> str:
        return "frame_agg" if i == depth - 1 else "self"

    def forward(self, x: torch.Tensor, g: torch.Tensor | None = None) -> torch.Tensor:
        return super().forward(x, None)


class _Positional(nn.Module):
    """Learned positions of the ``num_frames * num_patches`` observation tokens and the ``num_patches`` goal tokens."""

    def __init__(self, num_patches: int, num_frames: int, dim: int, emb_dropout: float):
        super().__init__()
        self.num_patches, self.num_frames = num_patches, num_frames
        self.pos_embedding = nn.Parameter(torch.randn(1, num_frames * num_patches, dim))
        self.pos_embedding_goal = nn.Parameter(torch.randn(1, num_patches, dim))
        self.dropout = nn.Dropout(emb_dropout)

    def _place(self, x: torch.Tensor, g: torch.Tensor | None = None) -> tuple[torch.Tensor, torch.Tensor | None]:
        n, limit = x.shape[1], self.pos_embedding.shape[1]
        if n > limit:
            raise SpaceError(
                f"{type(self).__name__} requires at most "
                f"num_frames * num_patches = {self.num_frames} * {self.num_patches} "
                f"= {limit} tokens, got {n}; give at most {self.num_frames} frames"
            )
        x = self.dropout(x + self.pos_embedding[:, :n])
        if g is not None:
            g = g + self.pos_embedding_goal[:, : g.shape[1]]
        return x, g


class Predictor(_Positional):
    """Goal-conditioned head: ``forward(x (B, T*P, dim), g (B, P, dim)) -> (B, T, out_dim)``
    (the action means of a policy, or a value with ``out_dim=1``)."""

    def __init__(
        self,
        *,
        num_patches: int,
        num_frames: int,
        dim: int,
        depth: int,
        heads: int,
        mlp_dim: int,
        out_dim: int,
        dim_head: int = 64,
        dropout: float = 0.0,
        emb_dropout: float = 0.0,
        causal: bool = True,
        pool_type: str = "attention",
    ):
        super().__init__(num_patches, num_frames, dim, emb_dropout)
        self.transformer = Transformer(
            dim, depth, heads, dim_head, mlp_dim, dropout, num_patches, num_frames, causal, pool_type
        )
        self.out_proj = nn.Linear(dim, out_dim)

    def forward(self, x: torch.Tensor, g: torch.Tensor) -> torch.Tensor:
        x, g = self._place(x, g)
        return self.out_proj(self.transformer(x, g))


class QPredictor(_Positional):
    """Goal-conditioned critic ``Q(s, a, g)``: ``forward(x (B, T*P, dim), a (B, T, action_dim),
    g (B, P, dim)) -> (B, T, 1)``; the action joins the frame embeddings in an MLP head
    (``q_head``: two ReLU layers of ``q_hidden_dim``)."""

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
        q_hidden_dim: int = 256,
        dim_head: int = 64,
        dropout: float = 0.0,
        emb_dropout: float = 0.0,
        causal: bool = True,
        pool_type: str = "attention",
    ):
        super().__init__(num_patches, num_frames, dim, emb_dropout)
        self.transformer = Transformer(
            dim, depth, heads, dim_head, mlp_dim, dropout, num_patches, num_frames, causal, pool_type
        )
        self.q_head = nn.Sequential(
            nn.Linear(dim + action_dim, q_hidden_dim),
            nn.ReLU(),
            nn.Linear(q_hidden_dim, q_hidden_dim),
            nn.ReLU(),
            nn.Linear(q_hidden_dim, 1),
        )

    def forward(self, x: torch.Tensor, a: torch.Tensor, g: torch.Tensor) -> torch.Tensor:
        x, g = self._place(x, g)
        frames = self.transformer(x, g)
        return self.q_head(torch.cat([frames, a.to(frames.dtype)], dim=-1))


class MetricValuePredictor(_Positional):
    """``V(s, g) = -||phi(s) - phi(g)||``: state and goal embedded separately by one
    self-attention stack (``embed_proj`` to ``embed_dim``). ``forward(x, g) -> (B, T, 1)``.
    As upstream, the goal is placed with the observation positions (``pos_embedding_goal``
    is kept for the state dict only)."""

    def __init__(
        self,
        *,
        num_patches: int,
        num_frames: int,
        dim: int,
        depth: int,
        heads: int,
        mlp_dim: int,
        embed_dim: int = 64,
        dim_head: int = 64,
        dropout: float = 0.0,
        emb_dropout: float = 0.0,
        causal: bool = True,
    ):
        super().__init__(num_patches, num_frames, dim, emb_dropout)
        self.embed_dim = embed_dim
        self.transformer = SelfAttentionTransformer(
            dim, depth, heads, dim_head, mlp_dim, dropout, num_patches, num_frames, causal
        )
        self.embed_proj = nn.Linear(dim, embed_dim)

    def encode(self, x: torch.Tensor) -> torch.Tensor:
        """``(B, T*P, dim) -> (B, T, embed_dim)``."""
        return self.embed_proj(self.transformer(self._place(x)[0]))

    def forward(self, x: torch.Tensor, g: torch.Tensor) -> torch.Tensor:
        sq = (self.encode(x) - self.encode(g)).square().sum(dim=-1, keepdim=True)
        return -torch.sqrt(sq.clamp(min=1e-6))


class DoublePredictorWrapper(nn.Module):
    """Two independent ``predictor_cls(**kwargs)`` (``net1``, ``net2``); ``forward`` returns both outputs."""

    def __init__(self, predictor_cls: Any, **kwargs: Any):
        super().__init__()
        self.net1 = predictor_cls(**kwargs)
        self.net2 = predictor_cls(**kwargs)

    def forward(self, *args: Any, **kwargs: Any) -> tuple[Any, Any]:
        return self.net1(*args, **kwargs), self.net2(*args, **kwargs)


class ExpectileLoss(nn.Module):
    """``mean(|tau - 1[w < 0]| * (targets - preds)^2)`` with ``w = adv`` when given, else the
    (detached) residual ``targets - preds``: ``tau > 0.5`` fits an upper expectile."""

    def __init__(self, tau: float = 0.9):
        super().__init__()
        if not 0.0 < float(tau) < 1.0:
            raise ConfigError(f"ExpectileLoss requires 0 < tau < 1, got {tau!r}")
        self.tau = float(tau)

    def forward(self, preds: torch.Tensor, targets: torch.Tensor, adv: torch.Tensor | None = None) -> torch.Tensor:
        residual = targets - preds
        sign_of = adv if adv is not None else residual.detach()
        weight = (self.tau - (sign_of < 0).to(residual.dtype)).abs()
        return (weight * residual.square()).mean()


class TeacherStudentWrapper(nn.Module):
    """An EMA copy (``teacher``) of ``student``, under the keys of stable-pretraining's
    ``TeacherStudentWrapper`` (``student.*``, ``teacher.*`` and the ``*ema_coefficient`` buffers).

    :meth:`update_teacher` moves the teacher's parameters and buffers towards the student's:
    ``teacher = c * teacher + (1 - c) * student``; ``warm_init`` starts the teacher equal to
    the student; coefficients 0 make the teacher the student itself. ``forward`` runs the teacher.
    """

    def __init__(
        self,
        student: nn.Module,
        warm_init: bool = True,
        base_ema_coefficient: float = 0.996,
        final_ema_coefficient: float = 1.0,
    ):
        super().__init__()
        for name, value in (
            ("base_ema_coefficient", base_ema_coefficient),
            ("final_ema_coefficient", final_ema_coefficient),
        ):
            if not 0.0 <= float(value) <= 1.0:
                raise ConfigError(f"TeacherStudentWrapper requires {name} in [0, 1], got {value!r}")
        self.student = student
        self.register_buffer("base_ema_coefficient", torch.tensor(float(base_ema_coefficient)))
        self.register_buffer("final_ema_coefficient", torch.tensor(float(final_ema_coefficient)))
        if float(base_ema_coefficient) == 0.0 and float(final_ema_coefficient) == 0.0:
            self.teacher = student
            self.register_buffer("ema_coefficient", self.base_ema_coefficient.clone())
            return
        self.teacher = copy.deepcopy(student)
        self.teacher.requires_grad_(False)
        self.register_buffer("ema_coefficient", torch.zeros(()) if warm_init else self.base_ema_coefficient.clone())
        if warm_init:
            self.update_teacher()
            self.ema_coefficient.copy_(self.base_ema_coefficient)

    @torch.no_grad()
    def update_teacher(self) -> None:
        c = float(self.ema_coefficient)
        if c in (0.0, 1.0):  # the teacher is the student, or fixed
            return
        params = zip(self.teacher.parameters(), self.student.parameters(), strict=True)
        for t, s in [*params, *zip(self.teacher.buffers(), self.student.buffers(), strict=True)]:
            if t.is_floating_point():
                t.mul_(c).add_(s.detach().to(t.dtype), alpha=1.0 - c)
            else:
                t.copy_(s)

    @torch.no_grad()
    def update_ema_coefficient(self, epoch: int, total_epochs: int) -> None:
        """Cosine schedule from ``base_ema_coefficient`` (epoch 0) to ``final_ema_coefficient``."""
        base, final = float(self.base_ema_coefficient), float(self.final_ema_coefficient)
        self.ema_coefficient.fill_(final - 0.5 * (final - base) * (1 + math.cos(epoch / total_epochs * math.pi)))

    def forward_student(self, *args: Any, **kwargs: Any) -> Any:
        return self.student(*args, **kwargs)

    def forward_teacher(self, *args: Any, **kwargs: Any) -> Any:
        with torch.no_grad():
            return self.teacher(*args, **kwargs)

    def forward(self, *args: Any, **kwargs: Any) -> Any:
        return self.forward_teacher(*args, **kwargs)


class EvalOnly(nn.Module):
    """``backbone`` frozen in eval mode (stable-pretraining's ``EvalOnly``; keys ``backbone.*``)."""

    def __init__(self, backbone: nn.Module):
        super().__init__()
        self.backbone = backbone
        self.backbone.requires_grad_(False)
        self.backbone.eval()

    def train(self, mode: bool = True) -> EvalOnly:
        super().train(mode)
        self.backbone.eval()
        return self

    def forward(self, *args: Any, **kwargs: Any) -> Any:
        with torch.no_grad():
            return self.backbone(*args, **kwargs)

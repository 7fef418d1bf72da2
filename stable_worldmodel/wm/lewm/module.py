"""Building blocks of LeWM and PLDM, with upstream 0.1.1's constructor arguments and
``state_dict`` names (checkpoints made by upstream load into these classes).

- :class:`Predictor`: a causal transformer over frame embeddings ``(B, T, D)`` conditioned
  on action embeddings ``(B, T, D)`` through AdaLN-zero blocks, with learned positions.
- :class:`Embedder`: action blocks ``(B, T, A)`` -> ``(B, T, emb_dim)`` (a 1x1 conv, then
  a SiLU MLP).
- :class:`MLP`: Linear -> norm -> activation -> Linear (projector heads, inverse dynamics).

Shapes: ``B`` batch, ``T`` frames, ``D`` embedding dim, ``A`` action dim.
"""

from __future__ import annotations

import torch
import torch.nn.functional as F
from torch import nn

__all__ = ["MLP", "Attention", "Block", "ConditionalBlock", "Embedder", "FeedForward", "Predictor", "Transformer"]


class FeedForward(nn.Module):
    """Pre-norm MLP of a transformer block: ``(..., dim) -> (..., dim)``."""

    def __init__(self, dim: int, hidden_dim: int, dropout: float = 0.0):
        super().__init__()
        self.net = nn.Sequential(
            nn.LayerNorm(dim),
            nn.Linear(dim, hidden_dim),
            nn.GELU(),
            nn.Dropout(dropout),
            nn.Linear(hidden_dim, dim),
            nn.Dropout(dropout),
        )

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return self.net(x)


class Attention(nn.Module):
    """Pre-norm multi-head self-attention, causal by default: ``(B, T, dim) -> (B, T, dim)``."""

    def __init__(self, dim: int, heads: int = 8, dim_head: int = 64, dropout: float = 0.0):
        super().__init__()
        inner = heads * dim_head
        self.heads, self.dim_head, self.dropout = heads, dim_head, dropout
        self.scale = dim_head**-0.5
        self.norm = nn.LayerNorm(dim)
        self.to_qkv = nn.Linear(dim, 3 * inner, bias=False)
        if heads == 1 and dim_head == dim:
            self.to_out: nn.Module = nn.Identity()
        else:
            self.to_out = nn.Sequential(nn.Linear(inner, dim), nn.Dropout(dropout))

    def __setstate__(self, state: dict) -> None:
        """Unpickling a module that upstream 0.1.1 pickled (a ``*_object.ckpt``): it has no
        ``dim_head`` attribute, which is its ``to_qkv`` width over ``3 * heads``."""
        super().__setstate__(state)
        if "dim_head" not in self.__dict__:
            self.dim_head = self.to_qkv.out_features // (3 * self.heads)

    def _heads(self, x: torch.Tensor) -> torch.Tensor:
        b, t, _ = x.shape
        return x.view(b, t, self.heads, self.dim_head).transpose(1, 2)

    def forward(self, x: torch.Tensor, causal: bool = True) -> torch.Tensor:
        p = self.dropout if self.training else 0.0
        if x.shape[1] == 1 and p == 0.0:  # one token attends to itself with weight 1: only its values are needed
            inner = self.heads * self.dim_head
            return self.to_out(F.linear(self.norm(x), self.to_qkv.weight[2 * inner :]))
        q, k, v = self.to_qkv(self.norm(x)).chunk(3, dim=-1)
        return self._attend(q, k, v, causal)

    def _attend(self, q: torch.Tensor, k: torch.Tensor, v: torch.Tensor, causal: bool) -> torch.Tensor:
        """Multi-head attention of queries ``q (B, Tq, inner)`` over ``k, v (B, T, inner)``, projected out."""
        b, tq, _ = q.shape
        p = self.dropout if self.training else 0.0
        out = F.scaled_dot_product_attention(
            self._heads(q), self._heads(k), self._heads(v), dropout_p=p, is_causal=causal
        )
        return self.to_out(out.transpose(1, 2).reshape(b, tq, self.heads * self.dim_head))

    def forward_last(self, x: torch.Tensor) -> torch.Tensor:
        """The last row of ``forward(x, causal=True)``: ``(B, T, dim) -> (B, 1, dim)``; the last token
        attends to every token, so only its query is computed."""
        if x.shape[1] == 1:
            return self(x)
        inner = self.heads * self.dim_head
        h = self.norm(x)
        q = F.linear(h[:, -1:], self.to_qkv.weight[:inner])
        k, v = F.linear(h, self.to_qkv.weight[inner:]).chunk(2, dim=-1)
        return self._attend(q, k, v, causal=False)


def _modulate(x: torch.Tensor, shift: torch.Tensor, scale: torch.Tensor) -> torch.Tensor:
    return torch.addcmul(shift, x, 1 + scale)


class ConditionalBlock(nn.Module):
    """Transformer block whose norms are shifted, scaled and gated by the condition
    (AdaLN-zero: the modulation starts at zero, so the block starts as the identity)."""

    def __init__(self, dim: int, heads: int, dim_head: int, mlp_dim: int, dropout: float = 0.0):
        super().__init__()
        self.attn = Attention(dim, heads=heads, dim_head=dim_head, dropout=dropout)
        self.mlp = FeedForward(dim, mlp_dim, dropout=dropout)
        self.norm1 = nn.LayerNorm(dim, elementwise_affine=False, eps=1e-6)
        self.norm2 = nn.LayerNorm(dim, elementwise_affine=False, eps=1e-6)
        self.adaLN_modulation = nn.Sequential(nn.SiLU(), nn.Linear(dim, 6 * dim))
        nn.init.zeros_(self.adaLN_modulation[1].weight)
        nn.init.zeros_(self.adaLN_modulation[1].bias)

    def forward(self, x: torch.Tensor, c: torch.Tensor) -> torch.Tensor:
        return self.modulated(x, self.adaLN_modulation(c))

    def modulated(self, x: torch.Tensor, mod: torch.Tensor, last: bool = False) -> torch.Tensor:
        """``forward`` with the condition's modulation ``adaLN_modulation(c): (B, T, 6 * dim)`` given
        (computed once per rollout). ``last=True``: only the last token's output ``(B, 1, dim)``."""
        shift1, scale1, gate1, shift2, scale2, gate2 = mod.chunk(6, dim=-1)
        h = _modulate(self.norm1(x), shift1, scale1)
        if last and x.shape[1] > 1:
            x, shift2, scale2, gate1, gate2 = x[:, -1:], shift2[:, -1:], scale2[:, -1:], gate1[:, -1:], gate2[:, -1:]
            x = x + gate1 * self.attn.forward_last(h)
        else:
            x = x + gate1 * self.attn(h)
        return x + gate2 * self.mlp(_modulate(self.norm2(x), shift2, scale2))


class Block(nn.Module):
    """Plain pre-norm transformer block (no condition)."""

    def __init__(self, dim: int, heads: int, dim_head: int, mlp_dim: int, dropout: float = 0.0):
        super().__init__()
        self.attn = Attention(dim, heads=heads, dim_head=dim_head, dropout=dropout)
        self.mlp = FeedForward(dim, mlp_dim, dropout=dropout)
        self.norm1 = nn.LayerNorm(dim, elementwise_affine=False, eps=1e-6)
        self.norm2 = nn.LayerNorm(dim, elementwise_affine=False, eps=1e-6)

    def forward(self, x: torch.Tensor, c: torch.Tensor | None = None) -> torch.Tensor:
        x = x + self.attn(self.norm1(x))
        return x + self.mlp(self.norm2(x))


def _linear_or_identity(d_in: int, d_out: int) -> nn.Module:
    return nn.Linear(d_in, d_out) if d_in != d_out else nn.Identity()


class Transformer(nn.Module):
    """``depth`` blocks between optional input / condition / output projections."""

    def __init__(
        self,
        input_dim: int,
        hidden_dim: int,
        output_dim: int,
        depth: int,
        heads: int,
        dim_head: int,
        mlp_dim: int,
        dropout: float = 0.0,
        block_class: type[nn.Module] = Block,
    ):
        super().__init__()
        self.norm = nn.LayerNorm(hidden_dim)
        self.layers = nn.ModuleList(block_class(hidden_dim, heads, dim_head, mlp_dim, dropout) for _ in range(depth))
        self.input_proj = _linear_or_identity(input_dim, hidden_dim)
        self.cond_proj = _linear_or_identity(input_dim, hidden_dim)
        self.output_proj = _linear_or_identity(hidden_dim, output_dim)

    def forward(self, x: torch.Tensor, c: torch.Tensor | None = None) -> torch.Tensor:
        x = self.input_proj(x)
        c = self.cond_proj(c) if c is not None else None
        for block in self.layers:
            x = block(x, c)
        return self.output_proj(self.norm(x))


class Predictor(nn.Module):
    """Autoregressive next-embedding predictor.

    ``forward(x, c)``: frame embeddings ``x: (B, T, input_dim)`` with ``T <= num_frames``
    and action embeddings ``c: (B, T, input_dim)`` -> ``(B, T, output_dim)``, where output
    ``t`` predicts the embedding of frame ``t + 1`` from frames ``<= t`` (causal attention).
    """

    def __init__(
        self,
        *,
        num_frames: int,
        depth: int,
        heads: int,
        mlp_dim: int,
        input_dim: int,
        hidden_dim: int,
        output_dim: int | None = None,
        dim_head: int = 64,
        dropout: float = 0.0,
        emb_dropout: float = 0.0,
    ):
        super().__init__()
        self.num_frames, self.depth, self.heads, self.dim_head = num_frames, depth, heads, dim_head
        self.input_dim, self.hidden_dim, self.mlp_dim = input_dim, hidden_dim, mlp_dim
        self.output_dim = output_dim or input_dim
        self.emb_dropout = emb_dropout
        self.pos_embedding = nn.Parameter(torch.randn(1, num_frames, input_dim))
        self.dropout = nn.Dropout(emb_dropout)
        self.transformer = Transformer(
            input_dim,
            hidden_dim,
            self.output_dim,
            depth,
            heads,
            dim_head,
            mlp_dim,
            dropout,
            block_class=ConditionalBlock,
        )

    def forward(self, x: torch.Tensor, c: torch.Tensor) -> torch.Tensor:
        return self.transformer(self._positioned(x), c)

    def _positioned(self, x: torch.Tensor) -> torch.Tensor:
        """``x`` plus the learned positions of its ``T <= num_frames`` frames (then embedding dropout)."""
        t = x.shape[1]
        if t > self.num_frames:
            raise ValueError(f"Predictor requires at most num_frames={self.num_frames} frames, got {t}")
        return self.dropout(x + self.pos_embedding[:, :t])

    # -- open-loop rollouts: the actions' modulation computed once, only the last output ---------------
    def condition(self, c: torch.Tensor) -> list[torch.Tensor]:
        """Per block, the AdaLN modulation of action embeddings ``c: (B, T, input_dim)``:
        ``(B, T, 6 * hidden_dim)`` each. A rollout computes it once for all its actions and hands
        :meth:`forward_last` the slices of each window (each action sits in up to ``num_frames`` windows)."""
        c = self.transformer.cond_proj(c)
        return [block.adaLN_modulation(c) for block in self.transformer.layers]

    def forward_last(self, x: torch.Tensor, mods: list[torch.Tensor]) -> torch.Tensor:
        """The last output of ``forward(x, c)``, ``(B, output_dim)``, from ``mods``: :meth:`condition`
        of ``c``, sliced to ``x``'s frames. The last block computes the last token only."""
        tr = self.transformer
        x = tr.input_proj(self._positioned(x))
        last = len(tr.layers) - 1
        for i, (block, mod) in enumerate(zip(tr.layers, mods, strict=True)):
            x = block.modulated(x, mod, last=i == last)
        return tr.output_proj(tr.norm(x[:, -1]))


class Embedder(nn.Module):
    """Action encoder: ``(B, T, input_dim) -> (B, T, emb_dim)`` (1x1 conv to ``smoothed_dim``, then MLP)."""

    def __init__(self, input_dim: int = 10, smoothed_dim: int = 10, emb_dim: int = 10, mlp_scale: int = 4):
        super().__init__()
        self.input_dim, self.smoothed_dim, self.emb_dim, self.mlp_scale = input_dim, smoothed_dim, emb_dim, mlp_scale
        self.patch_embed = nn.Conv1d(input_dim, smoothed_dim, kernel_size=1)
        self.embed = nn.Sequential(
            nn.Linear(smoothed_dim, mlp_scale * emb_dim), nn.SiLU(), nn.Linear(mlp_scale * emb_dim, emb_dim)
        )

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        x = x.to(self.patch_embed.weight.dtype)
        # a kernel-1 conv over time is a linear map of the last dim
        w = self.patch_embed.weight.squeeze(-1)
        return self.embed(F.linear(x, w, self.patch_embed.bias))


class MLP(nn.Module):
    """``(N, input_dim) -> (N, output_dim)``: Linear, ``norm_fn(hidden_dim)``, ``act_fn()``, Linear.

    ``norm_fn=None`` skips the norm. A ``BatchNorm1d`` norm accepts ``(N, D)`` only; other
    norms accept any leading shape.
    """

    def __init__(
        self,
        input_dim: int,
        hidden_dim: int,
        output_dim: int | None = None,
        norm_fn: type[nn.Module] | None = nn.LayerNorm,
        act_fn: type[nn.Module] = nn.GELU,
    ):
        super().__init__()
        self.input_dim, self.hidden_dim = input_dim, hidden_dim
        self.output_dim = output_dim or input_dim
        self.net = nn.Sequential(
            nn.Linear(input_dim, hidden_dim),
            norm_fn(hidden_dim) if norm_fn is not None else nn.Identity(),
            act_fn(),
            nn.Linear(hidden_dim, self.output_dim),
        )

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return self.net(x)

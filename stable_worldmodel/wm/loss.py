"""Regularizers and losses of the JEPA world models (upstream 0.1.1 names and semantics).

- :class:`SIGReg` (LeJEPA, arXiv 2511.08544): Epps-Pulley test of the embeddings against
  an isotropic Gaussian along random 1-D projections; LeWM's only anti-collapse term.
- :class:`VCReg`: VICReg-style variance (hinge on the std) and covariance terms, over the
  batch and over time.
- :class:`PLDMLoss` (arXiv 2502.14819): VCReg + temporal alignment + inverse dynamics.
- :class:`TemporalStraighteningLoss`: mean negative cosine of consecutive latent velocities.

Shapes: ``B`` batch, ``T`` time, ``D`` embedding dim, ``A`` action dim.
"""

from __future__ import annotations

import torch
import torch.nn.functional as F
from torch import nn

__all__ = ["PLDMLoss", "SIGReg", "TemporalStraighteningLoss", "VCReg"]


class SIGReg(nn.Module):
    """Sketched isotropic Gaussian regularizer.

    ``forward(proj)`` takes embeddings ``(T, B, D)`` (or ``(B, D)``), draws ``num_proj``
    random unit directions, and for each time step and direction compares the empirical
    characteristic function of the projected batch with the standard normal one,
    ``exp(-t^2 / 2)``, on ``knots`` points of ``t in [0, 3]`` (trapezoid weights times the
    Gaussian window). The statistic is scaled by the batch size ``B`` and averaged over
    directions and time: 0 for a perfect ``N(0, I)`` batch, large for a collapsed one.

    ``generator``: an optional ``torch.Generator`` for the directions (the default draws
    from the global RNG, so seeding torch makes training reproducible).

    Under distributed training the batch is gathered from every process first
    (:func:`stable_worldmodel.train.distributed.gather_batch`): the statistic and its gradients
    are those of the global batch.
    """

    def __init__(self, knots: int = 17, num_proj: int = 1024):
        super().__init__()
        if int(knots) < 2 or int(num_proj) < 1:
            raise ValueError(f"SIGReg requires knots >= 2 and num_proj >= 1, got knots={knots}, num_proj={num_proj}")
        self.num_proj = int(num_proj)
        t = torch.linspace(0.0, 3.0, int(knots), dtype=torch.float32)
        step = 3.0 / (int(knots) - 1)
        trapezoid = torch.full((int(knots),), 2.0 * step)
        trapezoid[0] = trapezoid[-1] = step
        window = torch.exp(-0.5 * t.square())
        self.register_buffer("t", t)
        self.register_buffer("phi", window)
        self.register_buffer("weights", trapezoid * window)

    def forward(self, proj: torch.Tensor, generator: torch.Generator | None = None) -> torch.Tensor:
        from ..train.distributed import gather_batch

        proj = gather_batch(proj, dim=-2)
        directions = torch.randn(proj.shape[-1], self.num_proj, device=proj.device, generator=generator)
        directions = directions / directions.norm(dim=0, keepdim=True)
        x = proj.float() @ directions  # (..., B, P)
        real, imag = _EmpiricalCF.apply(x, self.t)  # (K, ..., P)
        knots = (-1,) + (1,) * (real.dim() - 1)
        err = (real - self.phi.view(knots)).square() + imag.square()
        per_direction = self.weights @ err.flatten(1)  # (... * P,)
        return per_direction.mean() * proj.shape[-2]


class _EmpiricalCF(torch.autograd.Function):
    """Empirical characteristic function of ``x (..., B, P)`` at the knots ``t (K,)``, over B.

    Returns ``(mean cos(t x), mean sin(t x))``, each ``(K, ..., P)``. Knots lead the layout so
    every elementwise op runs on contiguous slices. The backward reuses the forward's cos and
    sin (autograd through ``cos``/``sin`` would evaluate both again): SIGReg's forward and
    backward take less than half the time of plain autograd (``(4, 64, 128)`` embeddings, 256
    directions, one CPU thread: 8.5 ms against 19.7 ms).
    """

    @staticmethod
    def forward(ctx, x: torch.Tensor, t: torch.Tensor):
        angles = t.view((-1,) + (1,) * x.dim()) * x  # (K, ..., B, P)
        cos = angles.cos()
        sin = angles.sin_()
        ctx.save_for_backward(cos, sin, t)
        return cos.mean(dim=-2), sin.mean(dim=-2)

    @staticmethod
    @torch.autograd.function.once_differentiable
    def backward(ctx, grad_real: torch.Tensor, grad_imag: torch.Tensor):
        cos, sin, t = ctx.saved_tensors
        scale = t.view((-1,) + (1,) * (grad_real.dim() - 1)) / cos.shape[-2]
        # d mean cos(t x_b) / d x_b = -t sin(t x_b) / B ; d mean sin(t x_b) / d x_b = t cos(t x_b) / B
        # (out of place: the saved cos and sin stay valid for a second backward, retain_graph=True)
        grad = cos * (grad_imag * scale).unsqueeze(-2)
        grad.sub_(sin * (grad_real * scale).unsqueeze(-2))
        return grad.sum(dim=0), None


class VCReg(nn.Module):
    """Variance-covariance regularizer over the batch and over time.

    ``forward(z)`` with ``z: (B, T, D)`` returns ``std_loss`` (mean hinge ``relu(1 - std)``
    of each dim over the batch), ``cov_loss`` (mean squared off-diagonal covariance over
    the batch), and ``std_t_loss`` / ``cov_t_loss``, the same over time. Under distributed
    training the batch is gathered from every process first, as for :class:`SIGReg`.
    """

    def __init__(self, eps: float = 1e-4):
        super().__init__()
        self.eps = float(eps)

    def _std(self, z: torch.Tensor) -> torch.Tensor:
        """``z: (N, G, D)`` -> hinge on the std over N, averaged over dims and G."""
        std = (z.var(dim=0) + self.eps).sqrt()
        return F.relu(1.0 - std).mean()

    @staticmethod
    def _cov(z: torch.Tensor) -> torch.Tensor:
        """``z: (N, G, D)`` (centred over N) -> mean squared off-diagonal covariance."""
        n, _, d = z.shape
        zg = z.transpose(0, 1)  # (G, N, D)
        cov = zg.transpose(1, 2) @ zg / max(n - 1, 1)  # (G, D, D)
        off = cov.square().sum(dim=(-1, -2)) - cov.diagonal(dim1=-2, dim2=-1).square().sum(-1)
        return (off / max(d * d - d, 1)).mean()

    def forward(self, z: torch.Tensor) -> dict[str, torch.Tensor]:
        from ..train.distributed import gather_batch

        if z.dim() == 2:
            z = z.unsqueeze(1)
        z = gather_batch(z, dim=0)
        z = z - z.mean(dim=0, keepdim=True)
        zt = z.transpose(0, 1)  # (T, B, D): statistics over time (of the batch-centred z)
        return {
            "std_loss": self._std(z),
            "std_t_loss": self._std(zt),
            "cov_loss": self._cov(z),
            "cov_t_loss": self._cov(zt),
        }


class PLDMLoss(nn.Module):
    """PLDM's terms: ``VCReg`` on ``z: (B, T, D)``, temporal alignment ``mse(z[:, :-1], z[:, 1:])``,
    and, given ``a_pred`` / ``a_target`` ``(B, T-1, A)``, the inverse-dynamics ``idm_loss``."""

    def __init__(self) -> None:
        super().__init__()
        self.vc_reg = VCReg()

    def forward(
        self, z: torch.Tensor, a_pred: torch.Tensor | None = None, a_target: torch.Tensor | None = None
    ) -> dict[str, torch.Tensor]:
        out: dict[str, torch.Tensor] = {}
        if a_pred is not None and a_target is not None:
            out["idm_loss"] = F.mse_loss(a_pred, a_target)
        out["temp_align_loss"] = F.mse_loss(z[:, :-1], z[:, 1:])
        out.update(self.vc_reg(z))
        return out


class TemporalStraighteningLoss(nn.Module):
    """``x: (B, T, D)`` -> minus the mean cosine similarity of consecutive velocities
    ``x[t+1] - x[t]`` (-1 for straight latent paths; needs T >= 3)."""

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        v = x[:, 1:] - x[:, :-1]
        return -F.cosine_similarity(v[:, :-1], v[:, 1:], dim=-1).mean()

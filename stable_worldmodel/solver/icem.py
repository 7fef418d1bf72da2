"""iCEM (Pinneri et al., 2020): CEM with colored noise, elite reuse and momentum."""

from __future__ import annotations

from typing import Any

import torch

from ..errors import check_int
from ._registry import register_solver
from ._start import GaussianStart
from .base import AUTO_BATCH, BaseSolver, PlanKnobs


def colored_noise(white: torch.Tensor, beta: float) -> torch.Tensor:
    """Turn white noise ``(..., H)`` into unit-variance noise with power spectrum ``1 / f**beta`` along H."""
    h = white.shape[-1]
    if beta == 0 or h == 1:
        return white
    freqs = torch.fft.rfftfreq(h, device=white.device).to(white.dtype)
    freqs[0] = freqs[1] if h > 1 else 1.0  # no infinite DC gain
    scale = freqs ** (-beta / 2)
    spectrum = torch.fft.rfft(white, dim=-1, norm="ortho") * scale
    # per-step variance of the result: (s0^2 + 2 sum s_k^2 [+ s_nyquist^2 once]) / H
    power = scale**2
    total = power[0] + 2 * power[1:].sum() - (power[-1] if h % 2 == 0 else 0)
    return torch.fft.irfft(spectrum, n=h, dim=-1, norm="ortho") / torch.sqrt(total / h)


def coloring_matrix(
    h: int, beta: float, device: torch.device | str | None = None, dtype: torch.dtype = torch.float32
) -> torch.Tensor:
    """The ``(H, H)`` matrix ``M`` with ``colored_noise(white, beta) == white @ M`` (up to rounding).

    :func:`colored_noise` is linear along H, so row ``i`` of ``M`` is the colored unit
    vector ``e_i``; one small matmul per iteration replaces an FFT round trip (the FFT and its
    bookkeeping were a third of an iCEM plan on the CPU).
    """
    return colored_noise(torch.eye(h, dtype=torch.float64), beta).to(device=device, dtype=dtype)


@register_solver("icem")
class ICEMSolver(GaussianStart, BaseSolver):
    """Improved CEM, batched over envs.

    Differences from :class:`~stable_worldmodel.solver.CEMSolver`: noise is colored along
    the horizon (power spectrum ``1 / f**noise_beta``: smoother plans), a fraction
    ``elite_keep_frac`` of the elites is carried into the next iteration's candidates,
    mean/std are updated with ``momentum`` (``new = momentum * old + (1 - momentum) * fit``),
    and the cheapest plan ever evaluated is returned (the final mean with ``return_mean=True``).
    Upstream 0.1.1's ``alpha`` (the momentum) and ``n_elite_keep`` (a count of kept elites) are
    accepted too. ``batch_size`` as in CEM; ``callbacks`` as in :mod:`.callbacks`.
    Returns ``actions: (B, H, A)``, ``costs: (B,)``, ``mean``, ``var`` (std).
    """

    _inference_mode = True
    _uses_topk = True
    knobs = PlanKnobs(elites="topk", summary="improved CEM: coloured noise, elites kept, momentum")

    def __init__(
        self,
        model: Any,
        batch_size: int | None = AUTO_BATCH,
        num_samples: int = 300,
        var_scale: float = 1,
        n_steps: int = 30,
        topk: int = 30,
        noise_beta: float = 2.0,
        elite_keep_frac: float = 0.3,
        momentum: float = 0.1,
        device: str | torch.device | None = "cpu",
        seed: int = 1234,
        callbacks: list | None = None,
        *,
        alpha: float | None = None,
        n_elite_keep: int | None = None,
        return_mean: bool = False,
    ) -> None:
        super().__init__(model, batch_size, num_samples, var_scale, device, seed, n_steps, topk, callbacks=callbacks)
        elite_keep_frac = self._check_number("elite_keep_frac", elite_keep_frac, minimum=0.0, maximum=1.0)
        if alpha is not None:  # upstream 0.1.1's name of the momentum
            momentum = alpha
        momentum = self._check_number("momentum" if alpha is None else "alpha", momentum, minimum=0.0, maximum=1.0)
        self.noise_beta = self._check_number("noise_beta", noise_beta, minimum=0.0)
        self.momentum = momentum
        self.n_keep = int(elite_keep_frac * self.topk)
        if n_elite_keep is not None:  # upstream 0.1.1: a count of elites instead of a fraction
            self.n_keep = min(check_int(type(self).__name__, "n_elite_keep", n_elite_keep, minimum=0), self.topk)
        self.return_mean = bool(return_mean)

    def _optimize(self, info: dict, init_action: torch.Tensor | None) -> dict:
        mean = self._initial_mean(init_action)
        std = torch.full_like(mean, self.var_scale)
        b, h, a = mean.shape
        s = self.num_samples
        color = None if self.noise_beta == 0 or h == 1 else coloring_matrix(h, self.noise_beta, self.device, self.dtype)
        info_new = self._expand(info, s)
        info_all = self._expand(info, s + self.n_keep)
        kept = None
        best, best_cost = mean, torch.full((b,), float("inf"), device=self.device, dtype=self.dtype)
        for step in range(self.n_steps):
            white = self._randn(s, a, h)  # colored along H, then laid out (b, S, H, A)
            noise = (white if color is None else torch.matmul(white, color)).transpose(-1, -2)
            noise[:, 0].zero_()  # candidate 0 is the mean
            # new candidates, then the kept elites, in one contiguous (b, S [+ n_keep], H, A) tensor
            candidates = mean.new_empty((b, s + (0 if kept is None else self.n_keep), h, a))
            self._clamp_(torch.addcmul(mean.unsqueeze(1), std.unsqueeze(1), noise, out=candidates[:, :s]))
            if kept is not None:
                candidates[:, s:] = kept
            costs = self._cost(info_all if kept is not None else info_new, candidates)
            elite_costs, elites = self._elites(candidates, costs, self.topk)
            better = elite_costs[:, 0] < best_cost
            best = torch.where(better[:, None, None], elites[:, 0], best)
            best_cost = torch.minimum(elite_costs[:, 0], best_cost)
            kept = elites[:, : self.n_keep] if self.n_keep else None
            fit_mean, fit_std = self._mean_std(elites)
            prev_mean, prev_var = mean, std
            mean = torch.lerp(fit_mean, mean, self.momentum)
            std = torch.lerp(fit_std, std, self.momentum)
            if self.callbacks:
                topk_inds = costs.topk(self.topk, dim=1, largest=False).indices
                state = dict(candidates=candidates, costs=costs, topk_vals=elite_costs, topk_candidates=elites)
                if self._notify(
                    step=step, **state, topk_inds=topk_inds, mean=mean, var=std, prev_mean=prev_mean, prev_var=prev_var
                ):
                    break
        return {"actions": mean if self.return_mean else best, "costs": best_cost, "mean": mean, "var": std}

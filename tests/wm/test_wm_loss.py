"""The regularizers and losses of the JEPA models on inputs whose value is known."""

from __future__ import annotations

import pytest
import torch
from _tiny import assert_close, randn

from stable_worldmodel.wm.loss import PLDMLoss, SIGReg, TemporalStraighteningLoss, VCReg


def directions(seed: int = 1) -> torch.Generator:
    return torch.Generator().manual_seed(seed)


# -- SIGReg ----------------------------------------------------------------------------------
def test_sigreg_is_small_for_standard_normal_samples():
    sigreg = SIGReg(num_proj=128)
    assert sigreg(randn(256, 8), generator=directions()) < 3.0
    assert sigreg(randn(3, 256, 8), generator=directions()) < 3.0  # (T, B, D)


@pytest.mark.parametrize("collapsed", ["constant", "shifted", "wide"])
def test_sigreg_is_large_away_from_the_standard_normal(collapsed):
    x = {"constant": torch.ones(256, 8), "shifted": randn(256, 8) + 2.0, "wide": 3.0 * randn(256, 8)}[collapsed]
    assert SIGReg(num_proj=128)(x, generator=directions()) > 50.0


def test_sigreg_directions_follow_the_generator():
    sigreg, x = SIGReg(num_proj=16), randn(64, 8)
    assert sigreg(x, generator=directions(3)) == sigreg(x, generator=directions(3))
    assert sigreg(x, generator=directions(3)) != sigreg(x, generator=directions(4))


def test_sigreg_is_differentiable_and_has_no_parameters():
    sigreg = SIGReg(num_proj=16)
    x = randn(32, 4).requires_grad_(True)
    sigreg(x, generator=directions()).backward()
    assert torch.isfinite(x.grad).all() and x.grad.abs().sum() > 0
    assert list(sigreg.parameters()) == []


def plain_sigreg(x: torch.Tensor, sigreg: SIGReg, generator: torch.Generator) -> torch.Tensor:
    """The Epps-Pulley statistic written out with plain autograd ops (the reference)."""
    d = torch.randn(x.shape[-1], sigreg.num_proj, generator=generator)
    angles = (x @ (d / d.norm(dim=0))).unsqueeze(-1) * sigreg.t
    err = (angles.cos().mean(-3) - sigreg.phi).square() + angles.sin().mean(-3).square()
    return ((err @ sigreg.weights) * x.shape[-2]).mean()


@pytest.mark.parametrize("shape", [(32, 4), (3, 32, 4), (2, 3, 16, 4)])
def test_sigreg_value_and_gradient_equal_plain_autograd(shape):
    sigreg = SIGReg(num_proj=16)
    x = (0.7 * randn(*shape) + 0.2).requires_grad_(True)
    ours = sigreg(x, generator=directions())
    (grad,) = torch.autograd.grad(ours, x, retain_graph=True)
    (again,) = torch.autograd.grad(ours, x)  # the saved cos / sin survive a first backward
    reference = plain_sigreg(x, sigreg, directions())
    (expected,) = torch.autograd.grad(reference, x)
    assert_close(ours, reference, atol=1e-6)
    assert_close(grad, expected, atol=1e-7)
    assert_close(again, expected, atol=1e-7)
    assert expected.abs().max() > 1e-3


def test_sigreg_checks_its_arguments():
    with pytest.raises(ValueError, match="knots"):
        SIGReg(knots=1)


# -- VCReg -----------------------------------------------------------------------------------
def standardized(*shape: int) -> torch.Tensor:
    """Samples with exactly zero mean and unit (unbiased) variance over dim 0."""
    x = randn(*shape)
    return (x - x.mean(0)) / x.std(0)


def test_vcreg_std_loss_is_zero_for_unit_variance():
    out = VCReg()(standardized(128, 4, 8))
    assert set(out) == {"std_loss", "std_t_loss", "cov_loss", "cov_t_loss"}
    assert out["std_loss"] == 0.0


def test_vcreg_std_loss_is_one_for_constant_embeddings():
    out = VCReg()(torch.ones(128, 4, 8))
    assert out["std_loss"] == pytest.approx(1.0, abs=0.02)
    assert out["std_t_loss"] == pytest.approx(1.0, abs=0.02)
    assert out["cov_loss"] == 0.0


def test_vcreg_cov_loss_sees_correlated_dims():
    x = randn(256, 2, 8)
    copies = x[..., :1].expand(256, 2, 8)  # eight copies of one dim
    assert VCReg()(x)["cov_loss"] < 0.05
    assert VCReg()(copies)["cov_loss"] > 0.5


# -- PLDMLoss --------------------------------------------------------------------------------
def test_pldm_loss_terms():
    z = randn(8, 4, 6)
    base = {"temp_align_loss", "std_loss", "std_t_loss", "cov_loss", "cov_t_loss"}
    assert set(PLDMLoss()(z)) == base
    out = PLDMLoss()(z, randn(8, 3, 2, seed=1), randn(8, 3, 2, seed=2))
    assert set(out) == base | {"idm_loss"}
    assert all(v.ndim == 0 and torch.isfinite(v) for v in out.values())


def test_pldm_loss_values():
    z = randn(8, 4, 6)
    a = randn(8, 3, 2, seed=1)
    out = PLDMLoss()(z, a, a)
    assert out["idm_loss"] == 0.0
    assert_close(out["temp_align_loss"], (z[:, 1:] - z[:, :-1]).square().mean())
    assert PLDMLoss()(torch.ones(8, 4, 6))["temp_align_loss"] == 0.0


# -- TemporalStraighteningLoss ---------------------------------------------------------------
def test_straightening_is_minus_one_on_a_straight_line():
    t = torch.arange(5.0).view(1, 5, 1)
    line = randn(3, 1, 8) + t * randn(3, 1, 8, seed=1)  # (3, 5, 8): a straight path per sample
    assert_close(TemporalStraighteningLoss()(line), torch.tensor(-1.0))


def test_straightening_is_plus_one_when_going_back_and_forth():
    v = randn(2, 1, 8)
    path = torch.cat([torch.zeros(2, 1, 8), v, torch.zeros(2, 1, 8), v], dim=1)
    assert_close(TemporalStraighteningLoss()(path), torch.tensor(1.0))

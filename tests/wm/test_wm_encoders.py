"""Image encoders: ConvEncoder shapes and its image-size check; vit_hf's argument checks
(which run before transformers is imported)."""

from __future__ import annotations

import pytest
import torch

from stable_worldmodel import keys
from stable_worldmodel.errors import ConfigError, SpaceError
from stable_worldmodel.wm.encoders import ConvEncoder, vit_hf


@pytest.mark.parametrize("size", [8, 16, 24])
def test_conv_encoder_gives_one_token(size):
    torch.manual_seed(0)
    enc = ConvEncoder(image_size=size, width=8, hidden_size=8)
    out = enc(torch.randn(3, 3, size, size))
    assert out.last_hidden_state.shape == (3, 1, 8)
    assert out["last_hidden_state"] is out.last_hidden_state
    assert enc.config.hidden_size == 8 and enc.config.image_size == size


def test_conv_encoder_runs_channels_last_on_cpu_with_the_same_output_and_gradients():
    torch.manual_seed(0)
    enc = ConvEncoder(image_size=16, width=8, hidden_size=8)
    seen = []
    enc.convs[0].register_forward_pre_hook(
        lambda _, args: seen.append(args[0].is_contiguous(memory_format=torch.channels_last))
    )
    x = torch.randn(4, 3, 16, 16)
    out = enc(x).last_hidden_state
    assert seen == [True]
    ref = enc.head(enc.convs(x).flatten(1)).unsqueeze(1)  # the same layers on the usual NCHW layout
    assert seen == [True, False]
    assert torch.allclose(out, ref, atol=1e-6, rtol=1e-5)
    grads = torch.autograd.grad(out.square().sum(), list(enc.parameters()))
    ref_grads = torch.autograd.grad(ref.square().sum(), list(enc.parameters()))
    assert all(torch.allclose(g, r, atol=1e-6, rtol=1e-4) for g, r in zip(grads, ref_grads, strict=True))
    assert all(p.is_contiguous() for p in enc.parameters())  # checkpoints keep the usual layout


def test_conv_encoder_names_the_expected_image_size():
    enc = ConvEncoder(image_size=16, width=8, hidden_size=8)
    with pytest.raises(SpaceError, match="16x16") as info:
        enc(torch.randn(2, 3, 8, 8))
    assert "(2, 3, 8, 8)" in str(info.value)
    with pytest.raises(SpaceError, match=r"\(N, 3, 16, 16\)"):
        enc(torch.randn(2, 1, 16, 16))  # wrong channels


def test_model_with_wrong_image_size_raises_space_error(make_model):
    with pytest.raises(SpaceError, match="16x16"):
        make_model("lewm").encode({keys.PIXELS: torch.randn(2, 1, 3, 32, 32)})


@pytest.mark.parametrize("kwargs", [{"image_size": 4}, {"width": 0}, {"hidden_size": 2.5}, {"in_channels": True}])
def test_conv_encoder_checks_its_arguments(kwargs):
    with pytest.raises(ConfigError):
        ConvEncoder(**kwargs)


def test_vit_hf_never_downloads():
    with pytest.raises(ConfigError, match="pretrained=False"):
        vit_hf(pretrained=True)


def test_vit_hf_unknown_size_suggests_the_close_one():
    with pytest.raises(ConfigError, match="Did you mean 'tiny'"):
        vit_hf(size="tinny")

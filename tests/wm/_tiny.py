"""Sizes of the tiny test world models and the moving-dot clips they train on."""

from __future__ import annotations

import torch
from _nets import TINY_JEPA

from stable_worldmodel import keys

IMAGE = 16
#: a width-8 CNN world model at 16x16 (``make(name, "tiny", action_dim=2, **TINY)``)
TINY = dict(TINY_JEPA, image_size=IMAGE, history_size=2)
#: the ViT variant of ``TINY`` (one layer of width 8, patch 8: 4 patches + CLS)
VIT = dict(
    encoder="vit",
    patch_size=8,
    vit_overrides={"hidden_size": 8, "num_hidden_layers": 1, "num_attention_heads": 2, "intermediate_size": 16},
)
ACTION_DIM = 2


def moving_dot(n: int = 32, steps: int = 3, size: int = IMAGE, seed: int = 0) -> dict[str, torch.Tensor]:
    """``n`` clips of ``steps`` frames of a 2x2 dot on a ``size`` x ``size`` image; the action
    ``(dx, dy)`` in {-1, 0, 1} moves the dot by ``2 * action`` pixels. Pixels in {-1, 1},
    shape ``(n, steps, 3, size, size)``; action ``(n, steps, 2)`` (the last one is NaN, as in
    recorded episodes)."""
    gen = torch.Generator().manual_seed(seed)
    pos = torch.randint(4, size - 6, (n, 2), generator=gen)
    action = torch.randint(-1, 2, (n, steps, 2), generator=gen).float()
    pixels = -torch.ones(n, steps, 3, size, size)
    for t in range(steps):
        for i in range(n):
            x, y = pos[i].tolist()
            pixels[i, t, :, y : y + 2, x : x + 2] = 1.0
        pos = (pos + 2 * action[:, t].long()).clamp(0, size - 2)
    action[:, -1] = float("nan")
    return {keys.PIXELS: pixels, keys.ACTION: action}


def randn(*shape: int, seed: int = 0) -> torch.Tensor:
    """Seeded standard normal samples (a private generator: the global RNG is left alone)."""
    return torch.randn(*shape, generator=torch.Generator().manual_seed(seed))


def images(*lead: int, seed: int = 0) -> torch.Tensor:
    """Float images ``(*lead, 3, IMAGE, IMAGE)``."""
    return randn(*lead, 3, IMAGE, IMAGE, seed=seed)


def condition_on_actions(model: torch.nn.Module, seed: int = 0) -> torch.nn.Module:
    """Draw the AdaLN-zero modulations of the predictor: a fresh one ignores its actions (its
    blocks start as the identity), so costs would not depend on the candidates, and a state
    dict that failed to load could go unnoticed."""
    gen = torch.Generator().manual_seed(seed)
    with torch.no_grad():
        for name, param in model.named_parameters():
            if "adaLN_modulation" in name:
                param.copy_(0.3 * torch.randn(param.shape, generator=gen))
    return model


def make_tiny(name: str, seed: int = 0, **overrides):
    """A seeded tiny model: ``make(name, "tiny", action_dim=2, **TINY, **overrides)``."""
    import stable_worldmodel.wm as wm

    torch.manual_seed(seed)
    if name == "dummy":
        return wm.make("dummy", "tiny", action_dim=ACTION_DIM, image_size=IMAGE, frameskip=1, **overrides)
    return wm.make(name, "tiny", action_dim=ACTION_DIM, **{**TINY, **overrides})


def fit_losses(
    model: torch.nn.Module, batch: dict, steps: int = 30, lr: float = 3e-3, optimizer=torch.optim.Adam
) -> list[float]:
    """Take ``steps`` optimizer steps on ``model.loss(batch)["loss"]`` (trainable parameters only);
    the losses before each step."""
    opt = optimizer([p for p in model.parameters() if p.requires_grad], lr=lr)
    losses = []
    for _ in range(steps):
        loss = model.loss(batch)["loss"]
        opt.zero_grad()
        loss.backward()
        opt.step()
        losses.append(float(loss.detach()))
    return losses


def assert_close(actual: torch.Tensor, expected: torch.Tensor, rtol: float = 1e-5, atol: float = 1e-6) -> None:
    """``torch.allclose`` with shapes checked (``torch.testing.assert_close`` costs ~1.5 s on first call)."""
    expected = torch.as_tensor(expected, dtype=actual.dtype)
    assert actual.shape == expected.shape, f"shape {tuple(actual.shape)} != {tuple(expected.shape)}"
    assert torch.allclose(actual, expected, rtol=rtol, atol=atol), (
        f"max abs diff {(actual - expected).abs().max().item():.3g}"
    )

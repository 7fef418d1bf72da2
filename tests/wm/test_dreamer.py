"""Dreamer on tiny models: shapes of every verb, the per-plan encoding cache, KL balancing and free
bits, checkpoints, training (a tiny batch, then the trainer on a recorded toy dataset) and typed
errors for bad inputs."""

from __future__ import annotations

import numpy as np
import pytest
import torch
from _tiny import ACTION_DIM, IMAGE, fit_losses, images, randn
from torch import nn

import stable_worldmodel.wm as wm
from stable_worldmodel import keys
from stable_worldmodel.errors import ConfigError, SpaceError, UnknownNameError

A = ACTION_DIM
#: a width-8 ConvEncoder at 16x16, deter 16, stoch 4, 3 frames per sample
NET = dict(
    image_size=IMAGE, cnn_width=8, embed_dim=8, deter_dim=16, stoch_dim=4, hidden=16, history_size=2, frameskip=1
)
F = 20


def make(seed: int = 0, **overrides) -> nn.Module:
    torch.manual_seed(seed)
    return wm.make("dreamer", "tiny", action_dim=A, **{**NET, **overrides}).eval()


@pytest.fixture
def model():
    return make()


def plan_info(b: int, s: int, t: int = 2, goal: bool = True) -> dict:
    ctx, g = images(b, t), images(b, 1, seed=5)
    info = {keys.PIXELS: ctx.unsqueeze(1).expand(b, s, *ctx.shape[1:])}
    if goal:
        info[keys.GOAL] = g.unsqueeze(1).expand(b, s, *g.shape[1:])
    return info


def batch(b: int = 4, t: int = 3, seed: int = 0) -> dict:
    return {
        keys.PIXELS: images(b, t, seed=seed),
        keys.ACTION: randn(b, t, A, seed=seed + 1).clamp(-1, 1),
        keys.REWARD: randn(b, t, seed=seed + 2),
    }


def test_shapes_of_every_verb(model):
    with torch.no_grad():
        assert model.encode({keys.PIXELS: images(2, 3)})["emb"].shape == (2, 3, F)
        assert model.encode({keys.PIXELS: images(2, 3), keys.ACTION: randn(2, 3, A)})["emb"].shape == (2, 3, F)
        info = model.rollout(plan_info(2, 3, goal=False), randn(2, 3, 4, A))
        assert info["predicted_emb"].shape == (2, 3, 5, F)
        assert model.get_cost(plan_info(2, 3), randn(2, 3, 4, A)).shape == (2, 3)
        assert model.get_cost({keys.PIXELS: images(2, 2), keys.GOAL: images(2, 1)}, randn(2, 4, A)).shape == (2,)
        assert model.decode(randn(2, 5, F)).shape == (2, 5, 3, IMAGE, IMAGE)
        assert model.encode_goal(images(2, 1)).shape == (2, 1, 8)  # the frame embedding (embed_dim)
        assert model.predict_embedding(randn(2, 5, F)).shape == (2, 5, 8)


def test_rollout_keeps_the_context_and_depends_on_actions(model):
    info = plan_info(1, 2, goal=False)
    with torch.no_grad():
        ctx = model.encode({keys.PIXELS: info[keys.PIXELS][:, 0]})["emb"]
        pred = model.rollout(info, randn(1, 2, 4, A))["predicted_emb"]
    torch.testing.assert_close(pred[:, 0, :2], ctx[:, :2])
    torch.testing.assert_close(pred[:, 1, :2], ctx[:, :2])
    assert not torch.allclose(pred[0, 0, 2:], pred[0, 1, 2:])


def test_get_cost_encodes_context_and_goal_once_per_plan(model):
    calls = []
    model.encoder.register_forward_hook(lambda *a: calls.append(1))
    info = plan_info(2, 3)
    with torch.no_grad():
        first = model.get_cost(info, randn(2, 3, 4, A))
        assert len(calls) == 2  # the context, the goal
        second = model.get_cost(info, randn(2, 3, 4, A, seed=1))
        assert len(calls) == 2
        again = model.get_cost(info, randn(2, 3, 4, A))
    assert info["emb"].shape == (2, 3, 2, F) and info["goal_emb"].shape == (2, 3, 1, 8)
    assert torch.equal(first, again) and not torch.equal(first, second)


def test_cost_compares_the_predicted_frame_embedding_with_the_goal_frames(model):
    info, cand = plan_info(2, 3), randn(2, 3, 4, A)
    with torch.no_grad():
        cost = model.get_cost(info, cand)
        last = model.predict_embedding(info["predicted_emb"][:, :, -1])  # (B, S, E)
        goal = model.encode_pixels(info["goal"][:, 0, -1])  # (B, E)
    assert torch.allclose(cost, (last - goal[:, None]).square().sum(-1), atol=1e-5)


def test_get_cost_final_and_min(model):
    cand = randn(2, 3, 4, A)
    with torch.no_grad():
        final = model.get_cost(plan_info(2, 3), cand)
        model.goal_cost = "min"
        low = model.get_cost(plan_info(2, 3), cand)
    assert (low <= final + 1e-5).all() and (low >= 0).all()


def test_kl_terms_are_nonnegative_and_free_bits_clip_them(model):
    mean, std = randn(4, 3, 4), torch.rand(4, 3, 4) + 0.2
    same = model.kl_terms((mean, std), (mean.clone(), std.clone()))
    assert float(same["kl"]) == pytest.approx(0.0, abs=1e-5)
    assert float(same["dyn_loss"]) == pytest.approx(1.0) and float(same["rep_loss"]) == pytest.approx(1.0)
    far = model.kl_terms((mean, std), (mean + 5.0, std))
    assert float(far["kl"]) > 1.0 and float(far["dyn_loss"]) == pytest.approx(float(far["kl"]), rel=1e-5)
    unclipped = make(free_bits=0.0)
    terms = unclipped.kl_terms((mean, std), (randn(4, 3, 4, seed=3), std))
    assert float(terms["dyn_loss"]) >= 0 and float(terms["rep_loss"]) >= 0
    out = model.train().loss(batch())
    assert set(out) == {"loss", "recon_loss", "kl", "dyn_loss", "rep_loss", "embed_loss"}
    assert float(out["kl"]) >= 0 and float(out["dyn_loss"]) >= 1.0 and float(out["rep_loss"]) >= 1.0


def test_loss_decreases(dot_data):
    model = make(free_bits=0.0).train()
    data = dot_data(n=8, steps=3)
    losses = fit_losses(model, data)
    assert np.isfinite(losses).all() and losses[-1] < 0.7 * losses[0]


def test_reconstruction_is_summed_over_each_frame(model):
    # a unit-variance Gaussian log-likelihood: a few wrong pixels cost as much in a big frame as in a small one
    data = batch()
    out = model.loss(data)  # eval mode: z is the mean, so the two filterings agree
    with torch.no_grad():
        feats = model.observe(data[keys.PIXELS], data[keys.ACTION])[0]
    err = (model.decode(feats) - data[keys.PIXELS]).square()
    assert float(out["recon_loss"]) == pytest.approx(float(err.sum((2, 3, 4)).mean()), rel=1e-4)


def test_fit_to_frames_keeps_the_mean_frame_which_decode_adds(model):
    frames = images(6, 1, seed=3)[:, 0]
    emb = randn(2, F, seed=4)
    with torch.no_grad():
        before = model.decode(emb)
        model.fit_to_frames(frames)
        after = model.decode(emb)
    assert torch.allclose(model.frame_mean, frames.mean(0))
    assert torch.allclose(after - before, frames.mean(0).expand_as(after), atol=1e-6)
    assert "frame_mean" in model.state_dict()
    with pytest.raises(SpaceError, match=r"\(6, 1, 3, 16, 16\)"):
        model.fit_to_frames(images(6, 1))


def test_training_fits_the_mean_frame(toy):
    from stable_worldmodel.train import train

    train(
        "dreamer",
        "toy",
        steps=1,
        batch_size=4,
        device="cpu",
        progress=False,
        name="dr-mean",
        val_every=0,
        warmup_steps=0,
        **NET,
    )
    import h5py

    loaded = wm.load_pretrained("dr-mean")
    protocol = wm.utils.read_protocol(wm.utils.resolve_checkpoint("dr-mean"))
    with h5py.File(protocol["dataset_path"]) as f:  # under 4096 frames: every training frame is used
        lengths, offsets = f["ep_len"][:], f["ep_offset"][:]
        rows = np.concatenate([np.arange(offsets[e], offsets[e] + lengths[e]) for e in protocol["train_episodes"]])
        pixels = torch.from_numpy(f["pixels"][np.sort(rows)]).permute(0, 3, 1, 2).float()
    expected = (pixels / 255 - 0.5).mean(0) / 0.5  # the tiny preset's mean 0.5 / std 0.5
    assert torch.allclose(loaded.frame_mean, expected, atol=1e-4)


def test_reward_head_is_trained_and_needs_rewards():
    cfg = wm.get_config("dreamer", "tiny", reward_head=True)
    assert cfg.needs_reward and not wm.get_config("dreamer", "tiny").needs_reward
    model = make(reward_head=True).train()
    out = model.loss(batch())
    assert "reward_loss" in out and torch.isfinite(out["loss"])
    data = batch()
    del data[keys.REWARD]
    with pytest.raises(UnknownNameError, match="'reward'"):
        model.loss(data)


def test_save_load_round_trip(model):
    cfg = wm.get_config("dreamer", "tiny", **NET)
    wm.save_pretrained(model, "dr", config=cfg.target_tree(A))
    loaded = wm.load_pretrained("dr").eval()
    assert type(loaded).__name__ == "Dreamer"
    cand = randn(2, 3, 3, A)
    with torch.no_grad():
        assert torch.equal(loaded.get_cost(plan_info(2, 3), cand), model.get_cost(plan_info(2, 3), cand))
    assert all(
        torch.equal(a, b) for a, b in zip(loaded.state_dict().values(), model.state_dict().values(), strict=True)
    )


def test_trains_on_the_toy_dataset(toy):
    from stable_worldmodel.train import train

    result = train(
        "dreamer",
        "toy",
        steps=2,
        batch_size=4,
        device="cpu",
        progress=False,
        name="dr",
        val_every=0,
        warmup_steps=0,
        reward_head=True,
        **NET,
    )
    assert np.isfinite(result.train_loss)
    loaded = wm.load_pretrained("dr").eval()
    with torch.no_grad():
        assert loaded.get_cost(plan_info(1, 2), randn(1, 2, 3, A)).shape == (1, 2)


def test_bad_inputs_raise_typed_errors(model):
    with pytest.raises(ConfigError, match="deter_dim.*0"):
        wm.get_config("dreamer", "tiny", deter_dim=0)
    with pytest.raises(ConfigError, match="kl_dyn.*-1"):
        wm.get_config("dreamer", "tiny", kl_dyn=-1.0)
    with pytest.raises(ConfigError, match="reward_head.*'yes'"):
        wm.get_config("dreamer", "tiny", reward_head="yes")
    with pytest.raises(ConfigError, match="min_std.*0"):
        wm.get_config("dreamer", "tiny", min_std=0.0)
    with pytest.raises(ConfigError, match="decoder with an int image_size.*Identity"):
        type(model)(model.encoder, nn.Identity(), model.rssm, A)
    with pytest.raises(UnknownNameError, match="'pixels'"):
        model.encode({})
    with pytest.raises(UnknownNameError, match="'goal'"):
        model.get_cost(plan_info(1, 2, goal=False), randn(1, 2, 3, A))
    with pytest.raises(SpaceError, match=r"\(1, 2, 3, 5\)"):
        model.rollout(plan_info(1, 2), randn(1, 2, 3, 5))
    with pytest.raises(ConfigError, match="at least 2 actions.*got 1"):
        model.rollout(plan_info(1, 2), randn(1, 2, 1, A))
    with pytest.raises(SpaceError, match=r"\(2, 3, 7\)"):
        model.encode({keys.PIXELS: images(2, 3), keys.ACTION: randn(2, 3, 7)})
    with pytest.raises(UnknownNameError, match="'closest'"):
        model.goal_cost = "closest"
        model.get_cost(plan_info(1, 2), randn(1, 2, 3, A))


def test_config_needs_no_torch():
    import subprocess
    import sys

    code = (
        "import sys; from stable_worldmodel.wm import get_config; c = get_config('dreamer', 'tiny'); "
        "c.target_tree(2); assert 'torch' not in sys.modules, 'torch imported'"
    )
    subprocess.run([sys.executable, "-c", code], check=True)

"""The world-model contract on tiny CNN models: shapes of encode / predict / rollout /
get_cost / loss, get_cost's per-plan encoding cache, batching, and that training lowers the loss."""

from __future__ import annotations

import numpy as np
import pytest
import torch
from _tiny import ACTION_DIM, IMAGE, assert_close, condition_on_actions, fit_losses, images, randn

from stable_worldmodel import keys
from stable_worldmodel.errors import ConfigError

D = 8  # TINY["embed_dim"]
A = ACTION_DIM  # TINY["frameskip"] == 1: an action block is one action
JEPA_CASES = {"lewm": ("lewm", {}), "pldm": ("pldm", {}), "pldm_no_idm": ("pldm", {"idm_hidden": 0})}


@pytest.fixture(params=sorted(JEPA_CASES))
def jepa(request, make_model):
    """A tiny LeWM, PLDM (with inverse dynamics) or PLDM without it, in eval mode, whose
    predictor depends on the actions."""
    name, overrides = JEPA_CASES[request.param]
    return condition_on_actions(make_model(name, **overrides)).eval()


def count_encoder_calls(module: torch.nn.Module) -> list:
    calls: list = []
    module.register_forward_hook(lambda mod, args, out: calls.append(args[0].shape[0]))
    return calls


# -- JEPA models (LeWM, PLDM) ------------------------------------------------------------------
def test_make_builds_the_requested_class(make_model):
    assert type(make_model("lewm")).__name__ == "LeWM"
    assert type(make_model("pldm")).__name__ == "PLDM"
    assert hasattr(make_model("pldm"), "idm")
    assert not hasattr(make_model("pldm", idm_hidden=0), "idm")
    assert "idm.net.0.weight" not in make_model("pldm", idm_hidden=0).state_dict()


def test_encode_adds_emb_and_act_emb(jepa):
    info = {keys.PIXELS: images(3, 2), keys.ACTION: randn(3, 2, A)}
    out = jepa.encode(info)
    assert out is info
    assert out["emb"].shape == (3, 2, D)
    assert out["act_emb"].shape == (3, 2, D)


def test_encode_without_action_adds_only_emb(jepa):
    out = jepa.encode({keys.PIXELS: images(3, 2)})
    assert out["emb"].shape == (3, 2, D)
    assert "act_emb" not in out


def test_predict_keeps_the_shape(jepa):
    assert jepa.predict(randn(3, 2, D), randn(3, 2, D, seed=1)).shape == (3, 2, D)
    assert jepa.predict(randn(3, 1, D), randn(3, 1, D, seed=1)).shape == (3, 1, D)


@pytest.mark.parametrize("context", [1, 2])
def test_rollout_with_candidates_per_env(jepa, context):
    b, s, h = 2, 3, 4
    ctx = images(b, context)
    info = {keys.PIXELS: ctx.unsqueeze(1).expand(b, s, *ctx.shape[1:])}  # what a solver passes
    with torch.no_grad():
        out = jepa.rollout(info, randn(b, s, h, A))
        assert out is info
        assert out["predicted_emb"].shape == (b, s, h + 1, D)
        # the first `context` rows are the context embeddings, the same for every candidate
        expected = jepa.encode_pixels(ctx)
    assert_close(out["predicted_emb"][:, :, :context], expected.unsqueeze(1).expand(b, s, context, D))


def test_rollout_with_3d_candidates(jepa):
    with torch.no_grad():
        out = jepa.rollout({keys.PIXELS: images(2, 1)}, randn(2, 4, A))
    assert out["predicted_emb"].shape == (2, 5, D)


def test_rollout_first_prediction_is_predict(jepa):
    pixels, cand = images(2, 1), randn(2, 3, A)
    with torch.no_grad():
        rolled = jepa.rollout({keys.PIXELS: pixels}, cand)["predicted_emb"]
        enc = jepa.encode({keys.PIXELS: pixels, keys.ACTION: cand[:, :1]})
        step = jepa.predict(enc["emb"], enc["act_emb"])
    assert_close(rolled[:, 1], step[:, -1])


def _reference_rollout(model, context: torch.Tensor, act_emb: torch.Tensor, window: int) -> torch.Tensor:
    """The open loop written plainly: every window through ``predict``, its last output kept."""
    frames = list(context.unbind(1))
    for k in range(len(frames), act_emb.shape[1] + 1):
        lo = max(0, k - window)
        frames.append(model.predict(torch.stack(frames[lo:k], 1), act_emb[:, lo:k])[:, -1])
    return torch.stack(frames, 1)


@pytest.mark.parametrize("depth", [1, 2])
@pytest.mark.parametrize("context", [1, 2, 3])
def test_rollouts_over_windows_of_frames_equal_the_plain_loop(make_model, depth, context):
    """With a history of several frames the rollout computes each action's modulation once and
    only the last token through the last block: values and gradients equal the plain loop's."""
    for name in ("lewm", "pldm"):
        model = condition_on_actions(make_model(name, depth=depth, history_size=3)).eval()
        emb, act = randn(4, context, D), randn(4, 5, D, seed=1)
        ours = model._open_loop(emb, act, 3, 6)
        ref = _reference_rollout(model, emb, act, 3)
        assert ours.shape == ref.shape == (4, 6, D)
        assert_close(ours, ref, atol=1e-6)
        params = [p for n, p in model.named_parameters() if n.startswith(("predictor.", "pred_proj."))]
        grads = torch.autograd.grad(ours.square().sum(), params)
        ref_grads = torch.autograd.grad(ref.square().sum(), params)
        for g, r in zip(grads, ref_grads, strict=True):
            assert_close(g, r, atol=1e-5)


def test_the_predictor_s_last_output_from_its_conditioning_equals_forward(make_model):
    predictor = condition_on_actions(make_model("lewm", depth=2, history_size=3)).predictor.eval()
    x, c = randn(5, 3, D), randn(5, 3, D, seed=1)
    mods = predictor.condition(c)
    for t in (1, 2, 3):
        assert_close(predictor.forward_last(x[:, :t], [m[:, :t] for m in mods]), predictor(x[:, :t], c[:, :t])[:, -1])
    with pytest.raises(ValueError, match="at most num_frames=3"):
        predictor.forward_last(randn(5, 4, D), [randn(5, 4, 6 * D)] * 2)


def test_rollout_needs_one_action_per_context_frame(jepa):
    with pytest.raises(ConfigError, match="at least 2 actions"):
        jepa.rollout({keys.PIXELS: images(2, 2)}, randn(2, 1, A))


def test_get_cost_shape(jepa):
    b, s = 2, 5
    info = {keys.PIXELS: images(b, s, 1), keys.GOAL: images(b, s, 1, seed=1)}
    with torch.no_grad():
        cost = jepa.get_cost(info, randn(b, s, 3, A))
    assert cost.shape == (b, s)
    assert torch.isfinite(cost).all() and (cost >= 0).all()
    assert info["predicted_emb"].shape == (b, s, 4, D)


def test_get_cost_encodes_context_and_goal_once_per_info(jepa):
    b, s = 2, 4
    ctx, goal = images(b, 1), images(b, 1, seed=1)
    info = {
        keys.PIXELS: ctx.unsqueeze(1).expand(b, s, 1, 3, IMAGE, IMAGE),
        keys.GOAL: goal.unsqueeze(1).expand(b, s, 1, 3, IMAGE, IMAGE),
    }
    calls = count_encoder_calls(jepa.encoder)
    with torch.no_grad():
        first = jepa.get_cost(info, randn(b, s, 3, A))
        assert calls == [b, b]  # the context and the goal, one copy per env (not per candidate)
        second = jepa.get_cost(info, randn(b, s, 3, A, seed=1))
        assert calls == [b, b]  # cached in the info dict
        again = jepa.get_cost(info, randn(b, s, 3, A))
    assert not torch.equal(first, second)
    assert_close(again, first)
    jepa.get_cost({keys.PIXELS: info[keys.PIXELS], keys.GOAL: info[keys.GOAL]}, randn(b, s, 3, A))
    assert len(calls) == 4  # a new dict is a new plan


def test_get_cost_of_batched_envs_equals_env_by_env(jepa):
    b, s, h = 3, 4, 3
    ctx, goal, cand = images(b, 1), images(b, 1, seed=1), randn(b, s, h, A, seed=2)

    def info(rows):
        return {
            keys.PIXELS: ctx[rows].unsqueeze(1).expand(-1, s, -1, -1, -1, -1),
            keys.GOAL: goal[rows].unsqueeze(1).expand(-1, s, -1, -1, -1, -1),
        }

    with torch.no_grad():
        batched = jepa.get_cost(info(slice(None)), cand)
        single = torch.cat([jepa.get_cost(info(slice(i, i + 1)), cand[i : i + 1]) for i in range(b)])
    assert_close(batched, single, rtol=1e-5, atol=1e-5)


def test_get_cost_accepts_an_info_without_the_candidate_axis(jepa):
    b, s = 2, 4
    ctx, goal, cand = images(b, 2), images(b, 1, seed=1), randn(b, s, 3, A, seed=2)
    per_env = {keys.PIXELS: ctx, keys.GOAL: goal}  # (B, T, C, h, w), as the dummy model accepts too
    per_candidate = {
        keys.PIXELS: ctx.unsqueeze(1).expand(b, s, 2, 3, IMAGE, IMAGE),
        keys.GOAL: goal.unsqueeze(1).expand(b, s, 1, 3, IMAGE, IMAGE),
    }
    with torch.no_grad():
        assert_close(jepa.get_cost(per_env, cand), jepa.get_cost(per_candidate, cand))


def test_get_cost_gradient_wrt_candidates_on_a_cached_info(jepa):
    """What the gradient solver does: differentiate get_cost w.r.t. the actions, step after step."""
    b, s = 2, 3
    info = {keys.PIXELS: images(b, s, 1), keys.GOAL: images(b, s, 1, seed=1)}
    for step in range(2):
        cand = randn(b, s, 3, A, seed=step).requires_grad_(True)
        (grad,) = torch.autograd.grad(jepa.get_cost(info, cand).sum(), [cand])
        assert grad.shape == cand.shape and torch.isfinite(grad).all() and grad.abs().sum() > 0


def test_loss_returns_total_and_named_terms(jepa, dot_data):
    jepa.train()
    out = jepa.loss(dot_data(8, 3))
    assert out["emb"].shape == (8, 3, D)
    scalars = {k: v for k, v in out.items() if k != "emb"}
    assert all(v.ndim == 0 and torch.isfinite(v) for v in scalars.values())
    if type(jepa).__name__ == "LeWM":
        assert set(scalars) == {"loss", "pred_loss", "sigreg_loss"}
        assert_close(out["loss"], out["pred_loss"] + jepa.sigreg_weight * out["sigreg_loss"])
    else:
        vc = {"std_loss", "cov_loss", "std_t_loss", "cov_t_loss", "temp_align_loss", "temp_straight_loss"}
        idm = {"idm_loss"} if hasattr(jepa, "idm") else set()
        assert set(scalars) == {"loss", "pred_loss"} | vc | idm
        total = out["pred_loss"] + sum(w * out[k] for k, w in jepa.loss_weights.items() if w and k in out)
        assert_close(out["loss"], total)
    out["loss"].backward()
    assert all(p.grad is not None for p in jepa.encoder.parameters())


def test_loss_rejects_too_few_frames(jepa, dot_data):
    with pytest.raises(ConfigError, match="history"):
        jepa.loss(dot_data(4, 1))


def test_pldm_loss_weights_are_checked(make_model):
    with pytest.raises(ConfigError, match="loss_weights"):
        make_model("pldm", loss_weights={"std_los": 1.0})


# -- DummyWorldModel ---------------------------------------------------------------------------
@pytest.fixture
def dummy(make_model):
    return make_model("dummy")


def test_dummy_encode(dummy):
    out = dummy.encode({keys.PIXELS: images(3, 2)})
    assert out["emb"].shape == out["embedding"].shape == (3, 2, 10)
    as_numpy = dummy.encode({keys.PIXELS: images(3, 2).numpy()})
    assert_close(as_numpy["emb"], out["emb"])


def test_dummy_predict_one_step_or_a_list(dummy):
    obs = {"embedding": randn(4, 10)}
    assert dummy.predict(obs, randn(4, A)).shape == (4, 10)
    steps = [randn(4, A, seed=k) for k in range(3)]
    manual = obs["embedding"]
    for a in steps:
        manual = dummy.predict({"embedding": manual}, a)
    assert_close(dummy.predict(obs, steps), manual)


@pytest.mark.parametrize("with_s_axis", [True, False])
def test_dummy_rollout(dummy, with_s_axis):
    b, s, h = 2, 3, 4
    pixels = images(b, s, 1) if with_s_axis else images(b, 1)
    out = dummy.rollout({keys.PIXELS: pixels}, randn(b, s, h, A))
    assert out["predicted_emb"].shape == (b, s, h + 1, 10)


def test_dummy_rollout_with_3d_candidates(dummy):
    out = dummy.rollout({keys.PIXELS: images(2, 1)}, randn(2, 4, A))
    assert out["predicted_emb"].shape == (2, 5, 10)


def test_dummy_rollout_after_encode(dummy):
    info = dummy.encode({keys.PIXELS: images(2, 1)})
    assert dummy.rollout(info, randn(2, 3, 4, A))["predicted_emb"].shape == (2, 3, 5, 10)


def test_dummy_get_cost_encodes_once_and_batches(dummy):
    b, s = 3, 4
    ctx, goal, cand = images(b, 1), images(b, 1, seed=1), randn(b, s, 2, A, seed=2)
    info = {keys.PIXELS: ctx, keys.GOAL: goal}
    calls = count_encoder_calls(dummy.encoder)
    with torch.no_grad():
        cost = dummy.get_cost(info, cand)
        assert cost.shape == (b, s) and len(calls) == 2
        assert_close(dummy.get_cost(info, cand), cost)
        assert len(calls) == 2
        single = torch.cat(
            [
                dummy.get_cost({keys.PIXELS: ctx[i : i + 1], keys.GOAL: goal[i : i + 1]}, cand[i : i + 1])
                for i in range(b)
            ]
        )
    assert_close(cost, single)


def test_dummy_loss(dummy, dot_data):
    out = dummy.loss(dot_data(4, 3))
    assert out["emb"].shape == (4, 3, 10)
    assert out["loss"].ndim == 0 and torch.equal(out["loss"], out["pred_loss"])


# -- training lowers the loss ------------------------------------------------------------------
@pytest.mark.parametrize(
    "name,overrides", [("lewm", {"sigreg_num_proj": 64}), ("pldm", {}), ("dummy", {})], ids=["lewm", "pldm", "dummy"]
)
def test_training_lowers_the_loss(make_model, dot_data, name, overrides):
    model = make_model(name, **overrides).train()
    data = dot_data(8, 3)
    losses = fit_losses(model, data, lr=3e-3 if name != "dummy" else 1e-3, optimizer=torch.optim.AdamW)
    first, last = np.mean(losses[:3]), np.mean(losses[-5:])
    assert np.isfinite(losses).all()
    assert last < 0.7 * first, f"{name}: loss {first:.4f} -> {last:.4f}"


# -- goal costs ------------------------------------------------------------------------------
def check_min_cost_is_the_closest_step(model):
    info = {keys.PIXELS: images(2, 1), keys.GOAL: images(2, 1, seed=9)}
    cand = randn(2, 3, 4, A)
    with torch.inference_mode():
        final = model.get_cost(info, cand)
        pred, goal = info["predicted_emb"], info["goal_emb"]
        model.goal_cost = "min"
        best = model.get_cost(info, cand)
    goal = {4: lambda g: g[:, 0, -1], 3: lambda g: g[:, -1], 2: lambda g: g}[goal.ndim](goal)  # (B, D)
    per_step = (pred[:, :, 1:] - goal[:, None, None]).square().sum(-1)  # (B, S, H): after 1..H action blocks
    assert_close(final, per_step[..., -1])
    assert_close(best, per_step.amin(-1))
    assert bool((best <= final + 1e-6).all()) and bool((best < final - 1e-6).any())


def test_goal_cost_min_is_the_closest_predicted_step(jepa):
    check_min_cost_is_the_closest_step(jepa)


def test_dummy_goal_cost_min_is_the_closest_predicted_step(dummy):
    check_min_cost_is_the_closest_step(dummy)


def test_unknown_goal_cost_is_named(jepa):
    jepa.goal_cost = "mean"
    with pytest.raises(KeyError, match="Unknown goal cost 'mean'.*final, min"):
        jepa.get_cost({keys.PIXELS: images(2, 1), keys.GOAL: images(2, 1)}, randn(2, 3, 4, A))


def test_single_token_attention_shortcut_equals_full_attention():
    from stable_worldmodel.wm.lewm.module import Attention

    torch.manual_seed(0)
    attn = Attention(8, heads=2, dim_head=4).eval()
    x = torch.randn(5, 1, 8)
    q, k, v = attn.to_qkv(attn.norm(x)).chunk(3, dim=-1)
    heads = lambda t: t.view(5, 1, 2, 4).transpose(1, 2)  # noqa: E731
    full = torch.nn.functional.scaled_dot_product_attention(heads(q), heads(k), heads(v), is_causal=True)
    expected = attn.to_out(full.transpose(1, 2).reshape(5, 1, 8))
    assert_close(attn(x), expected)
    assert attn(torch.randn(5, 3, 8)).shape == (5, 3, 8)  # longer sequences take the full path


def test_dummy_unknown_goal_cost_is_named(dummy):
    dummy.goal_cost = "mean"
    with pytest.raises(KeyError, match="Unknown goal cost 'mean'.*final, min"):
        dummy.get_cost({keys.PIXELS: images(2, 1), keys.GOAL: images(2, 1)}, randn(2, 3, 4, A))

"""TD-MPC2 on tiny models: shapes of every verb, SimNorm, the two-hot maths, the per-plan encoding
cache, checkpoints, training (a tiny batch, then the trainer on a recorded toy dataset with rewards),
the reward a batch serves, the missing-reward error and typed errors for bad inputs."""

from __future__ import annotations

import numpy as np
import pytest
import torch
from _tiny import ACTION_DIM, IMAGE, assert_close, fit_losses, images, randn
from torch import nn

import stable_worldmodel.wm as wm
from stable_worldmodel import keys
from stable_worldmodel.errors import ConfigError, DatasetFormatError, SpaceError, UnknownNameError

A = ACTION_DIM
#: a width-8 ConvEncoder at 16x16, a latent of 16 (2 simplices of 8), MLPs of 8, 3 Q heads, 2 transitions
NET = dict(
    image_size=IMAGE, cnn_width=8, embed_dim=16, mlp_dim=8, enc_dim=8, num_q=3, num_bins=21, frameskip=1, num_preds=2
)
L = 16


def make(seed: int = 0, **overrides) -> nn.Module:
    torch.manual_seed(seed)
    return wm.make("tdmpc2", "tiny", action_dim=A, **{**NET, **overrides}).eval()


@pytest.fixture
def model():
    return make()


def plan_info(b: int, s: int, t: int = 1) -> dict:
    """What a solver passes: each env's context expanded over its S candidates."""
    ctx = images(b, t)
    return {keys.PIXELS: ctx.unsqueeze(1).expand(b, s, *ctx.shape[1:])}


def batch(b: int = 4, t: int = 3, seed: int = 0) -> dict:
    return {
        keys.PIXELS: images(b, t, seed=seed),
        keys.ACTION: randn(b, t, A, seed=seed + 1).clamp(-1, 1),
        keys.REWARD: randn(b, t, seed=seed + 2),
    }


# -- maths ------------------------------------------------------------------------------------------
def test_simnorm_groups_sum_to_one():
    from stable_worldmodel.wm.tdmpc2 import SimNorm

    out = SimNorm(8)(randn(3, 5, 24))
    assert out.shape == (3, 5, 24) and (out >= 0).all()
    assert_close(out.unflatten(-1, (3, 8)).sum(-1), torch.ones(3, 5, 3))


def test_two_hot_round_trip():
    from stable_worldmodel.wm.tdmpc2 import symexp, symlog, two_hot, two_hot_inv

    x = torch.tensor([[-50.0, -1.5, 0.0], [0.3, 2.0, 700.0]])
    probs = two_hot(x, num_bins=101, vmin=-10.0, vmax=10.0)
    assert probs.shape == (2, 3, 101)
    assert_close(probs.sum(-1), torch.ones(2, 3))
    assert ((probs > 0).sum(-1) <= 2).all()
    assert_close(two_hot_inv(probs.clamp_min(1e-30).log(), -10.0, 10.0), x, rtol=1e-4, atol=1e-4)
    assert_close(symexp(symlog(x)), x, rtol=1e-5, atol=1e-5)
    # outside symexp([vmin, vmax]) the value saturates at the last bin
    assert_close(
        two_hot_inv(two_hot(torch.tensor([1e6]), 11, -2.0, 2.0).clamp_min(1e-30).log(), -2.0, 2.0),
        symexp(torch.tensor([2.0])),
    )


# -- verbs ------------------------------------------------------------------------------------------
def test_shapes_of_every_verb(model):
    with torch.no_grad():
        assert model.encode({keys.PIXELS: images(2, 3)})["emb"].shape == (2, 3, L)
        z, logits = model.predict(randn(2, L), randn(2, A))
        assert z.shape == (2, L) and logits.shape == (2, 21)
        assert_close(z.unflatten(-1, (2, 8)).sum(-1), torch.ones(2, 2))  # the dynamics end with SimNorm
        info = model.rollout(plan_info(2, 3), randn(2, 3, 4, A))
        assert info["predicted_emb"].shape == (2, 3, 5, L) and info["predicted_reward"].shape == (2, 3, 4)
        assert model.get_cost(plan_info(2, 3, t=2), randn(2, 3, 4, A)).shape == (2, 3)
        assert model.get_cost({keys.PIXELS: images(2, 1)}, randn(2, 4, A)).shape == (2,)  # no S axis
        assert model.get_action({keys.PIXELS: images(2, 2)}).shape == (2, A)
        assert model.get_action({keys.PIXELS: images(2)}, horizon=3).shape == (2, 3, A)  # a warm start
        assert model.get_action({keys.PIXELS: images(2, 1)}, horizon=3, prefix_actions=randn(2, 1, A)).shape == (
            2,
            3,
            A,
        )
        assert model.rollout(model.encode_obs({keys.PIXELS: images(2)}), 4).shape == (
            2,
            4,
            A,
        )  # upstream's policy rollout
        assert model.q_values(randn(2, L), randn(2, A)).shape == (3, 2)
        action = model.get_action({keys.PIXELS: images(5, 1)})
    assert (action.abs() <= 1).all()


def test_cost_is_minus_the_predicted_return(model):
    """With the reward head forced to predict 1 per step and Q heads 0, the cost is -sum(discount^t)."""
    with torch.no_grad():
        for head in (model.reward, *model.qs):
            head[-1].weight.zero_()
            head[-1].bias.zero_()
        from stable_worldmodel.wm.tdmpc2 import two_hot

        model.reward[-1].bias.copy_(two_hot(torch.tensor(1.0), 21, -10.0, 10.0).clamp_min(1e-30).log())
        cost = model.get_cost(plan_info(1, 2), randn(1, 2, 3, A))
    g = model.cfg["wm"]["discount"]
    assert g == 0.9  # the tiny preset's
    expected = -(1 + g + g**2)
    assert_close(cost, torch.full((1, 2), expected), atol=1e-2, rtol=0)


def test_get_cost_encodes_once_per_plan(model):
    info = plan_info(2, 3)
    cand = randn(2, 3, 4, A)
    with torch.no_grad():
        first = model.get_cost(info, cand)
        assert info["emb"].shape == (2, 3, L)
        info[keys.PIXELS] = torch.zeros_like(info[keys.PIXELS])  # no longer read: the cached latent is used
        assert torch.equal(model.get_cost(info, cand), first)


def test_get_cost_same_for_per_env_and_per_candidate_infos(model):
    b, s = 2, 3
    per_cand = plan_info(b, s)
    per_env = {k: v[:, 0] for k, v in per_cand.items()}
    cand = randn(b, s, 3, A, seed=4)
    with torch.no_grad():
        assert_close(model.get_cost(per_env, cand), model.get_cost(per_cand, cand), atol=1e-6)


def test_mppi_plans_on_its_cost_from_a_prior_warm_start(model):
    import gymnasium as gym

    from stable_worldmodel.policy import PlanConfig
    from stable_worldmodel.solver import MPPISolver

    solver = MPPISolver(model, num_samples=8, n_steps=2, topk=4)
    solver.configure(
        action_space=gym.spaces.Box(-1.0, 1.0, (2, A), np.float32), n_envs=2, config=PlanConfig(3, 1, action_block=1)
    )
    info = {keys.PIXELS: images(2, 1)}
    with torch.no_grad():
        warm = model.get_action(info, horizon=3)
    out = solver.solve(dict(info), init_action=warm)
    assert out["actions"].shape == (2, 3, A) and out["costs"].shape == (2,)
    assert torch.isfinite(out["costs"]).all()


# -- training ---------------------------------------------------------------------------------------
def test_loss_terms(model):
    model.train()
    out = model.loss(batch())
    assert {"loss", "model_loss", "consistency_loss", "reward_loss", "value_loss", "pi_loss", "emb"} == set(out)
    assert out["emb"].shape == (4, 3, L) and out["loss"].ndim == 0
    assert_close(out["model_loss"], out["loss"] - out["pi_loss"])  # what validation reports: no actor term
    assert model.validation_loss == "model_loss"
    out["loss"].backward()
    assert all(p.grad is not None for name, p in model.named_parameters() if not name.startswith("target_qs"))
    assert all(not p.requires_grad for p in model.target_qs.parameters())
    # the policy term gives the Q heads no gradient: only the value term does
    model.zero_grad()
    model._pi_loss(randn(4, 2, L).softmax(-1), randn(4, 2, A)).backward()
    assert all(p.grad is None for p in model.qs.parameters())
    assert any(p.grad is not None for p in model.pi.parameters())
    # in training mode each loss call moves the target heads by tau (0.01) towards the heads
    before = [p.clone() for p in model.target_qs.parameters()]
    with torch.no_grad():
        for p in model.qs.parameters():
            p.add_(1.0)
        model.loss(batch())
    for old, new in zip(before, model.target_qs.parameters(), strict=False):
        assert_close(new, old + 0.01, atol=1e-6, rtol=0)
    moved = [p.clone() for p in model.target_qs.parameters()]
    with torch.no_grad():
        model.eval().loss(batch())  # evaluation leaves them alone
    assert all(torch.equal(a, b) for a, b in zip(moved, model.target_qs.parameters(), strict=False))


def test_bc_coef_makes_the_prior_imitate_the_data():
    """``bc_coef`` adds ``bc_coef * |tanh mean - clip(action)|^2`` (rho-weighted over steps) to the
    policy term; trained on it, the prior's mean action moves to the batch's actions."""
    zs, acts = randn(4, 2, L).softmax(-1), randn(4, 2, A) * 2  # some beyond [-1, 1]: clipped
    plain, bc = make(), make(bc_coef=3.0)
    torch.manual_seed(0)
    base = plain._pi_loss(zs, acts)
    torch.manual_seed(0)
    with_bc = bc._pi_loss(zs, acts)
    mean_action = torch.tanh(bc.pi(zs).chunk(2, dim=-1)[0])
    per_step = (mean_action - acts.clamp(-1, 1)).square().mean(-1).mean(0)  # (H,)
    expected = (per_step * torch.tensor([1.0, 0.5])).mean() * 3.0  # rho = 0.5
    assert_close(with_bc - base, expected, atol=1e-5, rtol=1e-4)

    target = acts.clamp(-1, 1)
    gaps = {}
    for coef in (0.0, 3.0):  # the prior alone, trained on its term at fixed latents
        model = make(bc_coef=coef).train()
        opt = torch.optim.Adam(model.pi.parameters(), lr=3e-3)
        torch.manual_seed(0)
        for _ in range(60):
            loss = model._pi_loss(zs, acts)
            opt.zero_grad()
            loss.backward()
            opt.step()
        with torch.no_grad():
            gaps[coef] = float((torch.tanh(model.pi(zs).chunk(2, dim=-1)[0]) - target).abs().mean())
    assert gaps[3.0] < 0.5 * gaps[0.0], gaps  # 0.20 vs 0.80 here
    with pytest.raises(ConfigError, match="bc_coef >= 0"):
        wm.get_config("tdmpc2", "tiny", bc_coef=-1.0)


def test_loss_terms_equal_their_step_by_step_definition():
    """The reward and Q heads score all steps in one call; the terms are still the per-step sums of the docstring."""
    import torch.nn.functional as F

    from stable_worldmodel.wm.tdmpc2.module import two_hot

    model = make(num_preds=3, q_dropout=0.0).train()  # (the Q heads' dropout draws its masks per call)
    with torch.no_grad():  # away from the zero-initialised heads, whose uniform logits hide mistakes
        for p in model.parameters():
            p.add_(0.3 * randn(*p.shape, seed=p.numel()))
    data = batch(5, 4)
    rho, discount = model.cfg["wm"]["rho"], model.cfg["wm"]["discount"]
    torch.manual_seed(3)  # the draws loss() makes next, in its order (loss() then moves the target heads)
    with torch.no_grad():
        emb = model.encode_obs(model._inputs(data, "reference"))
        target_z = emb[:, 1:]
        next_action = model.sample_pi(target_z)[1]
        pick = torch.randperm(NET["num_q"])[:2]
        td_target = (
            data[keys.REWARD][:, :3] + discount * model.q_values(target_z, next_action, target=True)[pick].min(0).values
        )

        def ce(logits, target):
            return -(two_hot(target, 21, model.vmin, model.vmax) * F.log_softmax(logits, -1)).sum(-1).mean()

        z, consistency, reward_loss, value_loss = emb[:, 0], 0.0, 0.0, 0.0
        for t in range(3):
            za = torch.cat([z, data[keys.ACTION][:, t]], -1)
            value_loss += rho**t * sum(ce(q(za), td_target[:, t]) for q in model.qs)
            reward_loss += rho**t * ce(model.reward(za), data[keys.REWARD][:, t])
            z = model.dynamics(za)
            consistency += rho**t * F.mse_loss(z, target_z[:, t])
    torch.manual_seed(3)
    out = model.loss(data)
    assert 0 < rho < 1
    assert_close(out["consistency_loss"], consistency / 3, atol=1e-6, rtol=1e-5)
    assert_close(out["reward_loss"], reward_loss / 3, atol=1e-6, rtol=1e-5)
    assert_close(out["value_loss"], value_loss / (3 * NET["num_q"]), atol=1e-6, rtol=1e-5)
    assert out["value_loss"].item() > 0.1 and out["reward_loss"].item() > 0.1


def test_loss_decreases():
    model = make().train()
    data = batch(8, 3)
    torch.manual_seed(0)
    losses = fit_losses(model, data, steps=20)
    assert losses[-1] < 0.7 * losses[0], losses


def test_save_load_round_trip(model):
    cfg = wm.get_config("tdmpc2", "tiny", **NET)
    wm.save_pretrained(model, "td", config=cfg.target_tree(A))
    loaded = wm.load_pretrained("td")
    assert type(loaded).__name__ == "TDMPC2"
    cand = randn(2, 3, 3, A)
    with torch.no_grad():
        assert torch.equal(loaded.get_cost(plan_info(2, 3), cand), model.get_cost(plan_info(2, 3), cand))
    assert all(
        torch.equal(a, b) for a, b in zip(loaded.state_dict().values(), model.state_dict().values(), strict=False)
    )


def test_upstream_cnn_and_proprio():
    """Upstream's CNN (``pixel_encoder="tdmpc2"``, 64x64 -> 32 x 4 x 4) and a proprio encoder."""
    cfg = wm.get_config(
        "tdmpc2",
        "tiny",
        pixel_encoder="tdmpc2",
        num_channels=4,
        embed_dim=8,
        mlp_dim=8,
        enc_dim=8,
        num_q=2,
        num_bins=11,
        frameskip=1,
        proprio_dim=3,
        proprio_emb_dim=8,
    )
    model = wm.instantiate(cfg.target_tree(A)).eval()
    assert model.pixel_encoder.in_features == 4 * 4 * 4 and model.latent_dim == 16
    info = {keys.PIXELS: randn(2, 1, 3, 64, 64), keys.PROPRIO: randn(2, 1, 3)}
    with torch.no_grad():
        assert model.encode(info)["emb"].shape == (2, 1, 16)
        assert model.get_action(info).shape == (2, A)
    with pytest.raises(UnknownNameError, match="'proprio'"):
        model.get_action({keys.PIXELS: randn(2, 1, 3, 64, 64)})


# -- through the trainer ----------------------------------------------------------------------------
def test_trains_on_the_toy_dataset(toy):
    import json

    from stable_worldmodel.train import train

    result = train(
        "tdmpc2",
        "toy",
        steps=2,
        batch_size=4,
        device="cpu",
        progress=False,
        name="td",
        val_every=0,
        warmup_steps=0,
        **{**NET, "num_preds": 1},
    )
    assert np.isfinite(result.train_loss)
    loaded = wm.load_pretrained("td")
    with torch.no_grad():
        assert loaded.get_action({keys.PIXELS: images(1, 1)}).shape == (1, A)
    protocol = json.loads((result.folder / "protocol.json").read_text())
    assert protocol["model"] == "tdmpc2"
    # planned with by `swm eval --policy wm:td`: its own cost under the default cost="auto"; a goal cost is refused
    from stable_worldmodel.errors import ConfigError
    from stable_worldmodel.planning.learned import PlanSettings, world_model_policy

    policy, plan_protocol = world_model_policy(
        "td", PlanSettings(solver="mppi", horizon=2, samples=8, iterations=1), device="cpu"
    )
    assert plan_protocol["plan"]["cost"] == "auto" and policy.solver.model is not None
    with pytest.raises(ConfigError, match="cost='min'.*TDMPC2.*own cost.*cost='auto'"):
        world_model_policy("td", PlanSettings(cost="min"), device="cpu")


def test_validation_reports_the_world_model_loss_and_it_falls(toy):
    """``val/loss`` of a TD-MPC2 run is its ``model_loss`` (consistency, reward, value), not ``loss``,
    whose actor term ``-Q`` grows with the values; on the toy data it falls."""
    import json

    from stable_worldmodel.train import train

    torch.manual_seed(0)
    result = train(
        "tdmpc2",
        "toy",
        steps=60,
        batch_size=8,
        device="cpu",
        progress=False,
        name="tdv",
        val_every=20,
        warmup_steps=0,
        seed=0,
        **NET,
    )
    records = [json.loads(line) for line in (result.folder / "metrics.jsonl").read_text().splitlines()]
    val = [r["val/loss"] for r in records if "val/loss" in r]
    assert len(val) == 3 and val[0] > val[1] > val[2] and val[-1] < 0.9 * val[0], val  # 0.546, 0.480, 0.471 here
    model = wm.load_pretrained("tdv").eval()
    from stable_worldmodel.train.data import TrainData

    data = TrainData("toy", wm.get_config("tdmpc2", "tiny", **NET), seed=0, device=torch.device("cpu"))
    with torch.no_grad():
        out = model.loss(data.batch(np.arange(4)))
    assert float(out["model_loss"]) != pytest.approx(float(out["loss"]))  # the two differ: the right one is logged


def _write(home, name: str, columns: dict) -> str:
    from stable_worldmodel.data.writer import HDF5Writer

    home.mkdir(parents=True, exist_ok=True)
    with HDF5Writer(home / f"{name}.h5") as writer:
        writer.write_episodes([columns])
    return name


def test_batch_reward_is_the_sum_over_each_action_block(_stablewm_home):
    from stable_worldmodel.train.data import TrainData

    n = 12
    rng = np.random.default_rng(0)
    name = _write(
        _stablewm_home,
        "rew",
        {
            "pixels": rng.integers(0, 256, (n, IMAGE, IMAGE, 3), dtype=np.uint8),
            "action": rng.normal(size=(n, A)).astype(np.float32),
            "reward": np.arange(n, dtype=np.float64),
        },
    )  # row i earned reward i
    cfg = wm.get_config("tdmpc2", "tiny", **{**NET, "frameskip": 2, "num_preds": 2, "val_fraction": 0.0})
    data = TrainData(name, cfg, seed=0, device=torch.device("cpu"))
    out = data.batch(np.array([0, 3]))  # windows starting at rows 0 and 3 (frames every 2 rows)
    # block k of a window starting at row s holds the actions of rows s + 2k, s + 2k + 1, whose rewards
    # are recorded on rows s + 2k + 1 and s + 2k + 2
    expected = torch.tensor([[1 + 2, 3 + 4, 0], [4 + 5, 6 + 7, 0]], dtype=torch.float32)
    assert torch.equal(out[keys.REWARD], expected)
    assert out[keys.ACTION].shape == (2, 3, 2 * A)


def test_missing_reward_column_says_how_to_record_one(_stablewm_home):
    from stable_worldmodel.train import train

    rng = np.random.default_rng(0)
    _write(
        _stablewm_home,
        "noreward",
        {
            "pixels": rng.integers(0, 256, (6, IMAGE, IMAGE, 3), dtype=np.uint8),
            "action": rng.normal(size=(6, A)).astype(np.float32),
        },
    )
    with pytest.raises(DatasetFormatError) as err:
        train("tdmpc2", "noreward", steps=1, batch_size=2, device="cpu", progress=False, name="x", **NET)
    message = str(err.value)
    for part in ("'reward'", "'noreward'", "['action', 'pixels']", "record_dataset", "swm collect", "0 everywhere"):
        assert part in message, (part, message)


def test_goal_proprio_makes_it_goal_conditioned(_stablewm_home):
    """With ``goal_proprio_dim`` the latent also encodes the episode's goal (``goal_proprio``
    column): the trainer serves it normalized like ``proprio`` (the planner does the same), and
    the latent depends on it."""
    import json

    from stable_worldmodel.train import train
    from stable_worldmodel.train.data import TrainData

    rng = np.random.default_rng(0)
    n = 16
    goal = np.repeat(np.array([[10.0, 20.0], [30.0, 40.0]], np.float32), n // 2, axis=0)
    proprio = rng.normal(size=(n, 2)).astype(np.float32)
    name = _write(
        _stablewm_home,
        "goals",
        {
            "pixels": rng.integers(0, 256, (n, IMAGE, IMAGE, 3), dtype=np.uint8),
            "action": rng.normal(size=(n, A)).astype(np.float32),
            "proprio": proprio,
            "goal_proprio": goal,
            "reward": -np.abs(proprio - goal).sum(1),
        },
    )
    net = {**NET, "proprio_dim": 2, "goal_proprio_dim": 2, "proprio_emb_dim": 8, "val_fraction": 0.0}
    cfg = wm.get_config("tdmpc2", "tiny", **net)
    assert cfg.extra_columns == {"proprio": 2, "goal_proprio": 2}
    data = TrainData(name, cfg, seed=0, device=torch.device("cpu"))
    out = data.batch(np.array([0, 9]))
    assert out["goal_proprio"].shape == (2, 3, 2)
    # in the units of proprio: normalized by proprio's normalizer, as planning does (prepare_info's fallback)
    assert data.extra_normalizers["goal_proprio"] is data.extra_normalizers["proprio"]
    expected = data.extra_normalizers["proprio"].transform(goal[[0, 9]])
    assert_close(out["goal_proprio"][:, 0], torch.as_tensor(expected, dtype=torch.float32))
    result = train("tdmpc2", name, steps=2, batch_size=4, device="cpu", progress=False, name="tdg", val_every=0, **net)
    protocol = json.loads((result.folder / "protocol.json").read_text())
    assert set(protocol["normalizers"]) == {"action", "proprio"}
    model = wm.load_pretrained("tdg").eval()
    assert list(model.extra_encoders) == ["proprio", "goal_proprio"] and model.latent_dim == 16 + 8 + 8
    info = {keys.PIXELS: images(1, 1), keys.PROPRIO: randn(1, 1, 2)}
    with pytest.raises(UnknownNameError, match="'goal_proprio'"):
        model.get_action(info)
    with torch.no_grad():
        z = [model.encode({**info, "goal_proprio": torch.full((1, 1, 2), v)})["emb"] for v in (-1.0, 1.0)]
    assert not torch.allclose(z[0], z[1])
    with pytest.raises(
        ConfigError, match="goal_proprio_dim equal to the width of column 'goal_proprio'.*goal_proprio_dim=3 and 2"
    ):
        TrainData(
            name, wm.get_config("tdmpc2", "tiny", **{**net, "goal_proprio_dim": 3}), seed=0, device=torch.device("cpu")
        )
    with pytest.raises(ConfigError, match="goal_proprio_dim to be an integer >= 0"):
        wm.get_config("tdmpc2", "tiny", goal_proprio_dim=-2)


# -- bad inputs -------------------------------------------------------------------------------------
def test_bad_inputs_raise_typed_errors(model):
    from stable_worldmodel.wm.tdmpc2 import TDMPC2, SimNorm

    with pytest.raises(ConfigError, match="multiple of simnorm_dim=8"):
        wm.get_config("tdmpc2", embed_dim=12)
    with pytest.raises(ConfigError, match="history_size 1"):
        wm.get_config("tdmpc2", history_size=2)
    with pytest.raises(ConfigError, match="'tdmpc3'"):
        wm.get_config("tdmpc2", pixel_encoder="tdmpc3")
    with pytest.raises(ConfigError, match="image_size >= 35"):
        wm.get_config("tdmpc2", pixel_encoder="tdmpc2", image_size=16)
    with pytest.raises(ConfigError, match="num_q >= 2"):
        wm.get_config("tdmpc2", num_q=1)
    with pytest.raises(ConfigError, match="'mlp_dimm'"):
        TDMPC2({"action_dim": 2, "wm": {"mlp_dimm": 8}})
    with pytest.raises(ConfigError, match="action_dim to be a positive int, got None"):
        TDMPC2({"wm": {}})
    with pytest.raises(ConfigError, match="simplex_dim"):
        SimNorm(0)
    with pytest.raises(SpaceError, match=r"action blocks of 2 numbers, got shape \(2, 3\)"):
        model.predict(randn(2, L), randn(2, 3))
    with pytest.raises(UnknownNameError, match="'pixels'"):
        model.get_cost({keys.GOAL: images(2, 1)}, randn(2, 3, 2, A))
    with pytest.raises(UnknownNameError, match="'reward'"):
        model.loss({k: v for k, v in batch().items() if k != keys.REWARD})
    with pytest.raises(ConfigError, match="at least 2 frames"):
        model.loss(batch(t=1))
    with pytest.raises(SpaceError, match=r"\(B, S, H, A\)"):
        model.rollout(plan_info(2, 3), randn(2, A))
    with pytest.raises(ConfigError, match="horizon"):
        model.get_action({keys.PIXELS: images(2, 1)}, horizon=0)
    with pytest.raises(SpaceError, match="16, 16"):
        model.encode({keys.PIXELS: randn(1, 1, 3, 8, 8)})


def test_seed_module_name():
    from stable_worldmodel.wm.tdmpc import TDMPC, TDMPC2

    assert TDMPC is TDMPC2 is wm.TDMPC2


def test_configs_need_no_torch():
    import json
    import subprocess
    import sys

    code = (
        "import sys; sys.modules['torch'] = None  # any import fails fast\n"
        "import json, stable_worldmodel.wm as wm\n"
        "print(json.dumps([wm.get_config('tdmpc2', p).target_tree(2) for p in ('tiny', 'small', 'paper')]))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True, timeout=120)
    trees = json.loads(out.stdout)
    assert [t["cfg"]["wm"]["encoder"] for t in trees] == ["conv", "tdmpc2", "tdmpc2"]
    assert trees[2]["cfg"]["wm"]["encoding"] == {"pixels": 512} and trees[2]["cfg"]["action_dim"] == 10

"""State-input JEPAs (``encoder="state"``): a LeWM / PLDM that observes a dataset column (``state``,
``proprio``) through an MLP instead of pixels, trains on it, and plans toward ``goal_<key>`` from the
World's infos (issue 30: the state-input LeWM of upstream's Push-T comparison)."""

from __future__ import annotations

import json

import pytest
import torch

from stable_worldmodel import keys, wm
from stable_worldmodel.errors import ConfigError

#: a width-8 state LeWM over a 2-number state
STATE = dict(encoder="state", state_dim=2, state_width=8, embed_dim=8, depth=1, heads=2, dim_head=4, mlp_dim=16,
             projector_hidden=16, history_size=1, frameskip=1)  # fmt: skip
#: LeWM's own knob
LEWM = dict(sigreg_num_proj=16)


def state_config(name: str, **overrides):
    return wm.get_config(name, "tiny", **{**STATE, **(LEWM if name == "lewm" else {}), **overrides})


def test_the_config_reads_the_column_not_the_pixels():
    cfg = state_config("lewm")
    assert cfg.extra_columns == {keys.STATE: 2} and not cfg.reads_pixels
    assert cfg.target_tree(2)["obs_key"] == keys.STATE
    proprio = state_config("pldm", state_key=keys.PROPRIO)
    assert proprio.extra_columns == {keys.PROPRIO: 2}
    assert wm.get_config("lewm", "tiny").reads_pixels and wm.get_config("lewm", "tiny").extra_columns == {}


@pytest.mark.parametrize(
    ("overrides", "needle"),
    [({"state_dim": 0}, "state_dim > 0"), ({"state_key": "pixels"}, "state_key"), ({"encoder": "stat"}, "'state'")],
)
def test_bad_state_configs_are_typed_errors(overrides, needle):
    with pytest.raises(ConfigError, match=needle):
        state_config("lewm", **overrides)


@pytest.mark.parametrize(
    ("dims", "needle"),
    [([0, 2], r"\(0..1\), got \[0, 2\]"), ([1, 1], "distinct"), ("01", "distinct"), ([True], "distinct")],
)
def test_bad_state_dims_are_typed_errors(dims, needle):
    with pytest.raises(ConfigError, match=needle):
        state_config("lewm", state_dims=dims)


@pytest.mark.parametrize("name", ["lewm", "pldm"])
def test_state_dims_leave_the_other_entries_out_of_the_embedding(name, tmp_path):
    """``state_dims=[1]``: the embedding, hence the planner's distance, ignores entry 0 (Push-T's poses without the
    agent's velocity); the checkpoint keeps the selection."""
    from stable_worldmodel.wm.utils import load_pretrained, save_pretrained

    torch.manual_seed(0)
    cfg = state_config(name, state_dims=[1])
    assert cfg.encoder_tree()["dims"] == [1] and "dims" not in state_config(name).encoder_tree()
    model = wm.make(name, action_dim=2, preset="tiny", **STATE, **(LEWM if name == "lewm" else {}), state_dims=[1])
    model.eval()
    state = torch.randn(3, 1, 2)
    moved = state + torch.tensor([5.0, 0.0])
    assert torch.equal(model.encode_obs(state), model.encode_obs(moved))
    assert not torch.allclose(model.encode_obs(state), model.encode_obs(state + torch.tensor([0.0, 5.0])))
    folder = save_pretrained(model, "dims", config=cfg.target_tree(2), cache_dir=tmp_path).parent
    again = load_pretrained(folder).eval()
    assert again.encoder.config.dims == [1]
    assert torch.equal(again.encode_obs(state), model.encode_obs(state))


@pytest.mark.parametrize("name", ["lewm", "pldm"])
def test_a_state_model_encodes_and_plans_toward_the_goal_state(name):
    torch.manual_seed(0)
    model = wm.make(name, action_dim=2, preset="tiny", **STATE, **(LEWM if name == "lewm" else {})).eval()
    b, s, h = 2, 5, 3
    state = torch.randn(b, 1, 2)
    assert model.encode({keys.STATE: state})["emb"].shape == (b, 1, 8)
    cand = torch.randn(b, s, h, 2)

    def cost(goal: torch.Tensor) -> torch.Tensor:
        info = {keys.STATE: state.unsqueeze(1).expand(b, s, 1, 2), "goal_state": goal.unsqueeze(1).expand(b, s, 1, 2)}
        return model.get_cost(info, cand)

    near, far = cost(state), cost(state + 5.0)
    assert near.shape == (b, s) and not torch.allclose(near, far)  # the goal is the goal state, not an image
    with pytest.raises(Exception, match="goal_state"):
        model.get_cost({keys.STATE: state.unsqueeze(1).expand(b, s, 1, 2)}, cand)


@pytest.fixture(scope="module")
def toy_home(tmp_path_factory):
    from stable_worldmodel import World
    from stable_worldmodel.envs import expert_policy

    root = tmp_path_factory.mktemp("state_toy")
    with World("swm/Toy-v0", 2, (16, 16), max_episode_steps=30, verbose=0, vectorization_mode="sync") as world:
        world.set_policy(expert_policy("swm/Toy-v0"))
        world.record_dataset("toy", episodes=30, seed=0, cache_dir=root)
    return root


def test_training_reads_no_pixels_and_the_loss_falls(toy_home, one_torch_thread):
    from stable_worldmodel.train import train
    from stable_worldmodel.train.data import TrainData

    cfg = state_config("lewm")
    batch = TrainData("toy", cfg, seed=0, device=torch.device("cpu"), cache_dir=str(toy_home)).train_batch(
        torch.Generator().manual_seed(0), 4
    )
    assert set(batch) == {keys.ACTION, keys.STATE} and batch[keys.STATE].shape == (4, 2, 2)
    result = train("lewm", "toy", "tiny", steps=150, name="state-lewm", seed=0, device="cpu", progress=False,
                   cache_dir=str(toy_home), warmup_steps=0, batch_size=32, **STATE, **LEWM)  # fmt: skip
    losses = [r["train/loss"] for r in result.history if "train/loss" in r]
    assert sum(losses[-3:]) / 3 < 0.7 * losses[0], losses
    protocol = json.loads((result.folder / "protocol.json").read_text())
    assert set(protocol["normalizers"]) == {keys.ACTION, keys.STATE}


def test_swm_eval_plans_a_state_run_from_the_worlds_state_and_goal_state(toy_home, swm, monkeypatch, tmp_path):
    """Through the CLI: no image size to match, no waypoint graph of frames (auto subgoals fall back to the goal),
    and the plans reach the toy's goals that the random policy does not."""
    from stable_worldmodel.train import train

    monkeypatch.setenv("STABLEWM_HOME", str(toy_home))
    train("lewm", "toy", "tiny", steps=300, name="state-plan", seed=0, device="cpu", progress=False,
          warmup_steps=0, batch_size=32, encoder="state", state_dim=2, embed_dim=16, history_size=1, frameskip=1,
          sigreg_num_proj=64)  # the tiny preset's sizes otherwise  # fmt: skip
    common = ("--episodes", "10", "--num-envs", "5", "--max-steps", "30", "--image-size", "16", "--device", "cpu")
    plan = ("--samples", "64", "--iterations", "5", "--horizon", "3")
    rates = {}
    for policy, extra in (("wm:state-plan", plan), ("random", ())):
        out = tmp_path / f"{policy.replace(':', '_')}.json"
        result = swm("eval", "swm/Toy-v0", "--policy", policy, *common, *extra, "--json", str(out))
        assert result.exit_code == 0, result.output
        rates[policy] = json.loads(out.read_text())["success_rate"]
    assert rates["wm:state-plan"] >= 80.0 and rates["random"] <= 20.0, rates

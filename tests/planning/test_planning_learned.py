"""Planning with a learned world model: ``world_model_policy`` on checkpoints trained here on swm/Toy-v0.

One module fixture records an expert dataset and trains two tiny LeWM runs on the CPU (a few
seconds): ``lewm`` (frameskip 1, trained long enough to plan with) and ``lewm-fs2`` (frameskip
2, a few steps: for the action-block bookkeeping only).
"""

from __future__ import annotations

import numpy as np
import pytest
import torch
from _toy_home import HIDDEN_GOAL, IMAGE, TOY, toy_home

from stable_worldmodel import World, keys
from stable_worldmodel.errors import ConfigError, UnknownNameError
from stable_worldmodel.planning.learned import PlanSettings, world_model_policy
from stable_worldmodel.policy import RandomPolicy
from stable_worldmodel.solver import get_solver_class, list_solvers
from stable_worldmodel.wm.preprocess import Normalizer

#: every registered solver that plans continuous actions (pgd relaxes discrete ones)
SOLVERS = [name for name in list_solvers() if not getattr(get_solver_class(name), "discrete_actions", False)]

#: a width-8 CNN LeWM at 16x16 with a one-layer predictor
TINY = dict(
    image_size=IMAGE,
    embed_dim=16,
    cnn_width=8,
    depth=1,
    heads=2,
    dim_head=8,
    mlp_dim=32,
    projector_hidden=32,
    sigreg_num_proj=256,
    batch_size=32,
    warmup_steps=10,
)
#: evaluation seeds, far from the recorded ones (0..159)
EVAL_SEED = 10_000


@pytest.fixture(scope="module")
def home(tmp_path_factory):
    """A cache with dataset ``toy`` (160 expert episodes, 16x16) and checkpoints ``lewm`` / ``lewm-fs2``."""
    yield from toy_home(
        tmp_path_factory,
        "stablewm_learned",
        [
            ("lewm", "lewm", dict(steps=400, frameskip=1, **TINY)),
            ("lewm", "lewm-fs2", dict(steps=2, frameskip=2, **TINY)),
        ],
    )


def toy_world(num_envs: int = 2, max_episode_steps: int = 30) -> World:
    return World(
        TOY,
        num_envs,
        (IMAGE, IMAGE),
        max_episode_steps=max_episode_steps,
        verbose=0,
        seed=EVAL_SEED,
        vectorization_mode="sync",
    )


def make(home, run: str = "lewm", **settings):
    """``(policy, protocol)`` of checkpoint ``run`` planning on the CPU with ``PlanSettings(**settings)``."""
    return world_model_policy(run, PlanSettings(**settings), device="cpu", cache_dir=str(home))


class SolveSpy:
    """Records the ``init_action`` and the planned ``actions`` of every solve of ``policy.solver``."""

    def __init__(self, policy, monkeypatch):
        self.inits, self.plans = [], []
        solve = policy.solver.solve

        def spy(info, init_action=None):
            result = solve(info, init_action=init_action)
            self.inits.append(None if init_action is None else init_action.clone())
            self.plans.append(result["actions"].clone())
            return result

        monkeypatch.setattr(policy.solver, "solve", spy)

    def __len__(self) -> int:
        return len(self.plans)


def test_planning_with_the_trained_model_beats_random(home):
    """CEM on the trained model vs the random policy on the same 32 seeds, goal disk hidden."""

    def success_rate(policy) -> float:
        with toy_world(num_envs=4) as world:
            world.set_policy(policy)
            return world.evaluate(episodes=32, seed=EVAL_SEED, options=HIDDEN_GOAL)["success_rate"]

    policy, protocol = make(home, solver="cem", horizon=2, receding_horizon=1, samples=64, iterations=4)
    assert protocol["model"] == "lewm" and protocol["dataset"] == "toy" and protocol["image_size"] == IMAGE
    planned, random = success_rate(policy), success_rate(RandomPolicy(seed=0))
    # checked by hand over training seeds 0-5 x eval seeds 1e4, 2e4, 3e4: planner 34-69%, random 9-16%
    assert planned >= max(2 * random, random + 20), f"planner {planned:.1f}% vs random {random:.1f}%"


@pytest.mark.parametrize("solver", SOLVERS)
def test_every_solver_plans_and_encodes_context_and_goal_once_per_plan(home, solver, monkeypatch):
    settings = dict(solver=solver, horizon=3, receding_horizon=2, samples=12, iterations=3)
    policy, protocol = make(home, **settings)
    encoder = policy.solver.model.encoder
    encoded = []  # images per encoder call
    forward = encoder.forward

    def counting(pixels, **kwargs):
        encoded.append(pixels.shape[0])
        return forward(pixels, **kwargs)

    monkeypatch.setattr(encoder, "forward", counting)
    spy = SolveSpy(policy, monkeypatch)
    norm = Normalizer.from_dict(protocol["normalizers"][keys.ACTION])
    low, high = norm.transform(-np.ones((1, 2))).ravel(), norm.transform(np.ones((1, 2))).ravel()
    with toy_world() as world:
        world.set_policy(policy)
        world.reset(seed=EVAL_SEED, options=HIDDEN_GOAL)
        world.step()
        # one plan of 3 iterations: the context (B * T = 2 frames) and the goal (2 frames), encoded once each
        assert len(spy) == 1 and encoded == [2, 2]
        plan = spy.plans[0]
        assert plan.shape == (2, 3, 2)  # (B, H, A): normalized action blocks inside the mapped bounds
        assert torch.isfinite(plan).all()
        assert (plan.numpy() >= low - 1e-5).all() and (plan.numpy() <= high + 1e-5).all()
        action = world.infos[keys.ACTION][:, -1]
        assert action.shape == (2, 2) and action.dtype == np.float32 and world.action_space.contains(action)
        assert np.allclose(action, np.clip(norm.inverse_transform(plan[:, 0].numpy()), -1, 1), atol=1e-6)
        world.step()  # second action of the plan: no solve, no encoding
        assert len(spy) == 1 and len(encoded) == 2
        world.step()  # a new plan, encoded once more
        assert len(spy) == 2 and encoded == [2, 2, 2, 2]
    expected = PlanSettings(**settings).as_dict()
    assert {k: v for k, v in protocol["plan"].items() if k in expected} == expected
    # subgoals="auto" on a LeWM whose dataset is on disk: the graph, and the least patience (3 x 1 steps < 10)
    assert protocol["plan"]["subgoals"] == "auto" and protocol["plan"]["patience"] == 10
    assert protocol["device"] == "cpu" and protocol["action_block"] == 1


def test_receding_horizon_consumes_action_blocks_of_frameskip_steps(home, monkeypatch):
    """H = 3 blocks of frameskip 2: the first R = 2 blocks (4 env steps) run, then a replan warm-started
    with the last block."""
    policy, protocol = make(home, "lewm-fs2", solver="cem", horizon=3, receding_horizon=2, samples=8, iterations=2)
    assert protocol["action_block"] == 2 and policy.config.action_block == 2
    assert policy.config.horizon == 3 and policy.config.receding_horizon == 2
    spy = SolveSpy(policy, monkeypatch)
    norm = Normalizer.from_dict(protocol["normalizers"][keys.ACTION])
    taken = []
    with toy_world() as world:
        world.set_policy(policy)
        assert policy.solver.action_dim == 4  # one block = 2 env actions of 2 numbers
        world.reset(seed=EVAL_SEED, options=HIDDEN_GOAL)
        for _ in range(9):
            world.step()
            taken.append(world.infos[keys.ACTION][:, -1].copy())
    assert len(spy) == 3  # env steps 0, 4 and 8
    for k in range(2):
        plan = spy.plans[k].numpy()  # (B, H, 4)
        first = norm.inverse_transform(plan[:, :2].reshape(-1, 2)).reshape(2, 4, 2)  # 2 blocks -> 4 env steps
        assert np.allclose(np.stack(taken[4 * k : 4 * k + 4], axis=1), np.clip(first, -1, 1), atol=1e-6)
    assert spy.inits[0] is None
    assert spy.inits[1].shape == (2, 1, 4) and torch.equal(spy.inits[1], spy.plans[0][:, 2:])
    assert torch.equal(spy.inits[2], spy.plans[1][:, 2:])


@pytest.mark.parametrize("receding", [3, 1], ids=["mid-plan", "plan-boundary"])
def test_an_env_restarting_replans_every_env_without_warm_start(home, monkeypatch, receding):
    """Env 1 starts a new episode (its step_idx is 0) after one step of a 4-block plan: every env
    replans from scratch, and acts on the new plan from its first block."""
    policy, protocol = make(home, solver="cem", horizon=4, receding_horizon=receding, samples=8, iterations=2)
    norm = Normalizer.from_dict(protocol["normalizers"][keys.ACTION])
    spy = SolveSpy(policy, monkeypatch)
    with toy_world() as world:
        world.set_policy(policy)
        world.reset(seed=EVAL_SEED, options=HIDDEN_GOAL)
        world.step()
        world.reset_envs([1], seeds=[EVAL_SEED + 7], options=HIDDEN_GOAL)
        assert world.infos[keys.STEP_IDX][:, -1].tolist() == [1, 0]
        world.step()
        assert len(spy) == 2 and spy.inits[1] is None
        first = np.clip(norm.inverse_transform(spy.plans[1][:, 0].numpy()), -1, 1)
        assert np.allclose(world.infos[keys.ACTION][:, -1], first, atol=1e-6)
        world.step()  # no restart: the new plan goes on (or, at R = 1, a warm-started replan)
        assert len(spy) == 2 + (receding == 1)
        if receding == 1:
            assert torch.equal(spy.inits[2], spy.plans[1][:, 1:])


def test_a_new_evaluation_does_not_start_from_the_previous_plan(home, monkeypatch):
    """World.evaluate resets every env: the warm start left by an earlier rollout is dropped."""
    policy, _ = make(home, solver="cem", horizon=4, receding_horizon=3, samples=8, iterations=1)
    spy = SolveSpy(policy, monkeypatch)
    with toy_world(max_episode_steps=3) as world:
        world.set_policy(policy)
        world.evaluate(episodes=2, seed=EVAL_SEED, options=HIDDEN_GOAL)  # the 3 steps of one plan
        assert len(spy) == 1
        world.evaluate(episodes=2, seed=EVAL_SEED + 2, options=HIDDEN_GOAL)
        assert len(spy) == 2 and spy.inits[1] is None


# -- PlanSettings ------------------------------------------------------------------------------------
def test_plan_settings_unknown_solver_suggests_the_close_names():
    with pytest.raises(UnknownNameError) as info:
        PlanSettings(solver="cme")
    message = str(info.value)
    assert isinstance(info.value, KeyError) and "'cme'" in message
    assert "Did you mean" in message and message.index("'cem'") < message.index("'icem'")
    assert "Accepted: " + ", ".join(list_solvers()) in message


@pytest.mark.parametrize(
    "field, value", [("horizon", 0), ("samples", -3), ("iterations", 0), ("horizon", 2.5), ("samples", True)]
)
def test_plan_settings_sizes_must_be_positive_ints(field, value):
    with pytest.raises(ConfigError, match=f"PlanSettings requires {field} to be a positive int, got {value!r}"):
        PlanSettings(**{field: value})


def test_plan_settings_receding_horizon_is_within_the_horizon():
    with pytest.raises(ConfigError, match="receding_horizon <= horizon=3, got 4"):
        PlanSettings(horizon=3, receding_horizon=4)
    with pytest.raises(ConfigError, match="got 0"):
        PlanSettings(receding_horizon=0)
    assert PlanSettings(horizon=3).as_dict()["receding_horizon"] == 1  # default: MPC, replan after every block
    assert PlanSettings(horizon=3, receding_horizon=None).as_dict()["receding_horizon"] == 3  # None: the whole plan


def test_plan_settings_cost_is_checked_and_reaches_the_model(home):
    with pytest.raises(UnknownNameError, match="Unknown goal cost 'mni'. Did you mean 'min'"):
        PlanSettings(cost="mni")
    assert PlanSettings().cost == "auto"
    for cost, used in (("final", "final"), ("min", "min"), ("auto", "min")):
        policy, protocol = make(home, solver="cem", horizon=2, samples=8, iterations=1, cost=cost)
        assert policy.solver.model.goal_cost == used and protocol["plan"]["cost"] == cost


def _planned_actions(policy, steps: int = 4) -> np.ndarray:
    with toy_world() as world:
        world.set_policy(policy)
        world.reset(seed=EVAL_SEED, options=HIDDEN_GOAL)
        for _ in range(steps):
            world.step()
        return world.infos[keys.ACTION].copy()


def test_subgoal_graph_is_built_from_the_training_split_and_redirects_the_goal(home, monkeypatch):
    """``subgoals="graph"``: one node per training frame (frameskip 1), the waypoint replaces the
    goal embedding; with a lookahead longer than any path, the waypoint is the goal: same plans."""
    settings = dict(solver="cem", horizon=2, receding_horizon=1, samples=16, iterations=2)
    policy, protocol = make(home, **settings, subgoals="graph", lookahead=1)
    graph = protocol["plan"]["graph"]
    assert protocol["plan"]["subgoals"] == "graph" and protocol["plan"]["lookahead"] == 1
    train_frames = sum(int(n) for n in np.asarray(_dataset_lengths(home))[protocol["train_episodes"]])
    assert graph["stride"] == 1 and graph["nodes"] == train_frames and graph["edges"] > graph["nodes"] / 2
    seen = []
    solve = policy.solver.solve
    monkeypatch.setattr(
        policy.solver,
        "solve",
        lambda info, init_action=None: seen.append(info["goal_emb"].clone()) or solve(info, init_action),
    )
    redirected = _planned_actions(policy)
    model = policy.solver.model
    with toy_world() as world:
        world.reset(seed=EVAL_SEED, options=HIDDEN_GOAL)
        goal = model.encode_pixels(
            policy.transform[keys.GOAL](torch.as_tensor(world.infos[keys.GOAL][:, -1]).permute(0, 3, 1, 2))
        )
    assert seen[0].shape == (2, 1, goal.shape[-1]) and not torch.allclose(
        seen[0][:, 0], goal
    )  # a waypoint, not the goal
    far, _ = make(home, **settings, subgoals="graph", lookahead=10_000)
    plain, _ = make(home, **settings, subgoals="none")
    np.testing.assert_array_equal(_planned_actions(far), _planned_actions(plain))
    assert not np.array_equal(redirected, _planned_actions(plain))


def test_auto_subgoals_aim_at_waypoints_only_once_an_episode_stalls(home, monkeypatch):
    """``subgoals="auto"``: the goal while the monitor sees progress (4 steps < patience 10: the
    plain plans), the graph's waypoints for the envs it calls stalled (all: the graph's plans)."""
    from stable_worldmodel.planning.subgoals import StallMonitor

    settings = dict(solver="cem", horizon=2, receding_horizon=1, samples=16, iterations=2, lookahead=1)
    auto, protocol = make(home, **settings)
    assert protocol["plan"]["subgoals"] == "auto" and protocol["plan"]["patience"] == 10
    plain, _ = make(home, **settings, subgoals="none")
    np.testing.assert_array_equal(_planned_actions(auto), _planned_actions(plain))
    graph, _ = make(home, **settings, subgoals="graph")
    monkeypatch.setattr(
        StallMonitor, "update", lambda self, current, goal, restarted=None: torch.ones(len(goal), dtype=torch.bool)
    )
    stalled, _ = make(home, **settings)
    np.testing.assert_array_equal(_planned_actions(stalled), _planned_actions(graph))
    assert not np.array_equal(_planned_actions(stalled), _planned_actions(plain))


def _dataset_lengths(home):
    from stable_worldmodel.data import HDF5Dataset

    return HDF5Dataset("toy", cache_dir=home).lengths


def test_subgoal_graph_needs_the_training_dataset(home, monkeypatch):
    import shutil

    copy = home / "moved"
    copy.mkdir(exist_ok=True)
    shutil.copytree(home / "checkpoints", copy / "checkpoints", dirs_exist_ok=True)
    monkeypatch.setattr("stable_worldmodel.planning.learned._exists", lambda path: False)
    with pytest.raises(ConfigError, match="training dataset 'toy'"):
        world_model_policy("lewm", PlanSettings(subgoals="graph"), device="cpu", cache_dir=str(copy))

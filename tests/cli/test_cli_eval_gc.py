"""``swm eval --policy gc:RUN``: a goal-conditioned policy trained by our trainer acts through the CLI
(same checkpoint lookup and preprocessing / normalizer protocol as ``wm:RUN``), ``swm train gcbc --run``,
history and action blocks, held-out starts, and the one-line errors.

One module fixture records 30 expert episodes of swm/Toy-v0 at 16x16 and trains a tiny GCBC on them
for 300 steps (about 4 s); each test copies that cache into its own ``STABLEWM_HOME``.
"""

from __future__ import annotations

import json
import shutil

import pytest

TOY = "swm/Toy-v0"
RUN = "toy-gcbc"
#: a width-8 CNN GCBC at 16x16 acting on one frame
NET = dict(
    image_size=16,
    embed_dim=16,
    cnn_width=8,
    depth=3,
    heads=2,
    dim_head=8,
    mlp_dim=32,
    history_size=1,
    warmup_steps=0,
    batch_size=32,
)
SMALL = ("--device", "cpu", "--image-size", "16")


@pytest.fixture(scope="module")
def template(tmp_path_factory):
    """A cache holding dataset ``toy`` (30 expert episodes) and checkpoint ``toy-gcbc``."""
    import torch

    from stable_worldmodel import World
    from stable_worldmodel.envs import expert_policy
    from stable_worldmodel.train import train

    root = tmp_path_factory.mktemp("stablewm_eval_gc")
    threads = torch.get_num_threads()
    torch.set_num_threads(1)
    try:
        with World(TOY, 2, (16, 16), max_episode_steps=30, verbose=0, vectorization_mode="sync") as world:
            world.set_policy(expert_policy(TOY))
            world.record_dataset("toy", episodes=30, seed=0, cache_dir=root)
        train(
            "gcbc", "toy", "tiny", steps=300, name=RUN, seed=0, device="cpu", progress=False, cache_dir=str(root), **NET
        )
    finally:
        torch.set_num_threads(threads)
    return root


@pytest.fixture
def home(template, _stablewm_home, one_torch_thread):
    """This test's ``STABLEWM_HOME``, holding a copy of the template cache."""
    shutil.copytree(template, _stablewm_home, dirs_exist_ok=True)
    return _stablewm_home


def evaluate(swm, policy: str, out, *extra: str) -> dict:
    result = swm("eval", TOY, "--policy", policy, *extra, "--json", str(out))
    assert result.exit_code == 0, result.output
    return json.loads(out.read_text())


def test_trained_gcbc_beats_the_random_policy(swm, home, tmp_path):
    args = ("--episodes", "20", "--num-envs", "4", "--max-steps", "40", *SMALL)
    gc = evaluate(swm, f"gc:{RUN}", tmp_path / "gc.json", *args)
    random = evaluate(swm, "random", tmp_path / "random.json", *args)
    assert gc["seeds"] == random["seeds"] == [0, 19]  # the same starts and goals
    assert gc["successes"] >= random["successes"] + 5, (gc["successes"], random["successes"])
    assert gc["success_rate"] >= 50.0
    model = gc["model"]
    assert model["checkpoint"] == str(home / "checkpoints" / RUN)
    assert (model["model"], model["preset"], model["dataset"], model["steps"], model["image_size"]) == (
        "gcbc",
        "tiny",
        "toy",
        300,
        16,
    )
    assert "plan" not in gc and "history_size" not in gc  # one frame, nothing planned


def test_a_gcbc_reading_proprio_acts_from_the_worlds_proprio_and_goal_proprio(swm, home, tmp_path):
    """Upstream's gcbc default (use_proprio_encoder): proprio and the goal's proprio, normalized as in training."""
    from stable_worldmodel.train import train

    train("gcbc", "toy", "tiny", steps=300, name="prop", seed=0, device="cpu", progress=False,
          **{**NET, "proprio_dim": 2})  # fmt: skip
    protocol = json.loads((home / "checkpoints" / "prop" / "protocol.json").read_text())
    assert set(protocol["normalizers"]) == {"action", "proprio"}
    args = ("--episodes", "20", "--num-envs", "4", "--max-steps", "40", *SMALL)
    gc = evaluate(swm, "gc:prop", tmp_path / "gc.json", *args)
    random = evaluate(swm, "random", tmp_path / "random.json", *args)
    assert gc["successes"] >= random["successes"] + 5 and gc["success_rate"] >= 50.0, (gc, random)


def test_history_and_action_blocks_reach_the_policy(swm, home, tmp_path):
    """A policy on 2 frames and blocks of 2 actions: the World keeps 2 frames,
    the policy acts with the first action of each block."""
    from stable_worldmodel.train import train

    train(
        "gcbc",
        "toy",
        "tiny",
        steps=2,
        name="hist",
        seed=0,
        device="cpu",
        progress=False,
        **{**NET, "history_size": 2, "frameskip": 2},
    )
    record = evaluate(
        swm, "gc:hist", tmp_path / "out.json", "--episodes", "2", "--num-envs", "2", "--max-steps", "5", *SMALL
    )
    assert record["history_size"] == 2 and record["model"]["frameskip"] == 2
    assert 1 <= record["mean_length"] <= 5


def test_goal_conditioned_policy_objects(home):
    import numpy as np

    from stable_worldmodel import World
    from stable_worldmodel.planning.goal_policy import GoalConditionedPolicy, goal_conditioned_policy

    policy, protocol = goal_conditioned_policy(RUN, device="cpu")
    assert isinstance(policy, GoalConditionedPolicy) and protocol["history_size"] == 1 and protocol["action_block"] == 1
    assert "action" in policy.process and policy.transform["pixels"].size == 16
    with World(TOY, 2, (16, 16), max_episode_steps=5, verbose=0, vectorization_mode="sync") as world:
        world.set_policy(policy)
        world.reset(seed=0)
        action = policy.get_action(world.infos)
    assert action.shape == (2, 2) and action.dtype == np.float32 and np.abs(action).max() <= 1.0


def test_eval_gc_from_dataset_uses_held_out_episodes(swm, home, tmp_path):
    record = evaluate(
        swm,
        f"gc:{RUN}",
        tmp_path / "out.json",
        "--episodes",
        "3",
        "--num-envs",
        "3",
        *SMALL,
        "--from-dataset",
        "toy",
        "--goal-offset",
        "2",
        "--budget",
        "5",
    )
    val = json.loads((home / "checkpoints" / RUN / "protocol.json").read_text())["val_episodes"]
    assert record["held_out"] is True and set(record["episodes_idx"]) <= set(val)


def test_swm_train_gcbc_with_run_name(swm, home):
    result = swm(
        "train",
        "gcbc",
        "--dataset",
        "toy",
        "--preset",
        "tiny",
        "--steps",
        "2",
        "--batch-size",
        "4",
        "--device",
        "cpu",
        "--run",
        "cli-gcbc",
    )
    assert result.exit_code == 0, result.output
    assert "Trained gcbc (tiny) on toy: 2 steps" in result.stdout
    assert "--policy gc:cli-gcbc" in result.stdout
    protocol = json.loads((home / "checkpoints" / "cli-gcbc" / "protocol.json").read_text())
    assert protocol["model"] == "gcbc" and protocol["config"]["goal_probabilities"] == {"uniform": 1.0}


def test_unknown_gc_run_is_one_line(swm, home, error_line):
    result = swm("eval", TOY, "--policy", "gc:toy-gcbd", "--episodes", "1")
    assert result.exit_code == 1
    line = error_line(result)
    assert "'toy-gcbd'" in line and "Did you mean" in line and "'toy-gcbc'" in line


def test_gc_and_wm_checkpoints_are_not_interchangeable(swm, home, error_line):
    import stable_worldmodel.wm as wm
    from stable_worldmodel.wm.utils import save_pretrained

    config = wm.get_config("dummy", "tiny", image_size=16, frameskip=1)
    save_pretrained(
        wm.make("dummy", "tiny", action_dim=2, image_size=16, frameskip=1), "planner", config=config.target_tree(2)
    )
    result = swm("eval", TOY, "--policy", "gc:planner", "--episodes", "1", *SMALL)
    assert result.exit_code == 1
    assert "--policy wm:planner" in error_line(result)
    result = swm("eval", TOY, "--policy", f"wm:{RUN}", "--episodes", "1", *SMALL)
    assert result.exit_code == 1
    assert f"--policy gc:{RUN}" in error_line(result)


def test_bad_policy_name_lists_the_gc_form(swm, home, error_line):
    result = swm("eval", TOY, "--policy", "gcbc", "--episodes", "1")
    assert result.exit_code == 1
    assert "gc:<run>" in error_line(result)

"""``swm eval --policy wm:RUN``: planning with a checkpoint, its JSON record, the held-out dataset
protocol (``--from-dataset``) and the one-line errors.

One module fixture records a 16x16 toy dataset and trains a tiny LeWM for two steps (the
model does not have to be good here); each test copies that cache into its own ``STABLEWM_HOME``.
"""

from __future__ import annotations

import json
import shutil
from types import SimpleNamespace

import numpy as np
import pytest

from stable_worldmodel.cli.stats import wilson_interval
from stable_worldmodel.errors import ConfigError

TOY = "swm/Toy-v0"
RUN = "toy-lewm"
#: a tiny LeWM at 16x16; a quarter of the 12 episodes held out for validation
TINY = dict(
    image_size=16,
    embed_dim=16,
    cnn_width=8,
    depth=1,
    heads=2,
    dim_head=8,
    mlp_dim=32,
    projector_hidden=32,
    sigreg_num_proj=32,
    batch_size=8,
    frameskip=1,
    val_fraction=0.25,
)
#: a small plan, on the CPU, with 16x16 images
PLAN = ("--solver", "cem", "--samples", "16", "--iterations", "2", "--horizon", "3")
SMALL = ("--device", "cpu", "--image-size", "16")


@pytest.fixture(scope="module")
def template(tmp_path_factory):
    """A cache holding dataset ``toy`` (12 expert episodes) and checkpoint ``toy-lewm``."""
    from stable_worldmodel import World
    from stable_worldmodel.envs import expert_policy
    from stable_worldmodel.train import train

    root = tmp_path_factory.mktemp("stablewm_eval_wm")
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("STABLEWM_HOME", str(root))
        with World(TOY, 2, (16, 16), max_episode_steps=20, verbose=0, vectorization_mode="sync") as world:
            world.set_policy(expert_policy(TOY))
            world.record_dataset("toy", episodes=12, seed=0, cache_dir=root)
        train(
            "lewm", "toy", "tiny", steps=2, name=RUN, seed=0, device="cpu", progress=False, cache_dir=str(root), **TINY
        )
    return root


@pytest.fixture
def home(template, _stablewm_home):
    """This test's ``STABLEWM_HOME``, holding a copy of the template cache."""
    shutil.copytree(template, _stablewm_home, dirs_exist_ok=True)
    return _stablewm_home


def protocol(home) -> dict:
    return json.loads((home / "checkpoints" / RUN / "protocol.json").read_text())


def test_eval_wm_writes_success_rate_interval_seeds_and_plan(swm, home, tmp_path):
    out = tmp_path / "results" / "out.json"
    args = (
        "eval",
        TOY,
        "--policy",
        f"wm:{RUN}",
        "--episodes",
        "4",
        "--num-envs",
        "2",
        "--max-steps",
        "10",
        *PLAN,
        *SMALL,
    )
    result = swm(*args, "--json", str(out))
    assert result.exit_code == 0, result.output
    record = json.loads(out.read_text())

    assert (record["env"], record["policy"], record["episodes"], record["num_envs"]) == (TOY, f"wm:{RUN}", 4, 2)
    assert (record["protocol"], record["seeds"], record["max_steps"]) == ("seeds", [0, 3], 10)
    successes = sum(record["episode_successes"])
    assert len(record["episode_successes"]) == 4 and record["successes"] == successes
    assert record["success_rate"] == pytest.approx(100 * successes / 4)
    assert np.allclose(record["ci95"], [100 * v for v in wilson_interval(successes, 4)], atol=0.01)
    assert 1 <= record["mean_length"] <= 10
    assert record["plan"] == {
        "solver": "cem",
        "horizon": 3,
        "receding_horizon": 1,
        "samples": 16,
        "iterations": 2,
        "topk": None,
        "seed": 0,
        "cost": "auto",
        "subgoals": "auto",
        "lookahead": 1,
        "patience": 10,  # auto: the graph of its 9 training episodes
    }
    model = record["model"]
    assert model["checkpoint"] == str(home / "checkpoints" / RUN)
    assert (model["model"], model["preset"], model["dataset"], model["steps"]) == ("lewm", "tiny", "toy", 2)
    assert (model["frameskip"], model["history_size"], model["image_size"]) == (1, 1, 16)

    # the printed table agrees, and names the file
    assert "swm/Toy-v0: seeds 0..3, at most 10 steps" in result.stdout
    row = next(line for line in result.stdout.splitlines() if line.strip("│ ").startswith(f"wm:{RUN}"))
    assert f"{record['success_rate']:.1f}%" in row
    assert f"Results: {out}" in result.stdout


def test_eval_wm_from_dataset_starts_from_held_out_episodes(swm, home, tmp_path, monkeypatch):
    from stable_worldmodel.data import HDF5Dataset
    from stable_worldmodel.world import World

    steps = []
    world_step = World.step

    def counting_step(self):
        steps.append(self.num_envs)
        world_step(self)

    monkeypatch.setattr(World, "step", counting_step)
    out = tmp_path / "out.json"
    args = ("eval", TOY, "--policy", f"wm:{RUN}", "--episodes", "3", "--num-envs", "2", *PLAN, *SMALL)
    result = swm(*args, "--from-dataset", "toy", "--goal-offset", "2", "--budget", "4", "--json", str(out))
    assert result.exit_code == 0, result.output
    record = json.loads(out.read_text())

    assert (record["protocol"], record["dataset"], record["goal_offset"], record["budget"]) == ("dataset", "toy", 2, 4)
    assert record["held_out"] is True
    val = protocol(home)["val_episodes"]
    assert len(val) == 3 and set(record["episodes_idx"]) <= set(val)
    lengths = HDF5Dataset("toy", preload=False).lengths
    assert len(record["episodes_idx"]) == len(record["start_steps"]) == len(record["episode_successes"]) == 3
    for episode, start in zip(record["episodes_idx"], record["start_steps"], strict=False):
        assert 0 <= start and start + 2 < lengths[episode]  # the goal is a recorded state 2 steps later
    assert len(set(zip(record["episodes_idx"], record["start_steps"], strict=False))) == 3  # no repeated start
    # at most the budget: per episode, and per batch of 2 envs (3 episodes: 2 batches)
    assert 1 <= record["mean_length"] <= 4
    assert 1 <= len(steps) <= 2 * 4 and set(steps) == {2}
    assert "swm/Toy-v0: 3 starts from toy (goal +2 steps, budget 4)" in result.stdout
    assert "seeds" not in record


def test_eval_random_from_dataset_uses_every_episode(swm, home, tmp_path):
    out = tmp_path / "out.json"
    result = swm(
        "eval",
        TOY,
        "--episodes",
        "8",
        "--image-size",
        "16",
        "--from-dataset",
        "toy",
        "--goal-offset",
        "1",
        "--budget",
        "3",
        "--json",
        str(out),
    )
    assert result.exit_code == 0, result.output
    record = json.loads(out.read_text())
    assert record["held_out"] is False and "plan" not in record and "model" not in record
    assert not set(record["episodes_idx"]) <= set(protocol(home)["val_episodes"])


def test_protocol_upstream_sets_every_knob_and_options_given_win(swm, home, tmp_path):
    """``--protocol upstream`` (upstream's scripts/plan/config/pusht.yaml and solver/cem.yaml): 50 starts, seed
    42, goal +25, budget 50, CEM 300 x 30, horizon 5, receding horizon 5, cost final, no subgoals; what the
    user gives wins; the random floor starts from the held-out episodes of swm train's default split."""
    from stable_worldmodel.cli.evaluation import protocol_knobs
    from stable_worldmodel.data import HDF5Dataset
    from stable_worldmodel.train.data import split_episodes

    knobs = protocol_knobs("upstream", TOY)
    assert knobs == {
        "episodes": 50,
        "seed": 42,
        "solver": "cem",
        "horizon": 5,
        "receding_horizon": 5,
        "samples": 300,
        "iterations": 30,
        "cost": "final",
        "subgoals": "none",
        "goal_offset": 25,
        "budget": 50,
    }
    assert protocol_knobs("upstream", "swm/OGBCube-v0")["goal_offset"] == 200
    out = tmp_path / "wm.json"
    given = ("--episodes", "2", "--samples", "8", "--iterations", "1", "--goal-offset", "2", "--budget", "3")
    args = ("eval", TOY, "--policy", f"wm:{RUN}", *SMALL, "--from-dataset", "toy", "--protocol", "upstream")
    result = swm(*args, *given, "--json", str(out))
    assert result.exit_code == 0, result.output
    record = json.loads(out.read_text())
    plan = record["plan"]
    assert (record["protocol_name"], record["seed"], record["episodes"]) == ("upstream", 42, 2)
    assert (record["goal_offset"], record["budget"]) == (2, 3)  # given
    assert (plan["horizon"], plan["receding_horizon"], plan["cost"], plan["subgoals"]) == (5, 5, "final", "none")
    assert (plan["samples"], plan["iterations"], plan["solver"]) == (8, 1, "cem")  # given, given, the protocol's
    assert set(record["episodes_idx"]) <= set(protocol(home)["val_episodes"])  # the run's held-out episodes

    floor = tmp_path / "random.json"
    result = swm("eval", TOY, "--image-size", "16", "--from-dataset", "toy", "--protocol", "upstream",
                 "--goal-offset", "1", "--budget", "3", "--json", str(floor))  # fmt: skip
    assert result.exit_code == 0, result.output
    record = json.loads(floor.read_text())
    _, val = split_episodes(HDF5Dataset("toy", preload=False).num_episodes, 0.1, 0)
    assert record["episodes"] == 50 and set(record["episodes_idx"]) <= set(val.tolist())
    assert record["start_pool"].startswith("validation episodes of swm train's default split")
    same = tmp_path / "same.json"
    result = swm("eval", TOY, "--image-size", "16", "--from-dataset", "toy", "--protocol", "upstream",
                 "--held-out-of", f"wm:{RUN}", "--goal-offset", "1", "--budget", "3", "--json", str(same))  # fmt: skip
    assert result.exit_code == 0, result.output
    assert set(json.loads(same.read_text())["episodes_idx"]) <= set(protocol(home)["val_episodes"])


@pytest.mark.parametrize(
    ("extra", "needle"),
    [
        (("--protocol", "upstream"), "--protocol: requires --from-dataset NAME"),
        (("--from-dataset", "toy", "--protocol", "upstrem"), "Did you mean 'upstream'"),
        (("--held-out-of", "wm:x"), "--held-out-of: requires --from-dataset NAME"),
        (("--from-dataset", "toy", "--held-out-of", "random"), "--held-out-of requires a wm:/gc: run"),
    ],
)
def test_protocol_bad_input_is_one_line(swm, home, error_line, extra, needle):
    result = swm("eval", TOY, "--image-size", "16", "--episodes", "1", *extra)
    assert result.exit_code in (1, 2) and needle in error_line(result), result.output  # 2: a usage error


def test_eval_unknown_run_is_one_line_naming_where_checkpoints_are(swm, home, error_line):
    result = swm("eval", TOY, "--policy", "wm:nosuchrun", "--episodes", "1")
    assert result.exit_code == 1
    line = error_line(result)
    assert "'nosuchrun'" in line
    assert str(home / "checkpoints") in line and RUN in line  # where it looked, and what is there


@pytest.mark.parametrize(
    "options, needles",
    [
        (("--solver", "cme"), ["'cme'", "Did you mean", "'cem'"]),
        (("--horizon", "3", "--receding-horizon", "4"), ["receding_horizon", "horizon=3", "got 4"]),
        (("--cost", "mni"), ["goal cost 'mni'", "Did you mean 'min'", "final"]),
        (("--subgoals", "grpah"), ["subgoal method 'grpah'", "'graph'"]),
    ],
    ids=["solver", "receding-horizon", "cost", "subgoals"],
)
def test_eval_bad_plan_settings_are_one_line(swm, home, error_line, options, needles):
    result = swm("eval", TOY, "--policy", f"wm:{RUN}", "--episodes", "1", *options)
    assert result.exit_code == 1
    line = error_line(result)
    for needle in needles:
        assert needle in line, line
    if options[0] == "--solver":  # 'cem' is the first suggestion
        assert line.index("'cem'") < line.index("'icem'")


@pytest.mark.parametrize(
    "options, recorded",
    [
        (("--cost", "final", "--receding-horizon", "3"), {"cost": "final", "receding_horizon": 3}),
        (("--subgoals", "graph", "--lookahead", "2"), {"subgoals": "graph", "lookahead": 2}),
        (("--subgoals", "none"), {"subgoals": "none"}),
        (("--patience", "4"), {"subgoals": "auto", "patience": 4}),
    ],
    ids=["final-cost", "subgoals", "plain", "patience"],
)
def test_eval_plan_settings_are_recorded(swm, home, tmp_path, options, recorded):
    out = tmp_path / "out.json"
    args = (
        "eval",
        TOY,
        "--policy",
        f"wm:{RUN}",
        "--episodes",
        "2",
        "--num-envs",
        "2",
        "--max-steps",
        "6",
        *PLAN,
        *SMALL,
    )
    result = swm(*args, *options, "--json", str(out))
    assert result.exit_code == 0, result.output
    plan = json.loads(out.read_text())["plan"]
    assert {k: plan[k] for k in recorded} == recorded


def test_auto_subgoals_plan_on_the_goal_alone_without_the_training_dataset(swm, home, tmp_path):
    (home / "toy.h5").unlink()
    record = protocol(home)
    del record["dataset_path"]  # the template's file: found by name in this home only
    (home / "checkpoints" / RUN / "protocol.json").write_text(json.dumps(record))
    out = tmp_path / "out.json"
    args = (
        "eval",
        TOY,
        "--policy",
        f"wm:{RUN}",
        "--episodes",
        "2",
        "--num-envs",
        "2",
        "--max-steps",
        "4",
        *PLAN,
        *SMALL,
    )
    result = swm(*args, "--json", str(out))
    assert result.exit_code == 0, result.output
    plan = json.loads(out.read_text())["plan"]
    assert plan["subgoals"] == "none" and "patience" not in plan and "lookahead" not in plan


@pytest.mark.parametrize("option", [("--subgoals", "graph"), ("--compile",)], ids=["subgoals", "compile"])
def test_planner_options_need_a_wm_policy(swm, option):
    result = swm("eval", TOY, "--policy", "random", "--episodes", "1", *option)
    assert result.exit_code != 0
    assert "wm:RUN policies only" in result.output


def test_eval_compile_plans_through_a_compiled_cost(swm, home, tmp_path, compile_recorder):
    out = tmp_path / "out.json"
    args = ("eval", TOY, "--policy", f"wm:{RUN}", "--episodes", "2", "--num-envs", "2", "--max-steps", "4")
    result = swm(*args, *PLAN, *SMALL, "--compile", "--json", str(out))
    assert result.exit_code == 0, result.output
    assert compile_recorder.names == ["get_cost"]
    assert json.loads(out.read_text())["plan"]["compile"] is True


# -- dataset_starts: the (episode, start) pairs of --from-dataset --------------------------------
def test_dataset_starts_are_seeded_valid_and_distinct_while_possible():
    from stable_worldmodel.cli.evaluation import dataset_starts

    data = SimpleNamespace(lengths=np.array([3, 8, 6, 2]))
    eps, starts = dataset_starts(data, 5, goal_offset=3, seed=1, pool=[0, 1, 2])
    assert (eps, starts) == dataset_starts(data, 5, goal_offset=3, seed=1, pool=[0, 1, 2])
    assert set(eps) <= {1, 2}  # episode 0 is too short for the offset, 3 is outside the pool
    assert all(s + 3 < data.lengths[e] for e, s in zip(eps, starts, strict=False))
    assert len(set(zip(eps, starts, strict=False))) == 5
    # more starts than distinct pairs (5 + 3 = 8): every pair is used, then one repeats
    eps, starts = dataset_starts(data, 9, goal_offset=3, seed=0, pool=[0, 1, 2])
    assert len(eps) == 9 and len(set(zip(eps, starts, strict=False))) == 8
    with pytest.raises(ConfigError, match="--goal-offset 8"):
        dataset_starts(data, 2, goal_offset=8, seed=0)


def test_min_goal_distance_keeps_only_far_goals():
    """``--min-goal-distance D``: pairs whose goal's ``state`` row is at least D from the start's."""
    from stable_worldmodel.cli.evaluation import dataset_starts

    # two episodes of 6 rows; the state moves 1 per step in episode 0 and 3 per step in episode 1
    state = np.concatenate([np.arange(6.0), 100 + 3 * np.arange(6.0)])[:, None] * np.array([[0.6, 0.8]])
    data = SimpleNamespace(
        lengths=np.array([6, 6]), column_names=["state", "action"], get_col_data=lambda col: {"state": state}[col]
    )
    eps, starts = dataset_starts(data, 6, goal_offset=2, seed=0, min_distance=5.0)
    assert set(eps) == {1} and len(set(starts)) == 4  # episode 1's goals are 6 away, episode 0's 2
    eps, _ = dataset_starts(data, 6, goal_offset=2, seed=0, min_distance=2.0)
    assert set(eps) == {0, 1}
    with pytest.raises(ConfigError, match=r"at least 7 from their start, got none among .*farthest: 6\)"):
        dataset_starts(data, 2, goal_offset=2, seed=0, min_distance=7.0)
    bare = SimpleNamespace(lengths=np.array([6]), column_names=["action"])
    with pytest.raises(ConfigError, match="requires a 'state' column"):
        dataset_starts(bare, 2, goal_offset=2, seed=0, min_distance=1.0)


def test_eval_min_goal_distance_is_recorded_and_narrows_the_starts(swm, home, tmp_path):
    runs = {}
    for name, extra in (("all", ()), ("far", ("--min-goal-distance", "0.03"))):
        out = tmp_path / f"{name}.json"
        result = swm("eval", TOY, "--episodes", "12", "--image-size", "16", "--from-dataset", "toy",
                     "--goal-offset", "1", "--budget", "2", "--json", str(out), *extra)  # fmt: skip
        assert result.exit_code == 0, result.output
        runs[name] = json.loads(out.read_text())
    assert "min_goal_distance" not in runs["all"] and runs["far"]["min_goal_distance"] == 0.03
    from stable_worldmodel.data import HDF5Dataset

    data = HDF5Dataset("toy", cache_dir=home, preload=False)
    state = np.asarray(data.get_col_data("state"), np.float64).reshape(int(np.sum(data.lengths)), -1)
    first = np.concatenate([[0], np.cumsum(data.lengths)[:-1]])
    rows = first[runs["far"]["episodes_idx"]] + np.asarray(runs["far"]["start_steps"])
    assert (np.linalg.norm(state[rows + 1] - state[rows], axis=1) >= 0.03).all()
    result = swm("eval", TOY, "--image-size", "16", "--episodes", "1", "--min-goal-distance", "1")
    assert result.exit_code == 2 and "--min-goal-distance: requires --from-dataset NAME" in result.output


# -- the generalization report ---------------------------------------------------------------
def test_fov_sweep_reports_each_factor_for_expert_random_and_a_learned_model(swm, home, tmp_path):
    out = tmp_path / "sweep.json"
    policies = f"expert,random,wm:{RUN}"
    args = ("eval", TOY, "--policy", policies, "--fov-sweep", "all", "-n", "2", "--max-steps", "15", *PLAN, *SMALL)
    result = swm(*args, "--json", str(out))
    assert result.exit_code == 0, result.output
    report = json.loads(out.read_text())
    settings = ["in distribution", "agent", "goal", "background", "all factors"]  # the env's factor groups
    assert report["settings"] == settings and list(report["results"]) == ["expert", "random", f"wm:{RUN}"]
    assert report["protocol"]["episodes"] == 2 and report["protocol"]["plan"]["samples"] == 16
    for rows in report["results"].values():
        assert [r["setting"] for r in rows] == settings
        assert [r["variation"] for r in rows] == [[], ["agent"], ["goal"], ["background"], ["all"]]
        base = rows[0]["success_rate"]
        for r in rows:
            assert len(r["episode_successes"]) == 2
            assert r["success_rate"] == pytest.approx(50 * sum(r["episode_successes"]))
            assert r["drop"] == pytest.approx(r["success_rate"] - base)
    assert report["results"]["expert"][0]["success_rate"] == 100.0
    png = out.with_suffix(".png")
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert f"Heatmap: {png}" in result.stdout and "all factors" in result.stdout


@pytest.mark.parametrize(
    ("extra", "needle"),
    [
        (("--fov-sweep", "agnt"), "Did you mean one of 'agent'"),
        (("--fov-sweep", "all", "--variation", "agent"), "cannot be combined"),
        (("--fov-sweep", " , "), "requires 'all' or comma-separated factor names"),
    ],
)
def test_fov_sweep_bad_input_is_one_line(swm, home, error_line, extra, needle):
    result = swm("eval", TOY, "--policy", "expert", "-n", "1", *SMALL, *extra)
    assert result.exit_code != 0
    assert needle in error_line(result)

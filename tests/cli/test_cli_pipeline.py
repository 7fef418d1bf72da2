"""``swm collect``, ``swm eval``, ``swm envs`` and ``swm fovs`` on the toy env."""

from __future__ import annotations

import re

import numpy as np
import pytest

from stable_worldmodel.cli.stats import SuccessSummary, wilson_interval
from stable_worldmodel.data import HDF5Dataset, dataset_info, get_cache_dir, list_datasets
from stable_worldmodel.envs import list_envs

TOY = "swm/Toy-v0"
SMALL = ("--image-size", "16", "--max-steps", "20")


# -- collect -----------------------------------------------------------------------------
def test_collect_records_and_summarizes(swm):
    result = swm("collect", TOY, "--episodes", "3", "--policy", "expert", "--name", "toyset", "--seed", "5", *SMALL)
    assert result.exit_code == 0, result.output
    assert list_datasets() == ["toyset"]
    info = dataset_info("toyset")
    assert info["num_episodes"] == 3 and info["obs_shape"] == (16, 16, 3)
    assert "dataset toyset" in result.stdout  # the summary panel
    assert result.stdout.strip().splitlines()[-1].startswith("Recorded 3 expert episodes of swm/Toy-v0 to ")
    ds = HDF5Dataset("toyset")
    assert ds.lengths.max() <= 21  # at most --max-steps steps (+ the reset frame)


def test_collect_default_name_resume_and_overwrite(swm):
    assert swm("collect", TOY, "-n", "2", *SMALL).exit_code == 0
    assert list_datasets() == ["toy-v0-random"]
    again = swm("collect", TOY, "-n", "3", *SMALL)
    assert again.exit_code == 0 and "holds 2 episodes: recording 1 more to reach 3" in again.stdout
    assert dataset_info("toy-v0-random")["num_episodes"] == 3
    done = swm("collect", TOY, "-n", "3", *SMALL)
    assert done.exit_code == 0 and "nothing to record" in done.stdout and "Recorded 0 random" in done.stdout
    assert dataset_info("toy-v0-random")["num_episodes"] == 3
    fresh = swm("collect", TOY, "-n", "1", "--overwrite", *SMALL)
    assert fresh.exit_code == 0
    assert dataset_info("toy-v0-random")["num_episodes"] == 1


def test_collect_with_variation_records_factor_columns(swm):
    result = swm(
        "collect", TOY, "-n", "2", "--name", "varied", "--variation", "agent.color", "--variation", "goal", *SMALL
    )
    assert result.exit_code == 0, result.output
    names = dataset_info("varied")["variation"]["names"]
    assert "agent.color" in names and "goal.color" in names
    colors = HDF5Dataset("varied").get_col_data("variation.agent.color")
    assert len(np.unique(colors, axis=0)) > 1  # resampled per episode


def test_collect_seed_is_reproducible(swm):
    for name in ("a", "b"):
        assert swm("collect", TOY, "-n", "2", "--name", name, "--seed", "3", *SMALL).exit_code == 0
    a, b = HDF5Dataset("a"), HDF5Dataset("b")
    np.testing.assert_array_equal(a.get_col_data("state"), b.get_col_data("state"))


def _actions(name: str) -> np.ndarray:
    actions = HDF5Dataset(name).get_col_data("action")
    return actions[~np.isnan(actions).any(axis=1)]


def test_collect_expert_adds_seeded_action_noise_where_the_expert_takes_it(swm):
    room = ("swm/TwoRoom-v2", "--policy", "expert", "-n", "4", "--num-envs", "2", *SMALL)
    for name, extra in (("noisy", ()), ("again", ()), ("clean", ("--noise", "0")), ("half", ("--noise", "0.5"))):
        result = swm("collect", *room, "--name", name, "--seed", "1", *extra)
        assert result.exit_code == 0, result.output
    assert "(action noise 1)" in swm("collect", *room, "--name", "n2", "--seed", "2").stdout
    maze = swm(
        "collect", "swm/SimplePointMaze-v0", "--policy", "expert", "-n", "1", "--max-steps", "5", "--image-size", "16"
    )
    assert "(action noise 0.2)" in maze.stdout  # in units of the action bound (+-0.2 there)
    noisy, clean, half = _actions("noisy"), _actions("clean"), _actions("half")
    np.testing.assert_array_equal(noisy, _actions("again"))  # seeded
    distinct = [len(np.unique(np.round(a, 2), axis=0)) / len(a) for a in (clean, half, noisy)]
    assert distinct[0] < 0.5 < distinct[1] and distinct[2] > 0.5  # the clean controller repeats a few commands
    assert all(
        dataset_info(n)["num_episodes"] == 4 for n in ("noisy", "clean", "half")
    )  # the noisy expert still ends its episodes


def test_collect_noise_needs_an_expert_that_takes_it(swm, error_line):
    for args in (("swm/PushT-v1", "--policy", "expert"), (TOY, "--policy", "random")):
        result = swm("collect", *args, "--noise", "0.3", "-n", "1", *SMALL)
        assert result.exit_code == 1
        line = error_line(result)
        assert "--noise requires the expert policy" in line and args[0] in line
    assert list_datasets() == []


def test_collect_with_upstreams_collectors(swm, error_line):
    """Upstream's datasets by name: PushT's WeakPolicy (``--policy weak``, its targets kept within
    ``--dist-constraint`` of the block) and sticky actions (``--repeat-prob``, TwoRoom's
    ``ExpertPolicy(action_noise=2.0, action_repeat_prob=0.05)``)."""
    push = ("swm/PushT-v1", "-n", "2", *SMALL)
    result = swm("collect", *push, "--policy", "weak")
    assert result.exit_code == 0, result.output
    assert "Recorded 2 weak episodes of swm/PushT-v1" in result.stdout
    state, action = HDF5Dataset("pusht-v1-weak").get_col_data("state"), _actions("pusht-v1-weak")
    assert len(action) == 2 * 20 and np.abs(action).max() <= 1.0  # an episode's last row has no action (NaN)
    tight = swm("collect", *push, "--policy", "weak", "--dist-constraint", "1", "--name", "tight")
    assert tight.exit_code == 0 and "(dist constraint 1)" in tight.stdout
    # a target within 1 unit of the block: the agent walks towards it, so it ends nearer than the random walk does
    tight_state = HDF5Dataset("tight").get_col_data("state")
    gap = lambda s: np.linalg.norm(s[:, :2] - s[:, 2:4], axis=1)[-5:].mean()  # noqa: E731
    assert gap(tight_state) < gap(state)
    room = ("swm/TwoRoom-v1", "--policy", "expert", "-n", "2", "--seed", "3", *SMALL)
    sticky = swm("collect", *room, "--noise", "2.0", "--repeat-prob", "0.5", "--name", "sticky")
    assert sticky.exit_code == 0 and "(action noise 2, repeat prob 0.5)" in sticky.stdout, sticky.output
    acts = _actions("sticky")
    repeats = (np.abs(np.diff(acts, axis=0)).max(axis=1) == 0).mean()
    assert 0.3 < repeats < 0.7  # about half the steps repeat the previous action (noise 2 never repeats by itself)
    for args, needle in (
        (("swm/TwoRoom-v1", "--policy", "weak"), "--policy weak requires a PushT environment"),
        (("swm/PushT-v1", "--policy", "random", "--dist-constraint", "5"), "--dist-constraint requires --policy weak"),
    ):
        result = swm("collect", *args, "-n", "1", "--name", "bad", *SMALL)
        assert result.exit_code == 1 and needle in error_line(result)
    assert "bad" not in list_datasets()


@pytest.mark.parametrize(
    ("args", "needles"),
    [
        (("swm/Toyy-v0",), ["'swm/Toyy-v0'", "swm/Toy-v0"]),
        ((TOY, "--policy", "expret"), ["'expret'", "Did you mean 'expert'", "random"]),
        ((TOY, "--variation", "agent.colr"), ["'agent.colr'", "agent.color", "all"]),
        ((TOY, "--name", "a/../../b"), ["'a/../../b'", "would leave the cache folder"]),
    ],
)
def test_collect_bad_input_writes_nothing(swm, error_line, args, needles):
    result = swm("collect", *args, "-n", "1", *SMALL)
    assert result.exit_code == 1
    line = error_line(result)
    for needle in needles:
        assert needle in line
    assert list_datasets() == []


@pytest.mark.parametrize("option", ["--episodes", "--num-envs", "--max-steps", "--image-size", "--seed"])
def test_collect_bad_numbers(swm, error_line, option):
    result = swm("collect", TOY, option, "-7")
    assert result.exit_code == 2
    line = error_line(result)
    assert option in line and "-7" in line


# -- eval --------------------------------------------------------------------------------
def _row(stdout: str, policy: str) -> list[str]:
    line = next(line for line in stdout.splitlines() if line.strip("│ ").startswith(policy))
    return [cell.strip() for cell in line.strip("│").split("│")]


def test_eval_prints_success_table(swm):
    result = swm("eval", TOY, "--policy", "expert", "--episodes", "6", "--num-envs", "2", *SMALL)
    assert result.exit_code == 0, result.output
    policy, episodes, successes, rate, ci, length = _row(result.stdout, "expert")
    assert (episodes, successes, rate) == ("6", "6", "100.0%")
    low, high = wilson_interval(6, 6)
    assert ci == f"[{100 * low:.1f}, {100 * high:.1f}]"
    assert 1 <= float(length) <= 20
    assert "seeds 0..5" in result.stdout


def test_eval_random_matches_world_evaluate(swm):
    from stable_worldmodel.planning.policies import evaluate_policy, make_world

    result = swm("eval", TOY, "--episodes", "5", "--seed", "11", *SMALL)
    assert result.exit_code == 0
    with make_world(TOY, 1, 16, 20, seed=11, verbose=0) as world:
        expected = SuccessSummary.from_results("random", evaluate_policy(world, "random", 5, 11))
    _, episodes, successes, rate, _, length = _row(result.stdout, "random")
    assert int(successes) == expected.successes and rate == f"{100 * expected.rate:.1f}%"
    assert float(length) == pytest.approx(expected.mean_length, abs=0.05)


def test_eval_video(swm, tmp_path):
    out = tmp_path / "videos"
    result = swm("eval", TOY, "-p", "expert", "-n", "2", "--num-envs", "2", "--video", str(out), *SMALL)
    assert result.exit_code == 0, result.output
    videos = sorted(p.name for p in out.glob("*.mp4"))
    assert videos == ["env_0.mp4", "env_1.mp4"]
    assert all((out / v).stat().st_size > 0 for v in videos)


def test_eval_with_variation(swm, error_line):
    assert swm("eval", TOY, "-n", "2", "--variation", "all", *SMALL).exit_code == 0
    result = swm("eval", TOY, "-n", "2", "--variation", "nope", *SMALL)
    assert result.exit_code == 1
    assert "'nope'" in error_line(result)


def test_eval_unknown_env_suggests(swm, error_line):
    result = swm("eval", "TwoRoom")
    assert result.exit_code == 1
    line = error_line(result)
    assert "Did you mean" in line and "'swm/TwoRoom-v2'" in line


# -- envs / fovs ---------------------------------------------------------------------------
def test_envs_lists_every_env_with_factor_count():
    import os
    import subprocess
    import sys

    from stable_worldmodel.planning.policies import variation_space_of

    # in a child process: listing every env builds them all, and Craftax's import would leave JAX's threads in this
    # one, under every later test that forks (DataLoader workers, killed writers)
    env = {**os.environ, "COLUMNS": "200"}
    result = subprocess.run(
        [sys.executable, "-m", "stable_worldmodel", "envs"], capture_output=True, text=True, env=env
    )
    assert result.returncode == 0, result.stderr[-2000:]
    for env_id in list_envs():
        assert env_id in result.stdout
    row = next(line for line in result.stdout.splitlines() if TOY in line)
    assert re.search(rf"│\s+{len(variation_space_of(TOY).names())}\s+│", row)
    assert "toy" in row


def test_envs_marks_envs_whose_extra_is_missing(swm, monkeypatch):
    from stable_worldmodel import _optional

    available = _optional.is_available
    monkeypatch.setattr(_optional, "is_available", lambda m: m != "ogbench" and available(m))
    assert _optional.missing_extra(("continuous", "mujoco")) == "mujoco" and _optional.missing_extra(("toy",)) is None
    result = swm("envs", "--tag", "mujoco")
    assert result.exit_code == 0
    row = next(line for line in result.stdout.splitlines() if "swm/CartpoleDMControl-v0" in line)
    assert "n/a: pip install" in row  # the env is not even built: nothing to import


def test_envs_tag_filter(swm, error_line):
    result = swm("envs", "--tag", "toy")
    assert result.exit_code == 0
    assert TOY in result.stdout and "swm/PushT-v1" not in result.stdout
    bad = swm("envs", "--tag", "papr")
    assert bad.exit_code == 1
    assert "Did you mean 'paper'" in error_line(bad)


def test_fovs_tree(swm):
    result = swm("fovs", TOY)
    assert result.exit_code == 0
    out = result.stdout
    assert "swm/Toy-v0: 5 factors of variation" in out
    assert re.search(r"speed\s+Box \[0\.02, 0\.1\] default 0\.05", out)
    assert re.search(r"color\s+RGBBox \[0, 255\] \(3,\)", out)


def test_fovs_shows_one_range_for_uniform_bounds(swm):
    out = swm("fovs", "swm/TwoRoom-v1").stdout
    assert re.search(r"radius\s+Box \[7, 14\] \(1,\)", out)  # not [[7], [14]]
    assert re.search(r"size\s+MultiDiscrete \[1, 21\] \(3,\)", out)  # start .. start + nvec - 1


def test_fovs_unknown_env(swm, error_line):
    result = swm("fovs", "swm/Tooy-v0")
    assert result.exit_code == 1
    assert "swm/Toy-v0" in error_line(result)


def test_no_cache_written_by_read_only_commands(swm):
    for args in (("envs", "--tag", "toy"), ("fovs", TOY), ("list", "world")):
        assert swm(*args).exit_code == 0
    assert not any(get_cache_dir().glob("*.h5"))


def test_default_episode_limit_comes_from_the_registry(swm, monkeypatch):
    import dataclasses

    from stable_worldmodel.envs import _registry

    short = dataclasses.replace(_registry.get_entry(TOY), max_episode_steps=7)
    monkeypatch.setitem(_registry._ENTRIES, TOY, short)
    result = swm("eval", TOY, "-n", "2", "--image-size", "16")
    assert result.exit_code == 0, result.output
    assert "at most 7 steps" in result.stdout
    assert float(_row(result.stdout, "random")[-1]) <= 7
    assert "at most 9 steps" in swm("eval", TOY, "-n", "1", "--image-size", "16", "--max-steps", "9").stdout

"""``swm eval --policy wm:RUN`` where the run does not fit: another image size or action dimension
is a :class:`RunMismatchError` naming both values and the fix; another env id of the same actions
and frames is one warning line (``--force`` silences it); another frameskip is a RunMismatchError
of ``world_model_policy``; a partial run (killed before its last step) says which checkpoint it uses.

One module fixture records a 16x16 toy dataset and trains a tiny LeWM for two steps; each test
copies that cache into its own ``STABLEWM_HOME``.
"""

from __future__ import annotations

import json
import shutil

import pytest

from stable_worldmodel.errors import RunMismatchError

TOY = "swm/Toy-v0"
OTHER = "swm/TwoRoom-v2"  # 2-dim actions too
WIDE = "swm/ImagePositioning-v1"  # 9-dim actions
RUN = "toy-lewm"
TINY = {
    "image_size": 16,
    "embed_dim": 16,
    "cnn_width": 8,
    "depth": 1,
    "heads": 2,
    "dim_head": 8,
    "mlp_dim": 32,
    "projector_hidden": 32,
    "sigreg_num_proj": 32,
    "batch_size": 8,
    "frameskip": 1,
}
#: one short episode, planned on the CPU with a small plan and no subgoal graph
FAST = (
    "--episodes",
    "1",
    "--max-steps",
    "2",
    "--device",
    "cpu",
    "--samples",
    "4",
    "--iterations",
    "1",
    "--horizon",
    "2",
    "--subgoals",
    "none",
)


@pytest.fixture(scope="module")
def template(tmp_path_factory):
    """A cache holding dataset ``toy`` (4 expert episodes at 16x16) and checkpoint ``toy-lewm``."""
    from stable_worldmodel import World
    from stable_worldmodel.envs import expert_policy
    from stable_worldmodel.train import train

    root = tmp_path_factory.mktemp("stablewm_run_mismatch")
    with World(TOY, 1, (16, 16), max_episode_steps=12, verbose=0, vectorization_mode="sync") as world:
        world.set_policy(expert_policy(TOY))
        world.record_dataset("toy", episodes=4, seed=0, cache_dir=root)
    train("lewm", "toy", "tiny", steps=2, name=RUN, seed=0, device="cpu", progress=False, cache_dir=str(root), **TINY)
    return root


@pytest.fixture
def home(template, _stablewm_home, one_torch_thread):
    shutil.copytree(template, _stablewm_home, dirs_exist_ok=True)
    return _stablewm_home


def edit_protocol(home, **changes) -> dict:
    """Set (a value) or drop (``None`` given as ``...``) keys of the run's protocol.json."""
    path = home / "checkpoints" / RUN / "protocol.json"
    record = json.loads(path.read_text())
    for key, value in changes.items():
        if value is ...:
            record.pop(key, None)
        else:
            record[key] = value
    path.write_text(json.dumps(record))
    return record


def warnings(result) -> list[str]:
    return [line for line in result.stderr.splitlines() if line.startswith("Warning:")]


@pytest.fixture
def no_world(monkeypatch):
    """Fail if a World starts: the checks come first."""
    from stable_worldmodel.world import World

    def refuse(self, *args, **kwargs):
        raise AssertionError("a World was started before the run was checked")

    monkeypatch.setattr(World, "__init__", refuse)


# -- image size ------------------------------------------------------------------------------
def test_another_image_size_is_one_error_line_naming_both_and_the_fix(swm, home, error_line, no_world):
    result = swm("eval", TOY, "--policy", f"wm:{RUN}", "--image-size", "32", *FAST)
    assert result.exit_code == 1
    line = error_line(result)
    for needle in (
        f"wm:{RUN} requires --image-size 16",
        "16x16 frames",
        "got --image-size 32",
        "drop --image-size",
        "--force",
    ):
        assert needle in line, line


def test_image_size_defaults_to_the_runs_and_force_evaluates_at_another(swm, home, tmp_path):
    out = tmp_path / "out.json"
    result = swm("eval", TOY, "--policy", f"wm:{RUN}", *FAST, "--json", str(out))
    assert result.exit_code == 0, result.output
    assert json.loads(out.read_text())["image_size"] == 16 and not warnings(result)
    result = swm("eval", TOY, "--policy", f"wm:{RUN}", "--image-size", "32", "--force", *FAST, "--json", str(out))
    assert result.exit_code == 0, result.output
    assert json.loads(out.read_text())["image_size"] == 32 and not warnings(result)


# -- action dimension ------------------------------------------------------------------------
def test_another_action_dimension_is_one_error_line_even_with_force(swm, home, error_line, no_world):
    for extra in ((), ("--force",)):
        result = swm("eval", WIDE, "--policy", f"wm:{RUN}", "--image-size", "16", *FAST, *extra)
        assert result.exit_code == 1
        line = error_line(result)
        for needle in (
            "requires an env with 2-dim actions",
            f"got {WIDE} with 9-dim actions",
            "dataset 'toy'",
            "swm collect",
        ):
            assert needle in line, line


def test_a_sweep_file_checks_each_env_and_run_before_evaluating(swm, home, tmp_path, error_line, no_world):
    (tmp_path / "s.yaml").write_text(f"envs: [{TOY}, {WIDE}]\npolicies: [expert, wm:{RUN}]\nepisodes: 1\n")
    result = swm("sweep", str(tmp_path / "s.yaml"))
    assert result.exit_code == 1
    assert f"got {WIDE} with 9-dim actions" in error_line(result)
    (tmp_path / "s.yaml").write_text(f"envs: [{TOY}]\npolicies: [wm:{RUN}]\nimage_size: 32\n")
    line = error_line(swm("sweep", str(tmp_path / "s.yaml")))
    assert "requires image_size: 16" in line and "got image_size: 32" in line, line


def test_the_mismatch_is_a_typed_run_mismatch_error(home):
    from stable_worldmodel.cli.worlds import check_run_fits

    with pytest.raises(RunMismatchError, match="2-dim actions") as info:
        check_run_fits(f"wm:{RUN}", WIDE, 16)
    assert isinstance(info.value, ValueError)  # a ConfigError
    with pytest.raises(RunMismatchError, match="--image-size 16"):
        check_run_fits(f"wm:{RUN}", TOY, 64)
    check_run_fits(f"wm:{RUN}", TOY, 16)  # its own env and size


# -- env id: planning runs, one warning line -------------------------------------------------
def test_another_env_with_the_same_actions_and_frames_is_one_warning_that_force_silences(swm, home):
    edit_protocol(home, env=TOY)
    result = swm("eval", OTHER, "--policy", f"wm:{RUN}", *FAST)
    assert result.exit_code == 0, result.output
    (line,) = warnings(result)
    for needle in (f"trained on {TOY}", f"got {OTHER}", "2-dim actions and 16x16 frames", "--force"):
        assert needle in line, line
    assert "Traceback" not in result.output

    quiet = swm("eval", OTHER, "--policy", f"wm:{RUN}", *FAST, "--force")
    assert quiet.exit_code == 0, quiet.output
    assert not warnings(quiet)
    own = swm("eval", TOY, "--policy", f"wm:{RUN}", *FAST)  # its own env: nothing to say
    assert own.exit_code == 0 and not warnings(own)


def test_the_env_of_a_dataset_recorded_on_ray_is_read_from_its_manifest(tmp_path):
    from stable_worldmodel.planning.run_fit import RunFacts, check_run_fits

    (tmp_path / "manifest.json").write_text(json.dumps({"env": TOY, "episodes": 4}))
    facts = RunFacts.from_protocol(
        "r",
        {
            "dataset": "toy",
            "dataset_path": str(tmp_path),
            "action_dim": 2,
            "dataset_image_shape": [16, 16, 3],
            "image_size": 16,
            "frameskip": 1,
        },
    )
    assert facts.env == TOY and facts.frame_size == (16, 16)
    (line,) = check_run_fits(facts, "wm:r", env_id=OTHER, action_dim=2, image_size=16)
    assert TOY in line and OTHER in line
    assert check_run_fits(facts, "wm:r", env_id=OTHER, action_dim=2, image_size=16, force=True) == []


# -- frameskip -------------------------------------------------------------------------------
def test_world_model_policy_with_another_frameskip_is_a_run_mismatch_error(home):
    from stable_worldmodel.planning.learned import PlanSettings, world_model_policy

    settings = PlanSettings(samples=4, iterations=1, horizon=2, subgoals="none")
    with pytest.raises(RunMismatchError, match=r"requires frameskip=1 .* got frameskip=2; drop frameskip"):
        world_model_policy(RUN, settings, device="cpu", frameskip=2)
    _, protocol = world_model_policy(RUN, settings, device="cpu", frameskip=1)
    assert protocol["action_block"] == 1


# -- a partial run ---------------------------------------------------------------------------
@pytest.mark.parametrize("final", [None, ...], ids=["final-null", "final-absent"])
def test_a_partial_run_says_which_checkpoint_it_uses(swm, home, final):
    edit_protocol(home, final=final, steps_done=1, steps=2)
    result = swm("eval", TOY, "--policy", f"wm:{RUN}", *FAST)
    assert result.exit_code == 0, result.output
    (line,) = warnings(result)
    assert f"wm:{RUN} uses the checkpoint of step 1 of 2 (partial run" in line


@pytest.mark.parametrize("leaf", ["step_000001", "best"])
def test_a_snapshot_kept_during_training_is_not_called_a_partial_run(leaf):
    from stable_worldmodel.planning.run_fit import partial_note

    protocol = {"final": None, "steps_done": 1, "steps": 2}
    note = partial_note(f"wm:{RUN}/{leaf}", protocol)
    assert note == f"wm:{RUN}/{leaf} is a checkpoint kept while {RUN} trained: step 1 of 2"
    assert "--resume" in partial_note(f"wm:{RUN}", protocol)


def test_partial_run_needs_fewer_steps_done_than_steps():
    from stable_worldmodel.planning.run_fit import partial_run

    assert partial_run({"final": None, "steps_done": 3, "steps": 10}) == (3, 10)
    assert partial_run({"steps_done": 3, "steps": 10}) == (3, 10)
    assert partial_run({"final": {"train_loss": 0.1}, "steps_done": 10, "steps": 10}) is None
    assert partial_run({"final": None, "steps_done": 10, "steps": 10}) is None
    assert partial_run({}) is None  # an upstream checkpoint: nothing recorded

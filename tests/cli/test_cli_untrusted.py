"""The commands that load a run never run the code its ``config.json`` carries (issue 26):
``swm eval --policy wm:RUN`` / ``gc:RUN`` and ``swm train frame --from RUN`` stop with one
``Error:`` line naming the file, the key and the target, and create nothing."""

from __future__ import annotations

import json
import shutil

import pytest
from _nets import TINY_JEPA

TOY = "swm/Toy-v0"
TINY = dict(TINY_JEPA, sigreg_num_proj=16, batch_size=8, history_size=1)


@pytest.fixture(scope="module")
def template(tmp_path_factory):
    """A cache with dataset ``toy`` and a 2-step LeWM run ``good``."""
    from stable_worldmodel import World
    from stable_worldmodel.envs import expert_policy
    from stable_worldmodel.train import train

    root = tmp_path_factory.mktemp("stablewm_untrusted")
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("STABLEWM_HOME", str(root))
        with World(TOY, 1, (16, 16), max_episode_steps=20, verbose=0) as world:
            world.set_policy(expert_policy(TOY))
            world.record_dataset("toy", episodes=4, seed=0, cache_dir=root)
        train(
            "lewm",
            "toy",
            "tiny",
            steps=2,
            name="good",
            seed=0,
            device="cpu",
            progress=False,
            cache_dir=str(root),
            **TINY,
        )
    return root


@pytest.fixture
def evil(template, _stablewm_home, tmp_path):
    """Run ``evil``: run ``good`` whose config.json has ``os.system`` nested in its predictor;
    returns the marker path."""
    shutil.copytree(template, _stablewm_home, dirs_exist_ok=True)
    folder = _stablewm_home / "checkpoints" / "evil"
    shutil.copytree(_stablewm_home / "checkpoints" / "good", folder)
    marker = tmp_path / "PWNED"
    tree = json.loads((folder / "config.json").read_text())
    tree["predictor"]["payload"] = {"_target_": "os.system", "_args_": [f"touch {marker}"]}
    (folder / "config.json").write_text(json.dumps(tree))
    yield marker
    assert not marker.exists(), "a command ran the code a checkpoint carries"


@pytest.mark.parametrize(
    "args",
    [
        (
            "eval",
            TOY,
            "--policy",
            "wm:evil",
            "--episodes",
            "1",
            "--max-steps",
            "2",
            "--device",
            "cpu",
            "--image-size",
            "16",
        ),
        (
            "eval",
            TOY,
            "--policy",
            "gc:evil",
            "--episodes",
            "1",
            "--max-steps",
            "2",
            "--device",
            "cpu",
            "--image-size",
            "16",
        ),
        ("train", "frame", "--from", "evil", "--steps", "1", "--device", "cpu"),
    ],
    ids=["eval wm", "eval gc", "train frame"],
)
def test_commands_refuse_a_hostile_run(swm, evil, error_line, args, _stablewm_home):
    result = swm(*args)
    assert result.exit_code != 0
    line = error_line(result)
    assert "'os.system'" in line and "predictor.payload" in line, line
    assert str(_stablewm_home / "checkpoints" / "evil" / "config.json") in line
    assert "STABLEWM_TRUSTED_TARGETS" in line


def test_swm_eval_opens_a_run_once(swm, template, _stablewm_home, monkeypatch):
    """One ``swm eval --policy wm:RUN``: protocol.json parsed once, config and weights read once."""
    from stable_worldmodel.wm import run as run_module
    from stable_worldmodel.wm import utils as wmu

    shutil.copytree(template, _stablewm_home, dirs_exist_ok=True)
    run_module._OPENED.clear()
    reads, loads = [], []
    read_json, load = wmu._read_json, wmu.load_checkpoint
    monkeypatch.setattr(wmu, "_read_json", lambda *a: reads.append(a[0].name) or read_json(*a))
    monkeypatch.setattr(wmu, "load_checkpoint", lambda *a, **k: loads.append(a[0]) or load(*a, **k))
    result = swm(
        "eval",
        TOY,
        "--policy",
        "wm:good",
        "--episodes",
        "2",
        "--max-steps",
        "3",
        "--device",
        "cpu",
        "--solver",
        "random",
        "--samples",
        "4",
        "--horizon",
        "2",
        "--subgoals",
        "none",
    )
    assert result.exit_code == 0, result.output
    assert reads.count("protocol.json") == 1 and reads.count("config.json") == 1 and len(loads) == 1

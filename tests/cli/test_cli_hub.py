"""``swm push RUN REPO_ID`` (against a fake Hub: nothing leaves the machine) and
``swm eval ENV --policy wm:USER/REPO`` read from the Hugging Face cache layout, offline."""

from __future__ import annotations

import json
import shutil
import sys

import pytest

TOY = "swm/Toy-v0"
COMMIT = "c3" * 20
#: what planning on swm/Toy-v0 at 16x16 needs to know of the run
PROTOCOL = {
    "version": 1,
    "model": "lewm",
    "preset": "tiny",
    "env": TOY,
    "image_size": 16,
    "image_mean": [0.5] * 3,
    "image_std": [0.5] * 3,
    "action_dim": 2,
    "frameskip": 1,
    "history_size": 2,
    "dataset_image_shape": [16, 16, 3],
    "normalizers": {},
}
TINY = dict(
    image_size=16, embed_dim=8, cnn_width=8, depth=1, heads=2, dim_head=4, mlp_dim=16, projector_hidden=16, frameskip=1
)


def write_run(folder) -> None:
    """A tiny LeWM for swm/Toy-v0 in ``folder``, with a train_state.ckpt beside it (never uploaded)."""
    import torch

    import stable_worldmodel.wm as wm
    from stable_worldmodel.wm.utils import instantiate, write_checkpoint

    torch.manual_seed(0)
    tree = wm.get_config("lewm", "tiny", history_size=2, **TINY).target_tree(2)
    write_checkpoint(instantiate(tree), folder, tree, PROTOCOL)
    torch.save({"step": 1}, folder / "train_state.ckpt")


@pytest.fixture
def run(_stablewm_home):
    write_run(_stablewm_home / "checkpoints" / "r")
    return "r"


@pytest.fixture
def uploads(monkeypatch):
    """A fake Hub: ``uploads`` lists, per call, the repo, the options and the files sent."""
    import huggingface_hub
    from huggingface_hub import CommitInfo

    sent: list[dict] = []
    created: dict[str, bool] = {}

    def create_repo(api, repo_id, *, private=None, exist_ok=False, **kwargs):
        created[repo_id] = private

    def create_branch(api, repo_id, *, branch, exist_ok=False, **kwargs):
        sent.append({"branch": branch})

    def upload_folder(api, *, repo_id, folder_path, commit_message=None, revision=None, **kwargs):
        from pathlib import Path

        files = sorted(p.relative_to(folder_path).as_posix() for p in Path(folder_path).rglob("*") if p.is_file())
        sent.append(
            {
                "repo": repo_id,
                "private": created[repo_id],
                "revision": revision,
                "message": commit_message,
                "files": files,
            }
        )
        return CommitInfo(
            commit_url=f"https://huggingface.co/{repo_id}/commit/{'f' * 40}",
            commit_message=commit_message,
            commit_description="",
            oid="f" * 40,
        )

    monkeypatch.setattr(huggingface_hub.HfApi, "create_repo", create_repo)
    monkeypatch.setattr(huggingface_hub.HfApi, "create_branch", create_branch)
    monkeypatch.setattr(huggingface_hub.HfApi, "upload_folder", upload_folder)
    return sent


def test_push_prints_the_commit_url(swm, run, uploads):
    result = swm("push", run, "u/r")
    assert result.exit_code == 0, result.output
    assert f"https://huggingface.co/u/r/commit/{'f' * 40}" in result.stdout
    assert uploads == [
        {
            "repo": "u/r",
            "private": False,
            "revision": None,
            "message": "Upload r with stable-worldmodel",
            "files": ["README.md", "config.json", "protocol.json", "weights.pt"],
        }
    ]


def test_push_options_and_cache_dir(swm, uploads, tmp_path):
    write_run(tmp_path / "other" / "checkpoints" / "mine")
    args = ("push", "wm:mine", "me/mine", "--private", "--revision", "dev", "-m", "first", "--cache-dir")
    result = swm(*args, str(tmp_path / "other"))
    assert result.exit_code == 0, result.output
    assert uploads[0] == {"branch": "dev"}
    assert uploads[1]["private"] is True and uploads[1]["revision"] == "dev" and uploads[1]["message"] == "first"


@pytest.mark.parametrize(
    ("args", "expected"),
    [
        (("r", "not-a-repo"), "Error: push_to_hub requires a Hub repo id '<user>/<repo>'"),
        (("rr", "u/r"), "Did you mean 'r'?"),
        (("r", "u/r", "--revision", ".."), "requires a revision"),
    ],
)
def test_push_mistakes_are_one_error_line(swm, run, uploads, error_line, args, expected):
    result = swm("push", *args)
    assert result.exit_code == 1
    assert expected in error_line(result)
    assert uploads == []


def test_push_without_huggingface_hub_names_the_extra(swm, run, error_line, monkeypatch):
    monkeypatch.setitem(sys.modules, "huggingface_hub", None)
    result = swm("push", run, "u/r")
    assert result.exit_code == 1
    assert 'pip install "stable-worldmodel[hub]"' in error_line(result)


def test_push_offline_is_one_error_line(swm, run, error_line, monkeypatch):
    import huggingface_hub
    from huggingface_hub.errors import OfflineModeIsEnabled

    def offline(*args, **kwargs):
        raise OfflineModeIsEnabled("offline mode is enabled")

    monkeypatch.setattr(huggingface_hub.HfApi, "create_repo", offline)
    result = swm("push", run, "u/r")
    assert result.exit_code == 1
    assert "could not push 'r' to 'u/r'" in error_line(result)


@pytest.fixture
def hf(tmp_path, monkeypatch, _stablewm_home):
    """Run ``u/r`` only in the Hugging Face cache (``$HF_HUB_CACHE``, offline); returns its snapshot."""
    cache = tmp_path / "hf"
    monkeypatch.setenv("HF_HUB_CACHE", str(cache))
    monkeypatch.setenv("HF_HUB_OFFLINE", "1")
    write_run(tmp_path / "src")
    snapshot = cache / "models--u--r" / "snapshots" / COMMIT
    snapshot.mkdir(parents=True)
    for name in ("weights.pt", "config.json", "protocol.json"):
        shutil.copy(tmp_path / "src" / name, snapshot / name)
    (cache / "models--u--r" / "refs").mkdir()
    (cache / "models--u--r" / "refs" / "main").write_text(COMMIT)
    return snapshot


PLAN = ("--solver", "cem", "--samples", "4", "--iterations", "1", "--horizon", "2", "--subgoals", "none")
SMALL = ("--episodes", "1", "--max-steps", "3", "--device", "cpu", "--image-size", "16")


def test_eval_plans_with_a_run_from_the_hf_cache(swm, hf, tmp_path):
    out = tmp_path / "out.json"
    result = swm("eval", TOY, "--policy", "wm:u/r", *PLAN, *SMALL, "--json", str(out))
    assert result.exit_code == 0, result.output
    record = json.loads(out.read_text())
    assert json.dumps(record).count(str(hf.resolve())) >= 1  # the snapshot it planned with


def test_eval_with_a_missing_hub_run_names_both_places(swm, hf, error_line, _stablewm_home):
    result = swm("eval", TOY, "--policy", "wm:nobody/nothing", *SMALL)
    assert result.exit_code == 1
    line = error_line(result)
    assert str(_stablewm_home / "checkpoints" / "models--nobody--nothing") in line
    assert str(hf.parent.parent.parent / "models--nobody--nothing") in line

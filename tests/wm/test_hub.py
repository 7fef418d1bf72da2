"""The Hugging Face Hub (issue 32 item 5): ``<user>/<repo>[@<revision>]`` read from the Hugging Face
cache layout offline (after our own cache), ``push_to_hub`` and ``from_pretrained``.

No network: the Hugging Face cache is laid out by hand in ``tmp_path`` (``refs/<revision>`` naming a
commit, ``snapshots/<commit>/`` files linked into ``blobs/``, as huggingface_hub writes it), and the
Hub itself is a folder of ``tmp_path`` that fakes of ``HfApi.create_repo`` / ``create_branch`` /
``upload_folder`` and ``snapshot_download`` copy into and out of.
"""

from __future__ import annotations

import fnmatch
import hashlib
import json
import os
import shutil
import sys
from pathlib import Path

import pytest
import torch
from _tiny import ACTION_DIM, TINY, condition_on_actions, images, randn

import stable_worldmodel.wm as wm
from stable_worldmodel import keys
from stable_worldmodel.errors import (
    CheckpointError,
    ConfigError,
    DependencyNotInstalled,
    UnknownNameError,
    UntrustedCheckpointError,
)
from stable_worldmodel.planning import AutoCostModel
from stable_worldmodel.wm.run import Run
from stable_worldmodel.wm.utils import (
    from_pretrained,
    hf_hub_cache,
    instantiate,
    load_pretrained,
    push_to_hub,
    resolve_checkpoint,
    write_checkpoint,
)

MAIN, OTHER = "a1" * 20, "b2" * 20  # two commits (40 hex digits)
#: a protocol as swm train writes it, with what only makes sense on the machine that trained it
PROTOCOL = {
    "version": 1,
    "model": "lewm",
    "preset": "tiny",
    "dataset": "toy",
    "env": "swm/Toy-v0",
    "image_size": 16,
    "image_mean": [0.5] * 3,
    "image_std": [0.5] * 3,
    "action_dim": ACTION_DIM,
    "frameskip": 1,
    "history_size": 2,
    "steps": 4,
    "steps_done": 4,
    "final": {"train_loss": 0.25, "val_loss": 0.5},
    "normalizers": {},
    "dataset_path": "/home/alice/private/toy.h5",
    "provenance": {"host": "alice-laptop", "command": "swm train lewm --dataset toy", "versions": {"torch": "2"}},
}
UPLOADABLE = {"weights.pt", "config.json", "protocol.json", "README.md"}


def tree() -> dict:
    return wm.get_config("lewm", "tiny", **TINY).target_tree(ACTION_DIM)


def build(seed: int = 0) -> torch.nn.Module:
    """A tiny LeWM with trained-looking state (AdaLN modulations, BatchNorm statistics)."""
    torch.manual_seed(seed)
    model = condition_on_actions(instantiate(tree()), seed=seed)
    with torch.no_grad():
        model.train().encode({keys.PIXELS: images(4, 2, seed=seed)})
    return model.eval()


def outputs(model: torch.nn.Module) -> torch.Tensor:
    """Costs of fixed candidates: they go through every module."""
    info = {keys.PIXELS: images(2, 3, 1, seed=7), keys.GOAL: images(2, 3, 1, seed=8)}
    with torch.no_grad():
        return model.get_cost(info, randn(2, 3, 2, ACTION_DIM, seed=9))


def write_run(folder: Path, seed: int = 0, config: dict | None = None) -> torch.nn.Module:
    """A run folder as swm train leaves it: the model files plus what must never be uploaded."""
    model = build(seed)
    write_checkpoint(model, folder, config if config is not None else tree(), PROTOCOL)
    torch.save({"optimizer": {"lr": torch.tensor(1.0)}, "step": 4}, folder / "train_state.ckpt")
    write_checkpoint(model, folder / "step_2", tree())
    (folder / "old_object.ckpt").write_bytes(b"a pickle")
    (folder / "metrics.jsonl").write_text('{"step": 1}\n')
    return model


def lay_out(cache: Path, repo_id: str, source: Path, commit: str, refs=("main",), links: bool = True) -> Path:
    """``source``'s top-level files as snapshot ``commit`` of ``repo_id`` in the Hugging Face cache ``cache``."""
    repo = cache / f"models--{repo_id.replace('/', '--')}"
    snapshot = repo / "snapshots" / commit
    snapshot.mkdir(parents=True, exist_ok=True)
    for file in sorted(p for p in source.iterdir() if p.is_file()):
        data = file.read_bytes()
        if links:  # as huggingface_hub: the snapshot links into blobs/<sha256>
            blob = repo / "blobs" / hashlib.sha256(data).hexdigest()
            blob.parent.mkdir(parents=True, exist_ok=True)
            blob.write_bytes(data)
            (snapshot / file.name).symlink_to(os.path.relpath(blob, snapshot))
        else:  # as on a file system without links: copies
            (snapshot / file.name).write_bytes(data)
    for ref in refs:
        (repo / "refs" / ref).parent.mkdir(parents=True, exist_ok=True)
        (repo / "refs" / ref).write_text(commit)
    return snapshot


def model_files(folder: Path) -> Path:
    """A folder of only the model files of run ``folder`` (what a Hub repo holds)."""
    out = folder.parent / f"{folder.name}-files"
    out.mkdir()
    for name in ("weights.pt", "config.json", "protocol.json"):
        shutil.copy(folder / name, out / name)
    return out


@pytest.fixture
def hf(tmp_path, monkeypatch) -> Path:
    """An empty Hugging Face cache (``$HF_HUB_CACHE``), offline."""
    cache = tmp_path / "hf" / "hub"
    monkeypatch.setenv("HF_HUB_CACHE", str(cache))
    monkeypatch.setenv("HF_HUB_OFFLINE", "1")
    return cache


@pytest.fixture
def published(hf, tmp_path):
    """``u/r`` in the Hugging Face cache only (refs/main -> MAIN); returns (model, snapshot)."""
    run = tmp_path / "published"
    model = write_run(run)
    return model, lay_out(hf, "u/r", model_files(run), MAIN)


# -- reading the Hugging Face cache ---------------------------------------------------------------
@pytest.mark.parametrize("links", [True, False], ids=["blob-links", "copies"])
def test_load_pretrained_reads_the_hf_cache_layout(hf, tmp_path, links):
    run = tmp_path / "run"
    model = write_run(run)
    snapshot = lay_out(hf, "u/r", model_files(run), MAIN, links=links)
    assert resolve_checkpoint("u/r") == snapshot / "weights.pt"
    loaded = load_pretrained("u/r")
    assert torch.equal(outputs(loaded), outputs(model))
    assert torch.equal(outputs(loaded), outputs(load_pretrained(run)))  # same as loading the folder directly


def test_auto_cost_model_and_run_open_read_the_hf_cache(published):
    model, snapshot = published
    expected = outputs(model)
    assert torch.equal(outputs(AutoCostModel("u/r")), expected)
    run = Run.open("wm:u/r")
    assert run.folder == snapshot.resolve() and run.weights.name == "weights.pt"  # the link, not its blob
    assert run.protocol.env == "swm/Toy-v0" and run.protocol.weights_sha256  # protocol.json beside the link
    assert run.policy_name == "wm:u/r"
    assert torch.equal(outputs(run.load_model()), expected)


def test_a_damaged_blob_is_caught_by_the_recorded_sha256(published):
    _, snapshot = published
    blob = (snapshot / "weights.pt").resolve()
    data = bytearray(blob.read_bytes())
    data[len(data) // 2] ^= 0xFF
    blob.write_bytes(bytes(data))
    with pytest.raises(CheckpointError, match="damaged"):
        load_pretrained("u/r")


def test_a_revision_is_pinned_with_at(hf, tmp_path):
    first, second = tmp_path / "first", tmp_path / "second"
    model_main, model_v2 = write_run(first, seed=0), write_run(second, seed=1)
    lay_out(hf, "u/r", model_files(first), MAIN, refs=("main",))
    lay_out(hf, "u/r", model_files(second), OTHER, refs=("v2", "refs/pr/1"))
    expected_main, expected_v2 = outputs(model_main), outputs(model_v2)
    assert not torch.equal(expected_main, expected_v2)
    assert torch.equal(outputs(load_pretrained("u/r")), expected_main)  # refs/main
    assert torch.equal(outputs(load_pretrained("u/r@main")), expected_main)
    assert torch.equal(outputs(load_pretrained("u/r@v2")), expected_v2)  # a tag or branch
    assert torch.equal(outputs(load_pretrained("u/r@refs/pr/1")), expected_v2)  # a PR ref
    assert torch.equal(outputs(load_pretrained(f"u/r@{OTHER}")), expected_v2)  # a commit
    assert torch.equal(outputs(AutoCostModel("u/r@v2")), expected_v2)
    assert Run.open("wm:u/r@v2").folder.name == OTHER
    with pytest.raises(FileNotFoundError, match="refs/nope") as err:
        load_pretrained("u/r@nope")
    assert "refs: main, refs/pr/1, v2" in str(err.value) and "--revision nope" in str(err.value)


@pytest.mark.parametrize("name", ["u/r@", "u/r@../../x", "u/r@a//b", "u/r@ main"])
def test_a_bad_revision_is_a_config_error_naming_it(hf, name):
    with pytest.raises(ConfigError, match="requires a revision") as err:
        load_pretrained(name)
    assert repr(name) in str(err.value)


def test_our_cache_wins_over_the_hf_cache(published, _stablewm_home):
    _, snapshot = published
    ours = build(seed=3)
    write_checkpoint(ours, _stablewm_home / "checkpoints" / "models--u--r", tree())
    assert torch.equal(outputs(load_pretrained("u/r")), outputs(ours))
    assert torch.equal(outputs(AutoCostModel("u/r")), outputs(ours))
    assert Run.open("wm:u/r").folder == (_stablewm_home / "checkpoints" / "models--u--r").resolve()
    # a pinned revision is the Hugging Face cache's: our flat folder holds none
    assert resolve_checkpoint("u/r@main") == snapshot / "weights.pt"


def test_the_not_found_message_names_both_places_and_how_to_get_the_files(hf, _stablewm_home):
    with pytest.raises(FileNotFoundError) as err:
        load_pretrained("nobody/nothing")
    text = str(err.value)
    assert str(_stablewm_home / "checkpoints" / "models--nobody--nothing") in text  # ours
    assert str(hf / "models--nobody--nothing" / "snapshots") in text  # the Hugging Face cache
    assert "from_pretrained('nobody/nothing')" in text and "hf download nobody/nothing" in text
    assert "nothing is downloaded" in text
    with pytest.raises(FileNotFoundError, match="models--nobody--nothing"):
        Run.open("wm:nobody/nothing")
    with pytest.raises(UnknownNameError, match="Hugging Face cache") as err:
        AutoCostModel("nobody/nothing")
    assert str(hf) in str(err.value)


def test_the_hf_cache_is_found_where_huggingface_hub_looks(tmp_path, monkeypatch):
    for var in ("HF_HUB_CACHE", "HUGGINGFACE_HUB_CACHE", "HF_HOME", "XDG_CACHE_HOME"):
        monkeypatch.delenv(var, raising=False)
    monkeypatch.setenv("HOME", str(tmp_path / "home"))
    assert hf_hub_cache() == tmp_path / "home" / ".cache" / "huggingface" / "hub"
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    assert hf_hub_cache() == tmp_path / "xdg" / "huggingface" / "hub"
    monkeypatch.setenv("HF_HOME", str(tmp_path / "hfhome"))
    assert hf_hub_cache() == tmp_path / "hfhome" / "hub"
    monkeypatch.setenv("HUGGINGFACE_HUB_CACHE", str(tmp_path / "legacy"))
    assert hf_hub_cache() == tmp_path / "legacy"
    monkeypatch.setenv("HF_HUB_CACHE", "~/hubcache")
    assert hf_hub_cache() == tmp_path / "home" / "hubcache"
    run = tmp_path / "run"
    model = write_run(run)
    lay_out(tmp_path / "home" / "hubcache", "u/r", model_files(run), MAIN)
    assert torch.equal(outputs(load_pretrained("u/r")), outputs(model))


def test_the_hf_cache_is_read_without_huggingface_hub(published, monkeypatch):
    model, _ = published
    monkeypatch.setitem(sys.modules, "huggingface_hub", None)  # `import huggingface_hub` fails
    assert torch.equal(outputs(load_pretrained("u/r")), outputs(model))
    with pytest.raises(FileNotFoundError, match=r"stable-worldmodel\[hub\]"):
        load_pretrained("nobody/nothing")
    for call in (lambda: from_pretrained("u/r"), lambda: push_to_hub("r", "u/r")):
        with pytest.raises(DependencyNotInstalled, match=r"pip install \"stable-worldmodel\[hub\]\""):
            call()


def test_from_pretrained_offline_uses_the_real_snapshot_download_on_the_cache(published):
    model, _ = published  # HF_HUB_OFFLINE=1: huggingface_hub's own snapshot_download, no network
    assert torch.equal(outputs(from_pretrained("u/r")), outputs(model))
    assert torch.equal(outputs(from_pretrained("u/r", local_files_only=True, revision="main")), outputs(model))
    with pytest.raises(FileNotFoundError, match="HF_HUB_OFFLINE is set") as err:
        from_pretrained("nobody/nothing")
    assert "models--nobody--nothing" in str(err.value) and "hf download nobody/nothing" in str(err.value)
    with pytest.raises(FileNotFoundError, match="local_files_only=True"):
        from_pretrained("u/r@nope", local_files_only=True)


# -- a hostile config.json from the Hub ---------------------------------------------------------------
@pytest.fixture
def marker(tmp_path):
    path = tmp_path / "PWNED"
    yield path
    assert not path.exists(), "a checkpoint from the Hub ran code it carries"


def test_a_hostile_target_from_the_hub_is_refused(hf, tmp_path, marker):
    run = tmp_path / "evil"
    write_run(run, config={"_target_": "os.system", "_args_": [f"touch {marker}"]})
    snapshot = lay_out(hf, "mallory/evil", model_files(run), MAIN)
    for load in (load_pretrained, from_pretrained, AutoCostModel, lambda n: Run.open(f"wm:{n}").load_model()):
        with pytest.raises(UntrustedCheckpointError, match="os.system") as err:
            load("mallory/evil")
        assert "trusted_targets=" in str(err.value)
    assert str(snapshot / "config.json") in str(err.value)  # the file it came from


# -- push_to_hub and from_pretrained against a fake Hub ------------------------------------------
class FakeHub:
    """A Hub kept in ``root`` (laid out as a Hugging Face cache); what each call received."""

    def __init__(self, root: Path) -> None:
        self.root = root
        self.calls: list[tuple] = []
        self.uploads: list[set[str]] = []

    def repo(self, repo_id: str) -> Path:
        return self.root / f"models--{repo_id.replace('/', '--')}"

    def commit_of(self, repo_id: str, revision: str | None) -> str | None:
        ref = self.repo(repo_id) / "refs" / (revision or "main")
        return ref.read_text() if ref.is_file() else None

    def install(self, monkeypatch) -> FakeHub:
        import huggingface_hub
        from huggingface_hub import CommitInfo

        hub = self

        def create_repo(api, repo_id, *, private=None, exist_ok=False, **kwargs):
            hub.calls.append(("create_repo", repo_id, private, exist_ok, api.token))
            hub.repo(repo_id).mkdir(parents=True, exist_ok=True)
            return f"https://huggingface.co/{repo_id}"

        def create_branch(api, repo_id, *, branch, exist_ok=False, **kwargs):
            hub.calls.append(("create_branch", repo_id, branch, exist_ok))
            parent = hub.commit_of(repo_id, "main")
            if parent and not (hub.repo(repo_id) / "refs" / branch).exists():
                (hub.repo(repo_id) / "refs" / branch).parent.mkdir(parents=True, exist_ok=True)
                (hub.repo(repo_id) / "refs" / branch).write_text(parent)

        def upload_folder(api, *, repo_id, folder_path, commit_message=None, revision=None, **kwargs):
            folder = Path(folder_path)
            files = {p.relative_to(folder).as_posix(): p.read_bytes() for p in folder.rglob("*") if p.is_file()}
            hub.uploads.append(set(files))
            hub.calls.append(("upload_folder", repo_id, revision, commit_message))
            parent = hub.commit_of(repo_id, revision)
            digest = hashlib.sha1(repr((parent, sorted(files.items()))).encode())
            commit = digest.hexdigest()
            snapshot = hub.repo(repo_id) / "snapshots" / commit
            if parent:
                shutil.copytree(hub.repo(repo_id) / "snapshots" / parent, snapshot)
            snapshot.mkdir(parents=True, exist_ok=True)
            for name, data in files.items():
                (snapshot / name).write_bytes(data)
            ref = hub.repo(repo_id) / "refs" / (revision or "main")
            ref.parent.mkdir(parents=True, exist_ok=True)
            ref.write_text(commit)
            return CommitInfo(
                commit_url=f"https://huggingface.co/{repo_id}/commit/{commit}",
                commit_message=commit_message,
                commit_description="",
                oid=commit,
            )

        real_download = huggingface_hub.snapshot_download

        def snapshot_download(repo_id, *, revision=None, cache_dir=None, local_files_only=False, **kwargs):
            hub.calls.append(("snapshot_download", repo_id, revision, local_files_only, kwargs.get("token")))
            if local_files_only:  # the real one reads the cache
                return real_download(repo_id, revision=revision, cache_dir=cache_dir, local_files_only=True)
            commit = revision if revision and len(revision) == 40 else hub.commit_of(repo_id, revision)
            assert commit, f"the fake Hub has no {repo_id}@{revision}"
            source = hub.repo(repo_id) / "snapshots" / commit
            patterns = kwargs.get("allow_patterns") or ["*"]
            chosen = source.parent / f".chosen-{commit}"
            shutil.rmtree(chosen, ignore_errors=True)
            chosen.mkdir()
            for file in source.iterdir():
                if any(fnmatch.fnmatch(file.name, p) for p in patterns):
                    shutil.copy(file, chosen / file.name)
            snapshot = lay_out(Path(cache_dir), repo_id, chosen, commit, refs=(revision or "main",))
            shutil.rmtree(chosen)
            return str(snapshot)

        monkeypatch.setattr(huggingface_hub.HfApi, "create_repo", create_repo)
        monkeypatch.setattr(huggingface_hub.HfApi, "create_branch", create_branch)
        monkeypatch.setattr(huggingface_hub.HfApi, "upload_folder", upload_folder)
        monkeypatch.setattr(huggingface_hub, "snapshot_download", snapshot_download)
        return self


@pytest.fixture
def fake_hub(tmp_path, monkeypatch, hf) -> FakeHub:
    monkeypatch.delenv("HF_HUB_OFFLINE")  # "online", against the fake
    return FakeHub(tmp_path / "remote").install(monkeypatch)


@pytest.fixture
def trained(_stablewm_home):
    """Run ``r`` in our cache, as swm train leaves it (with train_state.ckpt, step_2/, a pickle...)."""
    folder = _stablewm_home / "checkpoints" / "r"
    return write_run(folder), folder


def test_push_then_from_pretrained_round_trips(fake_hub, trained, hf, monkeypatch):
    model, folder = trained
    info = push_to_hub("r", "u/r", token="hf_test")
    assert str(info).startswith("https://huggingface.co/u/r/commit/") and info.commit_url == str(info)
    assert fake_hub.uploads == [UPLOADABLE]  # no train_state.ckpt, step_2/, *_object.ckpt, metrics
    assert ("create_repo", "u/r", False, True, "hf_test") in fake_hub.calls
    remote = fake_hub.repo("u/r") / "snapshots" / fake_hub.commit_of("u/r", None)
    assert (remote / "weights.pt").read_bytes() == (folder / "weights.pt").read_bytes()
    assert (remote / "config.json").read_bytes() == (folder / "config.json").read_bytes()

    loaded = from_pretrained("u/r", token="hf_test")
    assert torch.equal(outputs(loaded), outputs(model)) and not loaded.training
    assert fake_hub.calls[-1] == ("snapshot_download", "u/r", None, False, "hf_test")
    snapshot = hf / "models--u--r" / "snapshots" / fake_hub.commit_of("u/r", None)
    assert sorted(p.name for p in snapshot.iterdir()) == sorted(UPLOADABLE)
    # downloaded once, it loads offline, by every name
    monkeypatch.setenv("HF_HUB_OFFLINE", "1")
    assert torch.equal(outputs(from_pretrained("u/r")), outputs(model))
    assert fake_hub.calls[-1][3] is True  # local_files_only from HF_HUB_OFFLINE
    assert torch.equal(outputs(load_pretrained("u/r")), outputs(model))
    assert torch.equal(outputs(AutoCostModel("u/r")), outputs(model))
    assert torch.equal(outputs(Run.open("wm:u/r").load_model()), outputs(model))


def test_the_pushed_protocol_and_model_card(fake_hub, trained):
    push_to_hub("r", "u/r")
    remote = fake_hub.repo("u/r") / "snapshots" / fake_hub.commit_of("u/r", None)
    protocol = json.loads((remote / "protocol.json").read_text())
    assert "dataset_path" not in protocol  # this machine's paths, host name and command line stay here
    assert "host" not in protocol["provenance"] and "command" not in protocol["provenance"]
    assert protocol["provenance"]["versions"] == {"torch": "2"}
    stored = json.loads((trained[1] / "protocol.json").read_text())
    assert protocol["weights_sha256"] == stored["weights_sha256"] and protocol["env"] == "swm/Toy-v0"
    card = (remote / "README.md").read_text()
    assert card.startswith("---\nlibrary_name: stable-worldmodel\n")
    for text in (
        "| Model | lewm (preset tiny) |",
        "| Dataset | toy |",
        "| Environment | swm/Toy-v0 |",
        "| Training steps | 4 |",
        'from_pretrained("u/r")',
        'load_pretrained("u/r")',
        "swm eval swm/Toy-v0 --policy wm:u/r",
        "stable_worldmodel.wm.lewm.LeWM",
    ):
        assert text in card, text


def test_push_takes_a_wm_spec_or_a_path_a_branch_and_private(fake_hub, trained, hf, monkeypatch):
    model, folder = trained
    push_to_hub("wm:r", "u/r", private=True, revision="dev", commit_message="first")
    assert ("create_repo", "u/r", True, True, None) in fake_hub.calls
    assert ("create_branch", "u/r", "dev", True) in fake_hub.calls
    assert ("upload_folder", "u/r", "dev", "first") in fake_hub.calls
    assert fake_hub.commit_of("u/r", None) is None  # nothing on main
    other = build(seed=5)
    elsewhere = folder.parent.parent.parent / "elsewhere"
    write_checkpoint(other, elsewhere, tree())  # no protocol.json: an upstream-style folder
    push_to_hub(elsewhere, "u/r")  # a path, to main
    assert fake_hub.uploads[-1] == {"weights.pt", "config.json", "README.md"}
    assert ("upload_folder", "u/r", None, "Upload elsewhere with stable-worldmodel") in fake_hub.calls
    assert torch.equal(outputs(from_pretrained("u/r@dev")), outputs(model))
    assert torch.equal(outputs(from_pretrained("u/r", revision="main")), outputs(other))
    monkeypatch.setenv("HF_HUB_OFFLINE", "1")
    assert torch.equal(outputs(load_pretrained("u/r@dev")), outputs(model))
    assert torch.equal(outputs(load_pretrained("u/r")), outputs(other))


def test_push_refuses_what_it_must_not_upload(fake_hub, trained, _stablewm_home):
    _, folder = trained
    for bad in ("no-slash", "a/b/c", "u--x/r", "u/r..x", "", None):
        with pytest.raises(ConfigError, match="requires a Hub repo id") as err:
            push_to_hub("r", bad)
        assert repr(bad) in str(err.value)
    with pytest.raises(FileNotFoundError, match="Did you mean 'r'"):
        push_to_hub("rr", "u/r")
    pickled = _stablewm_home / "checkpoints" / "pickled"
    pickled.mkdir()
    torch.save(torch.nn.Linear(2, 2), pickled / "weights.pt")  # a whole module: a pickle
    shutil.copy(folder / "config.json", pickled / "config.json")
    with pytest.raises(CheckpointError, match="pickled Python objects"):
        push_to_hub("pickled", "u/r")
    (pickled / "weights.pt").write_bytes((folder / "weights.pt").read_bytes())
    (pickled / "config.json").unlink()
    with pytest.raises(FileNotFoundError, match="requires config.json beside"):
        push_to_hub("pickled", "u/r")
    with pytest.raises(ConfigError, match="requires a revision"):
        push_to_hub("r", "u/r", revision="../main")
    assert fake_hub.uploads == []  # nothing went up


def test_hub_failures_are_typed_errors(fake_hub, trained, monkeypatch):
    import huggingface_hub
    from huggingface_hub.errors import LocalTokenNotFoundError, OfflineModeIsEnabled

    def offline(*args, **kwargs):
        raise OfflineModeIsEnabled("Cannot reach https://huggingface.co: offline mode is enabled.")

    monkeypatch.setattr(huggingface_hub.HfApi, "create_repo", offline)
    with pytest.raises(ConfigError, match="could not push 'r' to 'u/r': OfflineModeIsEnabled") as err:
        push_to_hub("r", "u/r")
    assert "HF_HUB_OFFLINE" in str(err.value)

    def no_token(*args, **kwargs):
        raise LocalTokenNotFoundError("Token is required but no token found.")

    monkeypatch.setattr(huggingface_hub.HfApi, "create_repo", no_token)
    with pytest.raises(ConfigError, match="hf auth login"):
        push_to_hub("r", "u/r")

    def bug(*args, **kwargs):
        raise KeyError("a bug of ours")

    monkeypatch.setattr(huggingface_hub.HfApi, "create_repo", bug)
    with pytest.raises(KeyError):  # not the Hub's: not dressed up as one
        push_to_hub("r", "u/r")


def test_from_pretrained_arguments(fake_hub, trained, marker, monkeypatch, tmp_path):
    model, _ = trained
    push_to_hub("r", "u/r")
    with pytest.raises(TypeError, match="unexpected keyword argument.*trust_remote_code"):
        from_pretrained("u/r", trust_remote_code=True)
    with pytest.raises(ConfigError, match="one revision"):
        from_pretrained("u/r@a", revision="b")
    with pytest.raises(ConfigError, match="requires a Hub repo id"):
        from_pretrained("not a repo")
    # extra_args pass through, and cannot smuggle a target in
    evil = {"predictor.norm": {"_target_": "os.system", "_args_": [f"touch {marker}"]}}
    with pytest.raises(UntrustedCheckpointError, match="predictor.norm"):
        from_pretrained("u/r", extra_args=evil)
    # another Hugging Face cache folder
    elsewhere = tmp_path / "elsewhere-hf"
    assert torch.equal(outputs(from_pretrained("u/r", cache_dir=elsewhere)), outputs(model))
    assert (elsewhere / "models--u--r" / "refs" / "main").is_file()

"""AutoCostModel / AutoActionableModel: load checkpoint folders or pickled modules from the cache."""

from __future__ import annotations

import os

import pytest
import torch

from stable_worldmodel.errors import ConfigError, UnknownNameError
from stable_worldmodel.planning import list_model_checkpoints
from stable_worldmodel.policy import AutoActionableModel, AutoCostModel


class Head(torch.nn.Module):
    def __init__(self, tag=0):
        super().__init__()
        self.tag = tag
        self.lin = torch.nn.Linear(2, 1)

    def get_cost(self, info, candidates):
        return candidates.sum(dim=(2, 3))


class Actor(torch.nn.Module):
    def get_action(self, info):
        return torch.zeros(1)


class Wrapper(torch.nn.Module):
    def __init__(self, tag=0):
        super().__init__()
        self.actor = Actor()
        self.head = Head(tag)


def save(obj, path, mtime=None):
    path.parent.mkdir(parents=True, exist_ok=True)
    torch.save(obj, path)
    if mtime is not None:
        os.utime(path, (mtime, mtime))


def test_finds_the_sub_module_in_the_default_cache(_stablewm_home):
    save(Wrapper(tag=1), _stablewm_home / "pusht_object.ckpt")
    model = AutoCostModel("pusht")
    assert isinstance(model, Head) and model.tag == 1 and not model.training
    assert isinstance(AutoActionableModel("pusht"), Actor)
    assert list_model_checkpoints() == ["pusht"]


def test_a_folder_resolves_to_its_one_checkpoint_only(tmp_path):
    save(Wrapper(tag=1), tmp_path / "run" / "epoch_1_object.ckpt", mtime=1_000)
    save(Wrapper(tag=2), tmp_path / "run" / "sub" / "epoch_2_object.ckpt", mtime=2_000)  # not searched
    assert AutoCostModel("run", cache_dir=tmp_path).tag == 1
    assert AutoCostModel(tmp_path / "run" / "sub" / "epoch_2_object.ckpt").tag == 2  # a file path
    assert list_model_checkpoints(tmp_path) == ["run"]
    save(Wrapper(tag=3), tmp_path / "run" / "epoch_3_object.ckpt", mtime=3_000)
    with pytest.raises(
        ConfigError,
        match=r"got 2 \*_object.ckpt files in .*run: epoch_1_object.ckpt, epoch_3_object.ckpt; pass the file",
    ):
        AutoCostModel("run", cache_dir=tmp_path)  # no "newest wins" guess
    assert list_model_checkpoints(tmp_path) == []  # what is listed is what loads


def test_loading_a_pickle_warns_naming_the_file(_stablewm_home):
    save(Head(), _stablewm_home / "tworoom_object.ckpt")
    with pytest.warns(UserWarning, match=r"tworoom_object.ckpt is a pickled checkpoint: loading it runs code"):
        AutoCostModel("tworoom")


def test_pickles_can_be_refused(_stablewm_home, monkeypatch):
    save(Head(), _stablewm_home / "tworoom_object.ckpt")
    with pytest.raises(ConfigError, match="refuses pickled checkpoints"):
        AutoCostModel("tworoom", allow_pickle=False)
    monkeypatch.setenv("STABLEWM_REFUSE_PICKLE", "1")
    with pytest.raises(ConfigError, match="STABLEWM_REFUSE_PICKLE is set"):
        AutoActionableModel("tworoom")


def test_pickle_of_a_class_that_cannot_be_found(_stablewm_home, monkeypatch):
    import sys
    import types

    module = types.ModuleType("gone_module")

    class Gone(torch.nn.Module):
        def get_cost(self, info, candidates):
            return 0

    Gone.__module__, Gone.__qualname__ = "gone_module", "Gone"
    module.Gone = Gone
    monkeypatch.setitem(sys.modules, "gone_module", module)
    _stablewm_home.mkdir(parents=True, exist_ok=True)
    torch.save(Gone(), _stablewm_home / "gone_object.ckpt")
    monkeypatch.delitem(sys.modules, "gone_module")
    with pytest.raises(ConfigError, match=r"classes pickled in .*gone_object.ckpt to be importable.*gone_module"):
        AutoCostModel("gone")


def test_missing_checkpoint_lists_the_available_ones(_stablewm_home):
    save(Head(), _stablewm_home / "tworoom_object.ckpt")
    with pytest.raises(UnknownNameError, match=r"Did you mean 'tworoom'.*Available.*tworoom"):
        AutoCostModel("tworom")


def test_module_without_the_method_is_an_error(_stablewm_home):
    save(Actor(), _stablewm_home / "bc_object.ckpt")
    with pytest.raises(ConfigError, match="get_cost"):
        AutoCostModel("bc")


# -- checkpoint folders (weights.pt + config.json) -------------------------------------------
def save_run(run="runx", cache_dir=None):
    """Save a tiny dummy model as checkpoint folder ``run``; returns (model, weights path)."""
    from stable_worldmodel import wm
    from stable_worldmodel.wm.utils import save_pretrained

    model = wm.make("dummy", "tiny", action_dim=2)
    tree = wm.get_config("dummy", "tiny").target_tree(2)
    return model, save_pretrained(model, run, config=tree, cache_dir=cache_dir)


def same_weights(a, b):
    sa, sb = a.state_dict(), b.state_dict()
    return sa.keys() == sb.keys() and all(torch.equal(sa[k], sb[k]) for k in sa)


def test_loads_a_checkpoint_folder(_stablewm_home):
    from stable_worldmodel.wm.dummy import DummyWorldModel

    model, weights = save_run()
    loaded = AutoCostModel("runx")
    assert isinstance(loaded, DummyWorldModel) and not loaded.training and same_weights(loaded, model)
    info = {"pixels": torch.zeros(1, 1, 3, 16, 16), "goal": torch.ones(1, 1, 3, 16, 16)}
    assert loaded.get_cost(info, torch.zeros(1, 4, 3, loaded.action_dim)).shape == (1, 4)  # (B, S)
    assert same_weights(AutoCostModel(weights), model)  # the .pt file
    assert same_weights(AutoCostModel(weights.parent), model)  # an absolute folder


def test_checkpoint_folder_with_cache_dir_and_user_repo(tmp_path):
    model, _ = save_run("models--someone--tiny", cache_dir=tmp_path)
    assert same_weights(AutoCostModel("someone/tiny", cache_dir=tmp_path), model)
    assert list_model_checkpoints(tmp_path) == ["models--someone--tiny"]


def test_checkpoint_folder_wins_over_a_pickled_module(_stablewm_home):
    model, _ = save_run("pusht")
    save(Wrapper(tag=1), _stablewm_home / "pusht_object.ckpt")
    assert same_weights(AutoCostModel("pusht"), model)
    assert list_model_checkpoints() == ["pusht"]


def test_lists_both_layouts(_stablewm_home):
    save_run("runx")
    save_run("sweep/a")
    save(Wrapper(), _stablewm_home / "tworoom_object.ckpt")
    assert list_model_checkpoints() == ["runx", "sweep/a", "tworoom"]
    assert isinstance(AutoCostModel("tworoom"), Head)  # the pickled one still loads


def test_checkpoint_without_get_action_is_an_error(_stablewm_home):
    save_run()
    with pytest.raises(ConfigError, match=r"AutoActionableModel requires a module with get_action\(\)"):
        AutoActionableModel("runx")


def test_unknown_name_names_both_layouts_and_all_candidates(_stablewm_home):
    save_run("runx")
    save(Head(), _stablewm_home / "tworoom_object.ckpt")
    with pytest.raises(UnknownNameError) as err:
        AutoCostModel("runz")
    message = str(err.value)
    assert (
        "weights.pt" in message
        and "config.json" in message
        and "<user>/<repo>" in message
        and "_object.ckpt" in message
    )
    assert "Did you mean 'runx'?" in message and "runx, tworoom" in message
    with pytest.raises(UnknownNameError, match="Did you mean 'tworoom'"):
        AutoCostModel("tworom")
    with pytest.raises(UnknownNameError, match="models--<user>--<repo>"):
        AutoCostModel("someone/missing")


def test_weights_without_config_is_explained(_stablewm_home):
    from stable_worldmodel.wm.utils import write_checkpoint

    model, _ = save_run()
    write_checkpoint(model, _stablewm_home / "checkpoints" / "bare", config=None)
    with pytest.raises(UnknownNameError, match=r"holds weights.pt but no config.json"):
        AutoCostModel("bare")

"""AutoCostModel / AutoActionableModel: load pickled modules from the cache."""

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


def test_folder_newest_checkpoint_wins_and_cache_dir_argument(tmp_path):
    save(Wrapper(tag=1), tmp_path / "run" / "epoch_1_object.ckpt", mtime=1_000)
    save(Wrapper(tag=2), tmp_path / "run" / "sub" / "epoch_2_object.ckpt", mtime=2_000)
    assert AutoCostModel("run", cache_dir=tmp_path).tag == 2
    assert AutoCostModel(tmp_path / "run" / "epoch_1_object.ckpt").tag == 1  # a file path
    assert list_model_checkpoints(tmp_path) == ["run"]


def test_missing_checkpoint_lists_the_available_ones(_stablewm_home):
    save(Head(), _stablewm_home / "tworoom_object.ckpt")
    with pytest.raises(UnknownNameError, match=r"Did you mean 'tworoom'.*Available.*tworoom"):
        AutoCostModel("tworom")


def test_module_without_the_method_is_an_error(_stablewm_home):
    save(Actor(), _stablewm_home / "bc_object.ckpt")
    with pytest.raises(ConfigError, match="get_cost"):
        AutoCostModel("bc")

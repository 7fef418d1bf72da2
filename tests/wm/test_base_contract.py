"""The world-model contract (``stable_worldmodel.wm.base``): every registered config is a
``WorldModelConfig`` carrying only fields its model uses, and the trainer and planning learn what
a model can do from its capabilities, not from its class or registry name."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
import torch
from _tiny import ACTION_DIM, TINY

import stable_worldmodel.wm as wm
from stable_worldmodel.errors import ConfigError
from stable_worldmodel.wm.base import (
    Actor,
    CostModel,
    DecodesFrames,
    DerivedFromRun,
    GoalConditioned,
    HasFrozenEncoder,
    HasValidationLoss,
    SupportsSubgoalGraph,
    WorldModelConfig,
    check_positive_int,
)
from stable_worldmodel.wm.config import JEPAConfig

MODELS = [m for m in wm.list_models() if m != "frame"]  # the frame decoder needs a source run


@pytest.mark.parametrize("name", MODELS)
def test_every_config_is_a_world_model_config_with_a_tree(name):
    cls = wm.get_config_class(name)
    assert issubclass(cls, WorldModelConfig)
    cfg = wm.get_config(name, "tiny")
    tree = cfg.target_tree(ACTION_DIM)
    assert tree["_target_"] == cls.target
    shared = {f.name for f in dataclasses.fields(WorldModelConfig)}
    assert shared <= set(cfg.to_dict())


def test_only_the_jepa_family_has_jepa_fields():
    jepa = {name for name in MODELS if issubclass(wm.get_config_class(name), JEPAConfig)}
    assert jepa == {"lewm", "pldm"}
    fields = {f.name for f in dataclasses.fields(wm.get_config_class("tdmpc2"))}
    assert not fields & {"vit_size", "heads", "depth", "projector_hidden", "encoder"}
    fields = {f.name for f in dataclasses.fields(wm.get_config_class("dummy"))}
    assert not fields & {"embed_dim", "vit_size", "heads"}
    with pytest.raises(ConfigError, match="has no field 'heads'"):
        wm.get_config("tdmpc2", "tiny", heads=4)


def test_config_capabilities():
    capabilities = {
        name: (
            wm.get_config_class(name).subgoal_graph,
            wm.get_config_class(name).needs_reward,
            isinstance(wm.get_config(name, "tiny"), GoalConditioned),
        )
        for name in MODELS
    }
    assert {n for n, (graph, _, _) in capabilities.items() if graph} == {"lewm", "pldm", "prejepa", "dinowm", "dreamer"}
    assert {n for n, (_, reward, _) in capabilities.items() if reward} == {"tdmpc2"}
    assert {n for n, (_, _, goals) in capabilities.items() if goals} == {"gcbc", "gcivl", "gciql"}
    assert not isinstance(wm.get_config("lewm", "tiny"), DerivedFromRun)
    prejepa = wm.get_config_class("prejepa")
    assert prejepa.subgoal_graph_unavailable({"proprio_dim": 0}) is None
    assert "proprio" in prejepa.subgoal_graph_unavailable({"proprio_dim": 4})
    assert "does not support" in wm.get_config_class("gcbc").subgoal_graph_unavailable({})
    assert wm.get_config("prejepa", "tiny", proprio_dim=3).extra_columns == {"proprio": 3}
    assert wm.get_config("lewm", "tiny").extra_columns == {}


def test_model_capabilities():
    lewm = wm.make("lewm", "tiny", action_dim=ACTION_DIM, **TINY)
    assert isinstance(lewm, (SupportsSubgoalGraph, CostModel)) and not isinstance(lewm, (Actor, HasFrozenEncoder))
    assert lewm.subgoal_keys() == ("emb", "goal_emb")
    prejepa = wm.make("prejepa", "tiny", action_dim=ACTION_DIM)
    assert isinstance(prejepa, HasFrozenEncoder) and prejepa.subgoal_keys() == ("pixels_emb", "pixels_goal_emb")
    with_proprio = wm.make("prejepa", "tiny", action_dim=ACTION_DIM, proprio_dim=2)
    with pytest.raises(ConfigError, match="without proprio"):
        with_proprio.subgoal_keys()
    dreamer = wm.make("dreamer", "tiny", action_dim=ACTION_DIM)
    assert isinstance(dreamer, DecodesFrames) and dreamer.subgoal_keys() == (None, "goal_emb")
    assert isinstance(wm.make("gcbc", "tiny", action_dim=ACTION_DIM), Actor)
    tdmpc2 = wm.make("tdmpc2", "tiny", action_dim=ACTION_DIM)
    assert isinstance(tdmpc2, HasValidationLoss) and tdmpc2.validation_loss == "model_loss"


def test_a_new_model_declares_a_capability_once_and_planning_sees_it(monkeypatch):
    """A registered config with ``subgoal_graph = True`` is planned with waypoints: no list to edit."""
    from stable_worldmodel.planning import learned
    from stable_worldmodel.wm import _registry

    @dataclasses.dataclass
    class MyConfig(wm.get_config_class("lewm")):
        model_name = "mine"

    monkeypatch.setitem(_registry._ENTRIES, "mine", MyConfig)
    protocol = {"model": "mine", "config": {}, "dataset": None}
    assert (
        learned._graph_unavailable(protocol, None) == "its protocol names no training dataset"
    )  # past the model check
    monkeypatch.setattr(MyConfig, "subgoal_graph", False)
    assert "does not support a subgoal graph" in learned._graph_unavailable(protocol, None)

    class Plain(torch.nn.Module):
        def encode_pixels(self, pixels):
            return pixels

    with pytest.raises(ConfigError, match="requires a model with subgoal_keys"):
        learned._WaypointHook.keys(Plain())


def test_check_positive_int():
    assert check_positive_int("X", "n", 3) == 3 and check_positive_int("X", "n", np.int64(2)) == 2
    assert check_positive_int("X", "n", 0, minimum=0) == 0
    for bad in (0, -1, True, 1.5, "2"):
        with pytest.raises(ConfigError, match=r"X requires n to be an integer >= 1, got"):
            check_positive_int("X", "n", bad)

"""Checkpoints (``stable_worldmodel.wm.utils``): save_pretrained / load_pretrained in upstream's
layout under ``$STABLEWM_HOME/checkpoints``, every way of naming one, and the errors."""

from __future__ import annotations

import functools
import json
import shutil

import pytest
import torch
from _tiny import ACTION_DIM, IMAGE, TINY, condition_on_actions, images, randn

import stable_worldmodel.wm as wm
from stable_worldmodel import keys
from stable_worldmodel.errors import ConfigError, UnknownNameError
from stable_worldmodel.wm.utils import instantiate, load_pretrained, save_pretrained


def config_of(name: str, **overrides) -> dict:
    """The ``_target_`` tree of the tiny ``name`` model (what config.json holds)."""
    if name == "dummy":
        return wm.get_config("dummy", "tiny", image_size=IMAGE, frameskip=1, **overrides).target_tree(ACTION_DIM)
    return wm.get_config(name, "tiny", **{**TINY, **overrides}).target_tree(ACTION_DIM)


def build(name: str, seed: int = 0, **overrides) -> torch.nn.Module:
    """A model of ``config_of(name)`` with trained-looking state: non-zero AdaLN modulations and
    BatchNorm running statistics, so a state dict that did not load would show."""
    torch.manual_seed(seed)
    model = condition_on_actions(instantiate(config_of(name, **overrides)))
    if name != "dummy":
        with torch.no_grad():
            model.train().encode({keys.PIXELS: images(4, 2, seed=seed)})  # BatchNorm running statistics
    return model.eval()


def outputs(model: torch.nn.Module) -> torch.Tensor:
    """Costs of fixed candidates: they go through every module (encoder, heads, predictor)."""
    info = {keys.PIXELS: images(2, 3, 1, seed=7), keys.GOAL: images(2, 3, 1, seed=8)}
    with torch.no_grad():
        return model.get_cost(info, randn(2, 3, 2, ACTION_DIM, seed=9))


@pytest.fixture
def saved(_stablewm_home):
    """``saved(name="lewm", run="run")``: save a tiny model; returns (model, run folder)."""

    def save(name: str = "lewm", run: str = "run", **overrides):
        model = build(name, **overrides)
        save_pretrained(model, run, config=config_of(name, **overrides))
        return model, _stablewm_home / "checkpoints" / run

    return save


# -- save / load -------------------------------------------------------------------------------
@pytest.mark.parametrize("name", ["lewm", "pldm", "dummy"])
def test_save_then_load_gives_identical_outputs(saved, name):
    model, folder = saved(name)
    assert sorted(p.name for p in folder.iterdir()) == ["config.json", "weights.pt"]
    assert json.loads((folder / "config.json").read_text()) == json.loads(json.dumps(config_of(name)))
    loaded = load_pretrained("run")
    assert type(loaded) is type(model) and not loaded.training
    assert torch.equal(outputs(loaded), outputs(model))
    state = model.state_dict()
    assert all(torch.equal(v, state[k]) for k, v in loaded.state_dict().items())


def test_save_pretrained_returns_the_weights_path(_stablewm_home):
    path = save_pretrained(build("lewm"), "a/b", config=config_of("lewm"))
    assert path == _stablewm_home / "checkpoints" / "a" / "b" / "weights.pt"
    assert load_pretrained("a/b/weights.pt") is not None


def test_save_pretrained_config_key(saved, _stablewm_home):
    save_pretrained(build("lewm"), "keyed", config={"model": config_of("lewm"), "lr": 1e-3}, config_key="model")
    assert "_target_" in json.loads((_stablewm_home / "checkpoints" / "keyed" / "config.json").read_text())


def test_save_pretrained_requires_a_run_name():
    with pytest.raises(ConfigError, match="run name"):
        save_pretrained(build("dummy"), "", config=config_of("dummy"))


def test_load_the_pt_file(saved):
    model, folder = saved()
    assert torch.equal(outputs(load_pretrained("run/weights.pt")), outputs(model))
    assert torch.equal(outputs(load_pretrained(folder / "weights.pt")), outputs(model))


def test_load_an_absolute_folder_anywhere(saved, tmp_path):
    model, folder = saved()
    elsewhere = tmp_path / "elsewhere"
    shutil.copytree(folder, elsewhere)
    (elsewhere / "weights.pt").rename(elsewhere / "lewm_epoch_3.pt")
    assert torch.equal(outputs(load_pretrained(str(elsewhere))), outputs(model))
    assert torch.equal(outputs(load_pretrained(elsewhere / "lewm_epoch_3.pt")), outputs(model))


def test_load_user_repo_from_the_hub_layout(saved):
    model, folder = saved()
    folder.rename(folder.parent / "models--user--repo")
    assert torch.equal(outputs(load_pretrained("user/repo")), outputs(model))


def test_missing_user_repo_names_the_folder_to_fill(_stablewm_home):
    with pytest.raises(FileNotFoundError, match="models--nobody--nothing") as info:
        load_pretrained("nobody/nothing")
    assert str(_stablewm_home / "checkpoints") in str(info.value)


def test_missing_run_suggests_the_close_ones(saved):
    saved(run="pusht_lewm")
    with pytest.raises(FileNotFoundError, match="Did you mean 'pusht_lewm'"):
        load_pretrained("pusht_lewn")


def test_folder_with_two_pt_files_is_ambiguous(saved):
    _, folder = saved()
    shutil.copy(folder / "weights.pt", folder / "weights_old.pt")
    with pytest.raises(ConfigError, match="exactly one .pt") as info:
        load_pretrained("run")
    assert "weights.pt" in str(info.value) and "weights_old.pt" in str(info.value)
    assert load_pretrained("run/weights_old.pt") is not None  # naming the file settles it


def test_corrupt_config_json_names_the_file(saved):
    _, folder = saved()
    (folder / "config.json").write_text('{"_target_": "stable_worldmodel.wm.lewm.LeWM", ')
    with pytest.raises(ConfigError, match="config.json") as info:
        load_pretrained("run")
    assert str(folder / "config.json") in str(info.value)


def test_config_without_target_is_refused(saved):
    _, folder = saved()
    (folder / "config.json").write_text('{"lr": 0.001}')
    with pytest.raises(ConfigError, match="_target_"):
        load_pretrained("run")


def test_missing_config_json(_stablewm_home):
    save_pretrained(build("dummy"), "no_config")  # warns: nothing to rebuild the model from
    with pytest.raises(FileNotFoundError, match="config.json"):
        load_pretrained("no_config")


def test_corrupt_weights_name_the_file(saved):
    _, folder = saved()
    (folder / "weights.pt").write_bytes(b"not a checkpoint")
    with pytest.raises(ConfigError, match="weights.pt"):
        load_pretrained("run")


def test_weights_with_other_keys_are_refused(saved):
    _, folder = saved()
    (folder / "config.json").write_text(json.dumps(config_of("pldm")))  # PLDM has an extra idm head
    with pytest.raises(ConfigError, match="do not fit.*missing keys.*idm"):
        load_pretrained("run")


def test_weights_with_other_shapes_are_refused(saved):
    _, folder = saved()
    (folder / "config.json").write_text(json.dumps(config_of("lewm", embed_dim=16)))
    with pytest.raises(ConfigError, match="weights.pt"):
        load_pretrained("run")


def test_extra_args_override_dotted_keys(saved):
    model, _ = saved(dropout=0.2)
    assert load_pretrained("run").predictor.transformer.layers[0].attn.dropout == 0.2
    loaded = load_pretrained("run", extra_args={"predictor.dropout": 0.0})
    assert loaded.predictor.transformer.layers[0].attn.dropout == 0.0
    assert torch.equal(outputs(loaded), outputs(model))


def test_partial_builds_the_batchnorm_heads(saved):
    saved()
    projector = load_pretrained("run").projector
    assert isinstance(projector.net[1], torch.nn.BatchNorm1d) and projector.net[1].num_features == 16


def test_load_pretrained_cache_dir(tmp_path):
    model = build("dummy")
    save_pretrained(model, "run", config=config_of("dummy"), cache_dir=tmp_path / "cache")
    assert (tmp_path / "cache" / "checkpoints" / "run" / "weights.pt").is_file()
    assert torch.equal(outputs(load_pretrained("run", cache_dir=tmp_path / "cache")), outputs(model))


# -- instantiate ---------------------------------------------------------------------------------
def test_instantiate_partial_and_nesting():
    built = instantiate({"norm": {"_target_": "torch.nn.BatchNorm1d", "_partial_": True}, "xs": [1, {"a": 2}]})
    assert isinstance(built["norm"], functools.partial) and built["norm"].func is torch.nn.BatchNorm1d
    assert isinstance(built["norm"](4), torch.nn.BatchNorm1d)
    assert built["xs"] == [1, {"a": 2}]
    assert instantiate({"_target_": "builtins.max", "_args_": [1, 3]}, trusted_targets=("builtins",)) == 3


def test_instantiate_errors():
    with pytest.raises(UnknownNameError, match="no_such_module"):
        instantiate({"_target_": "stable_worldmodel.no_such_module.Thing"})
    with pytest.raises(ConfigError, match="widht"):
        instantiate({"_target_": "stable_worldmodel.wm.encoders.ConvEncoder", "widht": 8})
    with pytest.raises(ConfigError, match="dotted name"):
        instantiate({"_target_": 3})

"""Probes (``stable_worldmodel.wm.probes``): attach_probe / get_probe / load_probe.

Behaviour follows upstream 0.1.1 as observed by running its module on small synthetic models:
probes live in ``model._probes`` (an ``nn.ModuleDict``), so they are in ``model.state_dict()`` as
``_probes.<key>.*``; ``get_probe`` returns ``None`` when there is none; ``load_probe`` attaches a
pickled module or loads a state dict strictly into the attached probe, on the CPU, and returns
``None``. The typed errors are ours (each also the builtin upstream raised), as is the refusal of
pickles under ``STABLEWM_REFUSE_PICKLE=1`` and of files holding neither a module nor a state dict.
"""

from __future__ import annotations

import io
import warnings

import pytest
import torch
from _tiny import images
from torch import nn

from stable_worldmodel import keys
from stable_worldmodel.errors import ArgumentTypeError, CheckpointError, ConfigError
from stable_worldmodel.wm.probes import (
    ProbeKeyError,
    ProbeNotFoundError,
    ProbeStateError,
    ProbeTypeError,
    attach_probe,
    get_probe,
    load_probe,
)


def linear(n_in: int = 8, n_out: int = 2, seed: int = 0) -> nn.Linear:
    torch.manual_seed(seed)
    return nn.Linear(n_in, n_out)


class Plain:
    """A model that is not an ``nn.Module`` (upstream attaches probes to any object)."""


def test_public_names_and_signatures_are_upstreams():
    import inspect

    import stable_worldmodel.wm.probes as probes

    assert probes.__all__ == ["attach_probe", "get_probe", "load_probe"]
    assert str(inspect.signature(attach_probe)) == "(model, key, probe)"
    assert str(inspect.signature(get_probe)) == "(model, key)"
    assert str(inspect.signature(load_probe)) == "(model, key, path)"


# -- attach / get -------------------------------------------------------------------------------
@pytest.mark.parametrize("model", [linear(2, 8), Plain()], ids=["module", "plain"])
def test_get_probe_is_none_without_that_probe(model):
    assert get_probe(model, "position") is None
    attach_probe(model, "position", linear())
    assert get_probe(model, "velocity") is None
    assert get_probe(model, 3) is None and get_probe(model, ["unhashable"]) is None


def test_attached_probes_are_submodules_of_the_model():
    model, probe = linear(2, 8), linear()
    assert attach_probe(model, "position", probe) is None
    assert get_probe(model, "position") is probe
    assert isinstance(model._probes, nn.ModuleDict)
    assert list(model.state_dict()) == ["weight", "bias", "_probes.position.weight", "_probes.position.bias"]
    model.eval()
    assert probe.training is False  # mode (and device, dtype) follow the model
    model.to(torch.float64)
    assert probe.weight.dtype == torch.float64


def test_attach_replaces_the_probe_under_the_same_key():
    model, first, second = linear(2, 8), linear(seed=1), linear(seed=2)
    attach_probe(model, "position", first)
    attach_probe(model, "speed", linear(8, 1))
    attach_probe(model, "position", second)
    assert get_probe(model, "position") is second
    assert list(model._probes) == ["position", "speed"]


def test_attach_on_a_plain_object_and_on_an_existing_dict():
    plain, probe = Plain(), linear()
    attach_probe(plain, "position", probe)
    assert isinstance(plain._probes, nn.ModuleDict) and get_probe(plain, "position") is probe
    mine = Plain()
    mine._probes = {}
    attach_probe(mine, "position", probe)
    assert mine._probes == {"position": probe}


def test_attach_refuses_a_probe_that_is_not_a_module():
    model = linear(2, 8)
    with pytest.raises(ProbeTypeError, match=r"torch\.nn\.Module, got function") as info:
        attach_probe(model, "position", lambda emb: emb)
    assert isinstance(info.value, TypeError) and isinstance(info.value, AssertionError)  # upstream: assert
    assert not hasattr(model, "_probes")


@pytest.mark.parametrize(
    "key, error, builtin",
    [(1, ArgumentTypeError, TypeError), ("a.b", ProbeKeyError, KeyError), ("", ProbeKeyError, KeyError)]
    + [("keys", ProbeKeyError, KeyError)],
)
def test_attach_refuses_keys_a_module_dict_cannot_hold(key, error, builtin):
    model = linear(2, 8)
    with pytest.raises(error, match=repr(key)) as info:
        attach_probe(model, key, linear())
    assert isinstance(info.value, builtin)
    assert not hasattr(model, "_probes")  # nothing changed


def test_attach_refuses_a_probes_attribute_that_holds_none_of_them():
    model = Plain()
    model._probes = 3
    with pytest.raises(ArgumentTypeError, match="model._probes to be a torch.nn.ModuleDict"):
        attach_probe(model, "position", linear())


# -- load ---------------------------------------------------------------------------------------
def test_load_a_pickled_module_attaches_it_on_the_cpu(tmp_path):
    saved = linear(seed=3)
    torch.save(saved, tmp_path / "probe.pt")
    model = linear(2, 8)
    attach_probe(model, "position", linear(seed=4))
    with pytest.warns(UserWarning, match="pickled probe"):
        assert load_probe(model, "position", tmp_path / "probe.pt") is None
    probe = get_probe(model, "position")
    assert probe is not saved and torch.equal(probe.weight, saved.weight) and probe.weight.device.type == "cpu"


def test_load_a_state_dict_into_the_attached_probe(tmp_path):
    torch.save(linear(seed=3).state_dict(), tmp_path / "probe.pt")
    model, probe = linear(2, 8), linear(seed=4)
    attach_probe(model, "position", probe)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no pickle: no warning
        load_probe(model, "position", str(tmp_path / "probe.pt"))
    assert get_probe(model, "position") is probe and torch.equal(probe.weight, linear(seed=3).weight)


def test_load_from_a_file_object():
    buffer = io.BytesIO()
    torch.save(linear(seed=3).state_dict(), buffer)
    buffer.seek(0)
    model = linear(2, 8)
    attach_probe(model, "position", linear(seed=4))
    load_probe(model, "position", buffer)
    assert torch.equal(get_probe(model, "position").bias, linear(seed=3).bias)


def test_a_state_dict_needs_an_attached_probe(tmp_path):
    torch.save(linear().state_dict(), tmp_path / "probe.pt")
    model = linear(2, 8)
    attach_probe(model, "speed", linear(8, 1))
    with pytest.raises(ProbeNotFoundError, match=r"under 'position'.*attached: speed") as info:
        load_probe(model, "position", tmp_path / "probe.pt")
    assert isinstance(info.value, ValueError)  # upstream's ValueError


@pytest.mark.parametrize(
    "state", [linear(5, 2).state_dict(), {"weight": torch.zeros(2, 8)}], ids=["shape", "missing-key"]
)
def test_a_state_dict_that_does_not_fit_is_refused(tmp_path, state):
    torch.save(state, tmp_path / "probe.pt")
    model = linear(2, 8)
    attach_probe(model, "position", linear())
    with pytest.raises(ProbeStateError, match="to fit the probe under 'position'") as info:
        load_probe(model, "position", tmp_path / "probe.pt")
    assert isinstance(info.value, RuntimeError)  # torch's load_state_dict error, as upstream


def test_pickles_are_refused_when_asked(tmp_path, monkeypatch):
    monkeypatch.setenv("STABLEWM_REFUSE_PICKLE", "1")
    torch.save(linear(), tmp_path / "module.pt")
    torch.save(linear(seed=3).state_dict(), tmp_path / "state.pt")
    model = linear(2, 8)
    with pytest.raises(CheckpointError, match="refuses the pickled probe"):
        load_probe(model, "position", tmp_path / "module.pt")
    attach_probe(model, "position", linear())
    load_probe(model, "position", tmp_path / "state.pt")  # a state dict needs no pickle
    assert torch.equal(get_probe(model, "position").weight, linear(seed=3).weight)


def test_files_that_hold_no_probe(tmp_path):
    model = linear(2, 8)
    with pytest.raises(FileNotFoundError, match="missing.pt"):
        load_probe(model, "position", tmp_path / "missing.pt")
    torch.save(torch.zeros(2), tmp_path / "tensor.pt")
    with pytest.raises(CheckpointError, match="a torch.nn.Module or a state dict, got Tensor"):
        load_probe(model, "position", tmp_path / "tensor.pt")  # upstream ignored it silently
    (tmp_path / "garbage.pt").write_bytes(b"not a torch file")
    with pytest.warns(UserWarning), pytest.raises(CheckpointError, match="cannot be read") as info:
        load_probe(model, "position", tmp_path / "garbage.pt")
    assert isinstance(info.value, ConfigError)
    assert not hasattr(model, "_probes")


# -- on a world model ---------------------------------------------------------------------------
def test_a_probe_of_a_world_models_embeddings_round_trips(make_model, tmp_path):
    """A linear probe reads a tiny LeWM's ``emb``; its state dict restores it on a second model."""
    pixels = {keys.PIXELS: images(4, 2)}
    model = make_model("lewm").eval()
    attach_probe(model, "position", linear(8, 2, seed=5))
    assert "_probes.position.weight" in model.state_dict()
    with torch.no_grad():
        emb = model.encode(dict(pixels))["emb"]  # (B, T, D) = (4, 2, 8)
        expected = get_probe(model, "position")(emb)
    torch.save(get_probe(model, "position").state_dict(), tmp_path / "position.pt")

    other = make_model("lewm").eval()
    attach_probe(other, "position", linear(8, 2, seed=6))
    load_probe(other, "position", tmp_path / "position.pt")
    with torch.no_grad():
        assert torch.equal(get_probe(other, "position")(emb), expected)
    assert expected.shape == (4, 2, 2)


def test_reached_as_an_attribute_of_the_lazy_package():
    """``swm.wm.probes`` works without importing it first: the package's lazy ``__getattr__``
    resolves the submodule (upstream needed ``import stable_worldmodel.wm.probes``)."""
    import stable_worldmodel as swm
    import stable_worldmodel.wm.probes as probes

    assert swm.wm.__getattr__("probes") is probes
    assert swm.wm.probes.load_probe is load_probe

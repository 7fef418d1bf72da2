"""The world-model registry and light configs: names, presets, overrides, their errors, and
that ``import stable_worldmodel.wm`` (and building a config) does not import torch."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

import stable_worldmodel.wm as wm
from stable_worldmodel.errors import ConfigError, UnknownNameError
from stable_worldmodel.wm import _registry

HEAVY = ("torch", "transformers", "h5py", "cv2", "mujoco", "matplotlib")  # as tests/test_import.py


def test_list_models():
    assert {"dummy", "lewm", "pldm"} <= set(wm.list_models())
    assert wm.list_models() == sorted(wm.list_models())


def test_unknown_model_suggests_the_close_name():
    with pytest.raises(UnknownNameError, match="lewm") as info:
        wm.make("lwm", action_dim=2)
    assert "Did you mean" in str(info.value)


def test_unknown_preset_suggests_the_close_name():
    with pytest.raises(ConfigError, match="(?i)did you mean 'tiny'"):
        wm.make("lewm", "tinny", action_dim=2)


def test_unknown_field_suggests_the_close_name():
    with pytest.raises(ConfigError, match="(?i)did you mean .*'embed_dim'"):
        wm.make("pldm", action_dim=2, embed_dm=8)


@pytest.mark.parametrize("bad", [0, -1, 2.0, True, None])
def test_make_requires_a_positive_int_action_dim(bad):
    with pytest.raises(ConfigError, match="action_dim"):
        wm.make("dummy", action_dim=bad)


@pytest.mark.parametrize(
    "field,value", [("encoder", "vti"), ("embed_dim", 0), ("dropout", 1.0), ("lr", 0.0), ("projector_hidden", -1)]
)
def test_config_values_are_checked(field, value):
    with pytest.raises(ConfigError, match=field if field != "lr" else "lr"):
        wm.get_config("lewm", "tiny", **{field: value})


def test_unknown_encoder_suggests_the_close_name():
    with pytest.raises(ConfigError, match="Did you mean 'vit'"):
        wm.get_config("lewm", encoder="vti")


def test_unknown_vit_size_is_a_config_error():
    with pytest.raises(ConfigError, match="Did you mean 'tiny'"):
        wm.get_config("lewm", encoder="vit", vit_size="tinny").target_tree(2)


def test_projector_needed_when_encoder_width_differs():
    config = wm.get_config("lewm", encoder="vit", projector_hidden=0, embed_dim=8)  # ViT-tiny is 192 wide
    with pytest.raises(ConfigError, match="projector_hidden"):
        config.target_tree(2)


def test_presets_render_json_trees():
    for name in wm.list_models():
        if name == "frame":  # its tree embeds a source run's: tests/train/test_frame_decoder.py
            continue
        cls = wm.get_config_class(name)
        for preset in cls.presets:
            tree = wm.get_config(name, preset).target_tree(3)
            assert tree["_target_"] == cls.target
            assert json.loads(json.dumps(tree)) == tree


def test_action_block_is_frameskip_actions():
    tree = wm.get_config("lewm", frameskip=5).target_tree(2)
    assert tree["action_encoder"]["input_dim"] == 10
    assert wm.get_config("pldm", frameskip=3).target_tree(2)["idm"]["output_dim"] == 6
    assert wm.get_config("dummy", frameskip=5).target_tree(2)["action_dim"] == 10


def test_register_model(monkeypatch):
    monkeypatch.setattr(_registry, "_ENTRIES", dict(_registry._ENTRIES))
    wm.register_model("mine", "stable_worldmodel.wm.dummy_config:DummyConfig")
    assert "mine" in wm.list_models()
    assert type(wm.make("mine", action_dim=2)).__name__ == "DummyWorldModel"
    with pytest.raises(ConfigError, match="new non-empty name"):
        wm.register_model("lewm", "stable_worldmodel.wm.dummy_config:DummyConfig")


def test_dir_lists_the_lazy_names():
    assert {"LeWM", "PLDM", "DummyWorldModel", "load_pretrained", "make"} <= set(dir(wm))
    assert set(wm.__all__) <= set(dir(wm))


_PROBE = """
import json, sys
import stable_worldmodel.wm as wm
before = sorted(sys.modules)
for name in ("lewm", "pldm", "dummy"):
    wm.get_config(name, "tiny").target_tree(2)
print(json.dumps({"import": before, "config": sorted(sys.modules)}))
"""


def test_import_and_configs_pull_in_no_heavy_module():
    out = subprocess.run([sys.executable, "-c", _PROBE], capture_output=True, text=True, check=True, timeout=120)
    modules = json.loads(out.stdout.strip().splitlines()[-1])
    for stage in ("import", "config"):
        loaded = [m for m in HEAVY if any(k == m or k.startswith(m + ".") for k in modules[stage])]
        assert not loaded, f"{stage} of stable_worldmodel.wm imported {loaded}"


def test_vit_configs_need_no_torch():
    code = (
        "import sys; sys.modules['torch'] = None  # any import of torch fails fast\n"
        "import stable_worldmodel.wm as wm; wm.get_config('lewm', 'small').target_tree(2)"
    )
    subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True, timeout=120)


def test_parse_override_reads_json_values():
    from stable_worldmodel.wm.config import parse_override

    assert parse_override("proprio_dim=2") == ("proprio_dim", 2)
    assert parse_override(" image_mean=[0.4, 0.5, 0.6]") == ("image_mean", [0.4, 0.5, 0.6])
    assert parse_override("backbone=cnn_aa") == ("backbone", "cnn_aa")  # not JSON: kept as text
    assert parse_override("pretrained=true") == ("pretrained", True)
    assert parse_override("path=a=b") == ("path", "a=b")  # split at the first '='
    for bad in ("lr", "=2", ""):
        with pytest.raises(ConfigError, match="requires KEY=VALUE"):
            parse_override(bad)


def test_lewm_cpu_preset_is_the_push_t_recipe():
    """``--preset cpu``: tiny sizes with a CNN of width 16, a history of 3, D=128, SIGReg at 0.09, 17500 steps (54%
    of upstream's Push-T protocol from pixels, 80% with ``encoder=state`` on the poses, docs/results); it renders
    and stays overridable."""
    tiny, cpu = wm.get_config("lewm", "tiny"), wm.get_config("lewm", "cpu")
    assert (cpu.history_size, cpu.embed_dim, cpu.sigreg_weight, cpu.sigreg_num_proj, cpu.cnn_width, cpu.steps) == (
        3,
        128,
        0.09,
        256,
        16,
        17500,
    )
    assert (cpu.encoder, cpu.depth, cpu.image_size) == (tiny.encoder, tiny.depth, 64)
    assert tiny.cnn_width == 8
    assert (tiny.history_size, tiny.embed_dim, tiny.sigreg_weight) != (3, 128, 0.09)
    tree = wm.get_config("lewm", "cpu", encoder="state", state_dim=7, state_dims=[0, 1, 2, 3, 4]).target_tree(5)
    assert tree["predictor"]["num_frames"] == 3 and tree["encoder"]["dims"] == [0, 1, 2, 3, 4]
    with pytest.raises(ConfigError, match="Did you mean 'cpu'"):
        wm.get_config("lewm", "cpuu")


def test_pldm_cpu_preset_is_its_push_t_recipe():
    """PLDM's ``--preset cpu``: the tiny sizes with a history of 3 and D=128 for 10000 steps (docs/results)."""
    tiny, cpu = wm.get_config("pldm", "tiny"), wm.get_config("pldm", "cpu")
    assert (cpu.history_size, cpu.embed_dim, cpu.steps) == (3, 128, 10000)
    assert (tiny.history_size, tiny.embed_dim) != (3, 128)
    assert (cpu.encoder, cpu.cnn_width, cpu.depth, cpu.loss_weights) == (
        tiny.encoder,
        tiny.cnn_width,
        tiny.depth,
        tiny.loss_weights,
    )
    assert wm.get_config("pldm", "cpu", steps=20).steps == 20
    assert wm.get_config("pldm", "cpu").target_tree(2)["predictor"]["num_frames"] == 3

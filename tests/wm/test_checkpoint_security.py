"""A checkpoint never runs the code it carries (issue 26): ``_target_`` names outside the trusted
prefixes are refused before anything is imported or called, wherever they sit in the tree; and
damaged weights (flipped bits, truncation, NaN/inf, another model's state dict, a full disk) are
typed errors naming the file."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap

import pytest
import torch
from _tiny import ACTION_DIM, IMAGE, TINY

import stable_worldmodel.wm as wm
from stable_worldmodel.errors import CheckpointError, ConfigError, DiskFullError, UntrustedCheckpointError
from stable_worldmodel.planning import AutoActionableModel, AutoCostModel
from stable_worldmodel.wm.utils import instantiate, load_checkpoint, load_pretrained, save_pretrained, write_checkpoint


def tiny_tree(name: str = "lewm") -> dict:
    return wm.get_config(name, "tiny", **TINY).target_tree(ACTION_DIM)


def hostile_payloads(marker) -> dict[str, dict]:
    """Trees that would create ``marker`` if any of their targets were called."""
    m = str(marker)
    return {
        "os.system": {"_target_": "os.system", "_args_": [f"touch {m}"]},
        "subprocess.call": {"_target_": "subprocess.call", "_args_": [["touch", m]]},
        "builtins.eval": {"_target_": "builtins.eval", "_args_": [f"open({m!r}, 'w')"]},
        "builtins.exec": {"_target_": "builtins.exec", "_args_": [f"open({m!r}, 'w').close()"]},
        "Path.write_text": {"_target_": "pathlib.Path.write_text", "_args_": [m, "x"]},
        # through modules that are trusted: the walk reaches os / pathlib / importlib from our own modules
        "our os": {"_target_": "stable_worldmodel.wm.utils.os.system", "_args_": [f"touch {m}"]},
        "our Path": {"_target_": "stable_worldmodel.wm.utils.Path.write_text", "_args_": [m, "x"]},
        "dunder": {"_target_": "stable_worldmodel.wm.lewm.LeWM.__init__.__globals__", "_args_": []},
        "torch.load via torch.nn": {"_target_": "torch.nn.functional.torch.load", "_args_": [m]},
        "transformers method": {"_target_": "transformers.AutoModel.from_pretrained", "_args_": [m]},
        "partial": {"_target_": "os.system", "_partial_": True, "_args_": [f"touch {m}"]},
    }


def write_run(folder, tree, model=None) -> None:
    """A checkpoint folder: ``config.json`` = ``tree`` and the weights of ``model`` (a tiny LeWM by default)."""
    model = model if model is not None else instantiate(tiny_tree())
    write_checkpoint(model, folder, tree)


@pytest.fixture
def marker(tmp_path):
    path = tmp_path / "PWNED"
    yield path
    assert not path.exists(), "a checkpoint ran code it carries"


@pytest.mark.parametrize("case", list(hostile_payloads("x")))
def test_hostile_top_level_target_is_refused_before_anything_runs(case, marker, _stablewm_home):
    tree = hostile_payloads(marker)[case]
    write_run(_stablewm_home / "checkpoints" / "evil", tree)
    with pytest.raises(UntrustedCheckpointError) as err:
        load_pretrained("evil")
    text = str(err.value)
    assert str(_stablewm_home / "checkpoints" / "evil" / "config.json") in text  # the file
    assert repr(tree["_target_"]) in text and "(top level)" in text  # the target and the key path
    assert "trusted_targets=" in text and "STABLEWM_TRUSTED_TARGETS" in text  # how to trust it


@pytest.mark.parametrize("where", ["predictor", "args", "deep list"])
def test_hostile_target_nested_in_a_lewm_tree_is_refused_with_its_key_path(where, marker, _stablewm_home):
    tree = tiny_tree()
    evil = hostile_payloads(marker)["os.system"]
    if where == "predictor":
        tree["predictor"]["norm"] = evil
        path = "predictor.norm"
    elif where == "args":
        tree["predictor"] = {"_target_": tree["predictor"]["_target_"], "_args_": [evil]}
        path = "predictor._args_[0]"
    else:
        tree["extra"] = [1, {"inner": [evil]}]
        path = "extra[1].inner[0]"
    write_run(_stablewm_home / "checkpoints" / "evil", tree)
    with pytest.raises(UntrustedCheckpointError) as err:
        load_pretrained("evil")
    assert f"at key {path}," in str(err.value)


@pytest.mark.parametrize("loader", [AutoCostModel, AutoActionableModel])
def test_auto_models_refuse_hostile_targets_also_with_pickles_refused(loader, marker, _stablewm_home, monkeypatch):
    monkeypatch.setenv("STABLEWM_REFUSE_PICKLE", "1")
    write_run(_stablewm_home / "checkpoints" / "evil", hostile_payloads(marker)["subprocess.call"])
    with pytest.raises(UntrustedCheckpointError, match="subprocess.call"):
        loader("evil")
    with pytest.raises(UntrustedCheckpointError, match="subprocess.call"):
        loader("evil", allow_pickle=False)


def test_extra_args_cannot_smuggle_a_target(marker, _stablewm_home):
    save_pretrained(instantiate(tiny_tree()), "ok", config=tiny_tree())
    with pytest.raises(UntrustedCheckpointError, match="predictor.norm"):
        load_pretrained("ok", extra_args={"predictor.norm": hostile_payloads(marker)["os.system"]})


def test_trusted_prefix_from_the_caller_or_the_environment(tmp_path, monkeypatch, _stablewm_home):
    (tmp_path / "mylab_models").mkdir()
    (tmp_path / "mylab_models" / "__init__.py").write_text(
        "import torch\n\nclass Net(torch.nn.Linear):\n    def __init__(self, n=3):\n        super().__init__(n, n)\n"
    )
    monkeypatch.syspath_prepend(str(tmp_path))
    folder = _stablewm_home / "checkpoints" / "lab"
    net = torch.nn.Linear(3, 3)
    write_run(folder, {"_target_": "mylab_models.Net", "n": 3}, model=net)
    with pytest.raises(UntrustedCheckpointError, match="mylab_models.Net"):
        load_pretrained("lab")
    assert "mylab_models" not in sys.modules  # refused before it was imported
    model = load_pretrained("lab", trusted_targets=("mylab_models.",))
    assert torch.equal(model.weight, net.weight)
    monkeypatch.setenv("STABLEWM_TRUSTED_TARGETS", "otherlab, mylab_models")
    assert torch.equal(load_pretrained("lab").weight, net.weight)
    # a trusted prefix admits what its package defines, not what it imports
    write_run(folder, {"_target_": "mylab_models.torch.load", "_args_": ["x"]}, model=net)
    with pytest.raises(UntrustedCheckpointError, match="mylab_models.torch.load"):
        load_pretrained("lab")


def test_every_builtin_kind_of_target_still_builds():
    built = instantiate(
        {
            "norm": {"_target_": "torch.nn.BatchNorm1d", "_partial_": True},
            "act": {"_target_": "torch.nn.functional.gelu", "_partial_": True},
            "vit": {
                "_target_": "stable_pretraining.backbone.utils.vit_hf",
                "size": "tiny",
                "image_size": 16,
                "patch_size": 8,
                "num_hidden_layers": 1,
                "hidden_size": 8,
                "num_attention_heads": 2,
            },
            "cfg": {"_target_": "transformers.ViTConfig", "hidden_size": 8},
            "cnn": {
                "_target_": "stable_worldmodel.wm.backbones.create_backbone",
                "name": "cnn_aa",
                "pretrained": False,
            },
        }
    )
    assert built["norm"](4).num_features == 4
    assert built["vit"].config.hidden_size == 8 and built["cfg"].hidden_size == 8
    for name in ("lewm", "pldm", "prejepa", "gcbc", "gciql", "tdmpc2", "dreamer", "dummy"):  # every tree we write
        tree = tiny_tree(name) if name in ("lewm", "pldm") else wm.get_config(name, "tiny").target_tree(ACTION_DIM)
        assert isinstance(instantiate(json.loads(json.dumps(tree))), torch.nn.Module), name


def test_our_functions_that_are_not_factories_are_refused(marker):
    with pytest.raises(UntrustedCheckpointError, match="not a module class or model factory"):
        instantiate({"_target_": "stable_worldmodel.wm.utils.save_pretrained", "_args_": [None, "x"]})
    with pytest.raises(UntrustedCheckpointError, match="trust_remote_code|not a module class"):
        instantiate({"_target_": "transformers.AutoConfig.from_pretrained", "_args_": ["x"], "trust_remote_code": True})
    with pytest.raises(ConfigError, match="trust_remote_code"):
        instantiate(
            {
                "_target_": "stable_worldmodel.wm.backbones.create_backbone",
                "name": "vit_tiny",
                "trust_remote_code": True,
            }
        )


def test_bad_partial_and_args_are_config_errors():
    with pytest.raises(ConfigError, match="_partial_"):
        instantiate({"_target_": "torch.nn.ReLU", "_partial_": "yes"})
    with pytest.raises(ConfigError, match="_args_"):
        instantiate({"_target_": "torch.nn.ReLU", "_args_": "x"})


# -- integrity ---------------------------------------------------------------------------------
@pytest.fixture
def run(_stablewm_home):
    """A run folder as the trainer writes it: weights.pt + config.json + protocol.json (with the sha256)."""
    torch.manual_seed(0)
    model = instantiate(tiny_tree()).eval()
    folder = _stablewm_home / "checkpoints" / "run"
    write_checkpoint(model, folder, tiny_tree(), {"model": "lewm", "image_size": IMAGE})
    return folder


def test_protocol_records_the_weights_sha256_and_loading_checks_it(run):
    import hashlib

    protocol = json.loads((run / "protocol.json").read_text())
    assert protocol["weights_sha256"] == hashlib.sha256((run / "weights.pt").read_bytes()).hexdigest()
    model, got = load_checkpoint("run")
    assert got["weights_sha256"] == protocol["weights_sha256"]


def test_a_flipped_bit_is_a_typed_error_naming_the_file(run):
    data = bytearray((run / "weights.pt").read_bytes())
    data[len(data) // 2] ^= 0x10
    (run / "weights.pt").write_bytes(bytes(data))
    with pytest.raises(CheckpointError, match=r"weights.pt is damaged: its sha256 is"):
        load_pretrained("run")


@pytest.mark.parametrize("with_protocol", [True, False])
def test_a_truncated_file_is_a_typed_error(run, with_protocol):
    if not with_protocol:
        (run / "protocol.json").unlink()
    data = (run / "weights.pt").read_bytes()
    (run / "weights.pt").write_bytes(data[: len(data) // 3])
    with pytest.raises(CheckpointError, match="weights.pt is damaged"):
        load_pretrained("run")


def test_nan_weights_name_the_first_bad_tensor(_stablewm_home):
    model = instantiate(tiny_tree())
    name = [k for k, v in model.state_dict().items() if v.is_floating_point()][3]
    with torch.no_grad():
        model.state_dict()[name].view(-1)[0] = float("nan")
    save_pretrained(model, "nan", config=tiny_tree())
    with pytest.raises(CheckpointError, match=rf"tensor '{name}' has 1 NaN/inf value"):
        load_pretrained("nan")


def test_a_state_dict_of_another_model_is_a_typed_error(run):
    (run / "config.json").write_text(json.dumps(tiny_tree("pldm")))
    (run / "protocol.json").unlink()
    with pytest.raises(CheckpointError, match="do not fit the model"):
        load_pretrained("run")


def test_pickled_objects_in_weights_pt_are_refused(_stablewm_home, marker):
    folder = _stablewm_home / "checkpoints" / "pickled"
    folder.mkdir(parents=True)
    torch.save({"w": torch.zeros(2), "obj": ConfigError("x")}, folder / "weights.pt")
    (folder / "config.json").write_text(
        json.dumps({"_target_": "torch.nn.Linear", "in_features": 1, "out_features": 2})
    )
    with pytest.raises(CheckpointError, match="pickled Python objects"):
        load_pretrained("pickled")


def test_disk_full_while_checkpointing_is_one_typed_error_and_keeps_the_previous_checkpoint(run, tmp_path):
    before = (run / "weights.pt").read_bytes()
    size = len(before)
    script = textwrap.dedent(f"""
        import resource, signal, sys, torch
        sys.path.insert(0, {str(os.path.dirname(__file__))!r})
        from pathlib import Path
        from stable_worldmodel.errors import DiskFullError
        from stable_worldmodel.wm.utils import write_checkpoint
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
        big = torch.nn.Linear(400, 400)
        resource.setrlimit(resource.RLIMIT_FSIZE, ({size + 4096}, {size + 4096}))
        try:
            write_checkpoint(big, Path({str(run)!r}), None)
        except DiskFullError as exc:
            print("DiskFullError:", exc)
    """)
    out = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    assert out.stdout.startswith("DiskFullError: Could not write") and "intact" in out.stdout, out.stdout
    assert "inline_container" not in out.stdout + out.stderr
    assert (run / "weights.pt").read_bytes() == before
    assert not [p for p in run.iterdir() if ".tmp" in p.name]
    load_pretrained("run")  # still loads
    assert issubclass(DiskFullError, OSError)

"""``swm show model TYPE`` lists every key ``swm train`` takes with its default and meaning: each field of
each registered model config, and each training key (``train()``'s arguments). A new field or argument
without a meaning fails here."""

from __future__ import annotations

import dataclasses
import inspect

import pytest

from stable_worldmodel.wm import get_config_class, list_models


@pytest.mark.parametrize("model", list_models())
def test_every_config_field_has_a_meaning(model):
    cls = get_config_class(model)
    meanings = cls.field_help()
    fields = [f.name for f in dataclasses.fields(cls) if f.init]
    assert list(meanings) == fields
    missing = [name for name in fields if not meanings[name].strip()]
    assert not missing, f"{cls.__name__} fields without a meaning (add them to a FIELD_HELP table): {missing}"


def test_every_training_key_has_a_meaning():
    from stable_worldmodel.cli.train import FLAGS, accepted_train_keys
    from stable_worldmodel.train import TRAIN_KEY_HELP, train

    arguments = [name for name, p in inspect.signature(train).parameters.items() if p.kind is not p.VAR_KEYWORD]
    assert sorted(TRAIN_KEY_HELP) == sorted(arguments)  # every argument of train(), and only those
    assert all(TRAIN_KEY_HELP[key].strip() for key in arguments)
    keys = accepted_train_keys()
    assert {"ckpt_every", "log_every", "val_every", "logger", "wandb_project"} <= set(keys)
    # the flags' keys are training keys or config fields (frameskip, source: documented with the fields)
    assert set(FLAGS) - set(keys) == {"frameskip", "source"}


def test_show_model_type_tables_keys_defaults_and_meanings(swm):
    result = swm("show", "model", "lewm")
    assert result.exit_code == 0, result.output
    out = " ".join(result.stdout.replace("│", " ").split())
    assert "Config fields (--set KEY=VALUE, --config FILE) key default meaning" in out
    assert "sigreg_weight 0.09 Weight of SIGReg" in out and "history_size 1 Context frames" in out
    assert "Training keys (their flags, --set KEY=VALUE, --config FILE) key default meaning" in out
    assert "ckpt_every None Steps between two periodic checkpoints" in out
    assert "logger 'tensorboard' Where metrics go" in out and "model (required) The model to train" in out

"""Cache management: datasets, models, worlds."""

from __future__ import annotations

import numpy as np
import pytest

from stable_worldmodel import data, keys


def test_dataset_info_list_delete(make_h5):
    make_h5((3, 4), name="ds")
    target = data.get_cache_dir() / "ds.h5"
    target.write_bytes((make_h5((3, 4), name="tmp")).read_bytes())
    assert data.list_datasets() == ["ds"]
    info = data.dataset_info("ds")
    assert info["num_episodes"] == 2 and info["num_steps"] == 7
    assert info["obs_shape"] == (8, 8, 3) and info["action_shape"] == (2,) and info["goal_shape"] is None
    assert keys.STATE in info["columns"] and info["variation"]["has_variation"] is False
    with pytest.raises(ValueError, match="ds"):
        data.dataset_info("dz")
    leftovers = [target.with_name(f".ds.h5.{kind}") for kind in ("partial", "redo")]  # a killed writer's
    for leftover in leftovers:
        leftover.write_bytes(b"x")
    assert data.delete_dataset("ds") == target
    assert data.list_datasets() == [] and not any(p.exists() for p in leftovers)
    with pytest.raises(KeyError):
        data.delete_dataset("ds")


def test_models():
    root = data.get_cache_dir()
    for name in ("pusht_weights.ckpt", "pusht_weights_epoch_2.ckpt", "pusht_object.ckpt", "other_object.ckpt", "x.txt"):
        (root / name).write_bytes(b"")
    assert data.list_models() == ["other", "pusht"]
    assert len(data.delete_model("pusht")) == 3
    assert data.list_models() == ["other"]
    with pytest.raises(KeyError, match="other"):
        data.delete_model("pusht")


def test_worlds_and_is_image():
    assert "swm/Toy-v0" in data.list_worlds()
    info = data.world_info("swm/Toy-v0", image_shape=(32, 32))
    assert info["action_space"]["type"] == "Box" and info["action_space"]["shape"] == (2,)
    assert info["variation"]["has_variation"] and "agent.color" in info["variation"]["names"]
    assert data.world_info("swm/Toy-v0", image_shape=(32, 32)) is info  # cached
    with pytest.raises(ValueError, match="Toy"):
        data.world_info("swm/Toy-v9")
    assert data.is_image(np.zeros((4, 4, 3), np.uint8))
    assert not data.is_image(np.zeros((4, 4, 3), np.float32))
    assert not data.is_image(np.zeros((4, 4, 2), np.uint8))

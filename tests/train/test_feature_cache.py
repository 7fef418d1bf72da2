"""The frozen-encoder feature cache (``stable_worldmodel.train.features``): computed once per
dataset and encoder, reused by later runs, equal to encoding on the fly, never half-written."""

from __future__ import annotations

import os

import numpy as np
import pytest
import torch

from stable_worldmodel import keys
from stable_worldmodel.train import train
from stable_worldmodel.train.data import TrainData
from stable_worldmodel.train.features import cache_file, feature_fingerprint, load_or_compute_features

#: a tiny PreJEPA (frozen random CNN of 2x2 patches of 8 features, one predictor layer) at 16x16
NET = dict(
    backbone="cnn",
    image_size=16,
    embed_dim=8,
    cnn_width=8,
    cnn_grid=2,
    depth=1,
    heads=2,
    dim_head=4,
    mlp_dim=16,
    history_size=2,
    frameskip=1,
    warmup_steps=0,
    batch_size=4,
)


def _model_and_data(toy, seed=0, **overrides):
    import stable_worldmodel.wm as wm

    cfg = wm.get_config("prejepa", "tiny", **{**NET, **overrides})
    data = TrainData(toy, cfg, seed=seed, device=torch.device("cpu"))
    torch.manual_seed(seed)
    model = wm.make("prejepa", "tiny", action_dim=data.action_dim, **{**NET, **overrides}).eval()
    return cfg, data, model


def test_second_run_reuses_the_features_of_the_first(toy, _stablewm_home):
    first = train("prejepa", toy, steps=2, progress=False, name="a", val_every=0, seed=0, **NET)
    second = train("prejepa", toy, steps=2, progress=False, name="b", val_every=0, seed=0, **NET)
    assert first.features.computed and not second.features.computed
    assert first.features.path == second.features.path and first.features.path.is_file()
    assert first.features.path.parent.parent.name == ".features"  # beside the dataset
    other = train("prejepa", toy, steps=2, progress=False, name="c", val_every=0, seed=1, **NET)
    assert other.features.computed and other.features.path != first.features.path  # other random encoder
    off = train("prejepa", toy, steps=2, progress=False, name="d", val_every=0, seed=0, feature_cache=False, **NET)
    assert off.features is None
    # the blur encoder (the tiny preset's) has no weights but statistics of the training split:
    # the same split reuses the file, another split (seed) fits other statistics and gets its own
    blur = {**NET, "backbone": "blur", "blur_pool": 2}
    b0 = train("prejepa", toy, steps=2, progress=False, name="e", val_every=0, seed=0, **blur)
    b0_again = train("prejepa", toy, steps=2, progress=False, name="f", val_every=0, seed=0, **blur)
    b1 = train("prejepa", toy, steps=2, progress=False, name="g", val_every=0, seed=1, **blur)
    assert b0.features.computed and not b0_again.features.computed and b0.features.path == b0_again.features.path
    assert b1.features.computed and b1.features.path not in (b0.features.path, first.features.path)


def test_cached_batches_equal_encoding_on_the_fly(toy):
    cfg, data, model = _model_and_data(toy)
    index = np.arange(min(6, data.num_train))
    live = data.batch(index)
    cache = load_or_compute_features(
        data.dataset, model.encode_pixels, model.frozen_encoder(), cfg, torch.device("cpu")
    )
    data.use_features(cache.features)
    cached = data.batch(index)
    assert keys.PIXELS not in cached
    torch.testing.assert_close(cached["pixels_emb"], model.encode_pixels(live[keys.PIXELS]), rtol=1e-5, atol=1e-6)
    torch.testing.assert_close(cached[keys.ACTION], live[keys.ACTION])
    with torch.no_grad():
        torch.testing.assert_close(model.loss(cached)["loss"], model.loss(live)["loss"], rtol=1e-5, atol=1e-7)


def test_a_rewritten_dataset_or_another_preprocessing_gets_a_new_file(toy, _stablewm_home):
    cfg, data, model = _model_and_data(toy)
    path = data.dataset.path
    before = feature_fingerprint(model.frozen_encoder(), cfg, path)
    assert feature_fingerprint(model.frozen_encoder(), cfg, path) == before
    cfg.image_mean = (0.4, 0.5, 0.5)
    assert feature_fingerprint(model.frozen_encoder(), cfg, path) != before
    cfg.image_mean = (0.5, 0.5, 0.5)
    stat = os.stat(path)
    os.utime(path, ns=(stat.st_atime_ns, stat.st_mtime_ns + 1_000_000))
    assert feature_fingerprint(model.frozen_encoder(), cfg, path) != before


def test_a_failure_while_filling_leaves_no_cache_file(toy):
    cfg, data, model = _model_and_data(toy)
    calls = []

    def failing(images):
        calls.append(1)
        if len(calls) == 2:
            raise RuntimeError("killed")
        return model.encode_pixels(images)

    with pytest.raises(RuntimeError, match="killed"):
        load_or_compute_features(data.dataset, failing, model.frozen_encoder(), cfg, torch.device("cpu"), chunk_rows=8)
    folder = cache_file(data.dataset.path, "x").parent
    assert not any(folder.iterdir())  # neither the cache nor a .partial
    cache = load_or_compute_features(
        data.dataset, model.encode_pixels, model.frozen_encoder(), cfg, torch.device("cpu"), chunk_rows=8
    )
    assert cache.computed and len(cache.features) == data.dataset.num_rows


def test_a_damaged_cache_is_computed_again(toy):
    cfg, data, model = _model_and_data(toy)
    first = load_or_compute_features(
        data.dataset, model.encode_pixels, model.frozen_encoder(), cfg, torch.device("cpu")
    )
    first.path.write_bytes(b"not a numpy file")
    again = load_or_compute_features(
        data.dataset, model.encode_pixels, model.frozen_encoder(), cfg, torch.device("cpu")
    )
    assert again.computed and len(again.features) == data.dataset.num_rows

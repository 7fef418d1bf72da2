"""With ``frameskip > 1`` a dataset's ``transform`` sees the raw ``(T * frameskip, A)`` action rows,
as the original releases give them (issue 28: every upstream ``column_normalizer`` on ``action``
failed with "size 10 vs 2"); the blocks ``(T, frameskip * A)`` are formed after it, on the item
path and the batched (DataLoader) path alike."""

from __future__ import annotations

import numpy as np
import torch

from stable_worldmodel.data import HDF5Dataset
from stable_worldmodel.data.utils import column_normalizer
from stable_worldmodel.data.writer import HDF5Writer


def _write(path) -> None:
    rng = np.random.default_rng(0)
    episodes = [
        {"action": rng.normal(3.0, 2.0, (n, 2)).astype(np.float32), "state": rng.normal(size=(n, 4)).astype(np.float32)}
        for n in (30, 25)
    ]
    with HDF5Writer(path) as w:
        w.write_episodes(episodes)


def test_a_column_normalizer_on_actions_works_with_frameskip(tmp_path):
    _write(tmp_path / "d.h5")
    plain = HDF5Dataset(tmp_path / "d.h5", frameskip=5, num_steps=2)
    seen = []

    def spy(item):
        seen.append(tuple(item["action"].shape))
        return norm(item)

    norm = column_normalizer(plain, "action", "action")
    data = HDF5Dataset(tmp_path / "d.h5", frameskip=5, num_steps=2, transform=spy)
    item = data[3]
    assert seen == [(10, 2)]  # the raw rows of 2 frames x 5 steps
    assert item["action"].shape == (2, 10) and item["state"].shape == (2, 4)
    raw = plain[3]["action"].reshape(10, 2)
    mean, std = plain.get_col_data("action").mean(0), plain.get_col_data("action").std(0)
    expected = ((raw.numpy() - mean) / std).reshape(2, 10)
    assert np.allclose(item["action"].numpy(), expected, atol=1e-4)
    batch = data.__getitems__([3, 7, 11])  # what a DataLoader calls
    assert all(b["action"].shape == (2, 10) for b in batch)
    assert torch.allclose(batch[0]["action"], item["action"])
    loader = torch.utils.data.DataLoader(data, batch_size=4)
    assert next(iter(loader))["action"].shape == (4, 2, 10)

"""Small tensors leave DataLoader workers by value, large ones through shared memory."""

from __future__ import annotations

import pickle
from multiprocessing.reduction import ForkingPickler

import pytest
import torch

from stable_worldmodel.data import _ipc


@pytest.mark.parametrize("dtype", [torch.float32, torch.float64, torch.int64, torch.uint8, torch.bool])
def test_small_tensors_pickle_by_value(dtype):
    tensor = torch.arange(24).reshape(2, 3, 4).to(dtype)
    for t in (tensor, tensor.transpose(0, 2), tensor[:, 1]):
        fn, args = _ipc._reduce_tensor(t)
        assert fn is torch.from_numpy
        back = fn(*pickle.loads(pickle.dumps(args)))
        assert back.dtype == t.dtype and back.shape == t.shape
        assert torch.equal(back, t)


def test_large_and_special_tensors_keep_torch_sharing():
    from torch.multiprocessing.reductions import reduce_tensor

    big = torch.zeros(_ipc.SMALL_TENSOR_BYTES // 4 + 1)
    for t in (big, torch.zeros(3, requires_grad=True), torch.zeros(3, dtype=torch.bfloat16)):
        fn, _ = _ipc._reduce_tensor(t)
        assert fn is reduce_tensor(t)[0]


def test_prepare_worker_leaves_the_main_process_alone(monkeypatch):
    before = ForkingPickler._extra_reducers.get(torch.Tensor)
    _ipc.prepare_worker()
    assert ForkingPickler._extra_reducers.get(torch.Tensor) is before


def test_prepare_worker_registers_once_in_a_worker(monkeypatch):
    import torch.utils.data

    registered = []
    monkeypatch.setattr(torch.utils.data, "get_worker_info", lambda: object())
    monkeypatch.setattr(ForkingPickler, "register", classmethod(lambda cls, t, fn: registered.append((t, fn))))
    monkeypatch.setattr(_ipc, "_prepared_pid", None)
    _ipc.prepare_worker()
    _ipc.prepare_worker()
    assert registered == [(torch.Tensor, _ipc._reduce_tensor)]


def _mark_registration(item):
    item["by_value"] = torch.tensor(ForkingPickler._extra_reducers.get(torch.Tensor) is _ipc._reduce_tensor)
    return item


def test_dataloader_workers_send_small_tensors_by_value(make_h5):
    from stable_worldmodel.data import HDF5Dataset

    ds = HDF5Dataset(make_h5((6, 6)), num_steps=2, transform=_mark_registration)
    assert not ds[0]["by_value"]  # the main process keeps torch's pickling
    batches = list(torch.utils.data.DataLoader(ds, batch_size=4, num_workers=2))
    assert all(b["by_value"].all() for b in batches)

"""Conversions between the World's numpy infos / actions and a model's torch tensors."""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import Any

import gymnasium as gym
import numpy as np
import torch

from .. import keys
from ..errors import SpaceError

__all__ = ["apply_process", "find_process", "is_image", "prepare_info", "to_env_actions"]


def find_process(process: Mapping[str, Any], key: str) -> Any:
    """The processor of ``key``; a goal key ``goal_<k>`` falls back to the one of ``k``."""
    if key in process:
        return process[key]
    prefix = keys.goal_key("")
    if key.startswith(prefix):
        return process.get(key[len(prefix) :])
    return None


def apply_process(fn: Callable[[np.ndarray], Any], array: np.ndarray) -> np.ndarray:
    """Apply a fitted processor (sklearn style: 2-D in, 2-D out) to ``(..., D)``; shape kept."""
    flat = array.reshape(-1, array.shape[-1]) if array.ndim >= 1 else array.reshape(1, 1)
    out = fn(flat)
    out = out.detach().cpu().numpy() if torch.is_tensor(out) else np.asarray(out)
    return out.reshape(*array.shape[:-1], -1) if array.ndim >= 1 else out.reshape(())


def is_image(value: torch.Tensor) -> bool:
    """``(..., H, W, C)`` uint8 with C in 1, 3, 4: an image batch as the World stores it."""
    from ..data.writer import is_image_column

    return value.ndim >= 3 and is_image_column(tuple(value.shape[-3:]), value.dtype)


def _apply_transform(fn: Callable[[Any], Any], value: torch.Tensor) -> torch.Tensor:
    """Images ``(..., H, W, C)`` go through ``fn`` as one ``(N, C, H, W)`` batch; others as they are."""
    if not is_image(value):
        return fn(value)
    lead = value.shape[:-3]
    batch = value.reshape(-1, *value.shape[-3:]).permute(0, 3, 1, 2)
    out = fn(batch)
    return out.reshape(*lead, *out.shape[1:])


def prepare_info(
    info_dict: Mapping[str, Any],
    process: Mapping[str, Any] | None = None,
    transform: Mapping[str, Callable[[Any], Any]] | None = None,
) -> dict[str, Any]:
    """The World's numpy infos ``(B, T, ...)`` -> a new dict of torch tensors for a model.

    Per key: ``process[key].transform`` (a fitted normalizer, called on the numpy array
    flattened to 2-D ``(-1, D)``; ``goal_<k>`` uses ``process[k]`` when it has none of its
    own), then conversion to torch (string/object arrays are left as numpy), then
    ``transform[key]`` (``goal`` falls back to ``transform["pixels"]``). Image entries
    ``(..., H, W, C)`` uint8 are given to the transform as one ``(N, C, H, W)`` batch and
    come back ``(..., C', H', W')``. The input dict is never modified.
    """
    process, transform = process or {}, transform or {}
    out: dict[str, Any] = {}
    for key, value in info_dict.items():
        proc = find_process(process, key)
        if proc is not None:
            array = value.detach().cpu().numpy() if torch.is_tensor(value) else np.asarray(value)
            value = apply_process(proc.transform, array)
        if isinstance(value, np.ndarray) and value.dtype.kind in "biuf":
            value = torch.from_numpy(np.ascontiguousarray(value))
        fn = transform.get(key, transform.get(keys.PIXELS) if key == keys.GOAL else None)
        if fn is not None and torch.is_tensor(value):
            value = _apply_transform(fn, value)
        out[key] = value
    return out


def to_env_actions(
    action: Any, process: Mapping[str, Any] | None, action_space: gym.Space, *, steps: bool = False
) -> np.ndarray:
    """Model actions -> numpy env actions for the batched ``action_space`` ``(B, ...)``.

    ``action`` holds ``B * prod(single)`` numbers (any shape, e.g. ``(B, A)``); with
    ``steps=True`` it holds K env steps per env and the result is ``(B, K, *single)``.
    ``process["action"].inverse_transform`` is applied on the 2-D ``(-1, prod(single))``
    view. Box actions are clipped to the bounds and cast to the space dtype; discrete ones
    are rounded to integers and clipped to the valid range.
    """
    array = action.detach().cpu().numpy() if torch.is_tensor(action) else np.asarray(action)
    shape = tuple(action_space.shape)
    b, single = shape[0], shape[1:]
    width = int(np.prod(single, dtype=np.int64))
    per_env = array.size // b if b and array.size % b == 0 else -1
    if per_env < 0 or per_env % width or (not steps and per_env != width):
        what = f"{b} x K x {single}" if steps else f"{b} x {single}"
        raise SpaceError(f"to_env_actions requires {what} actions, got an array of shape {array.shape}")
    proc = (process or {}).get(keys.ACTION)
    if proc is not None:
        array = apply_process(proc.inverse_transform, array.reshape(-1, width))
    low = high = None
    if isinstance(action_space, gym.spaces.Box):
        low, high = action_space.low, action_space.high
    elif isinstance(action_space, gym.spaces.MultiDiscrete):
        low, high = action_space.start, action_space.start + action_space.nvec - 1
    elif isinstance(action_space, gym.spaces.MultiBinary):
        low, high = np.zeros(shape), np.ones(shape)
    if steps:
        array = np.asarray(array).reshape(b, per_env // width, *single)
        low, high = (None, None) if low is None else (np.expand_dims(low, 1), np.expand_dims(high, 1))
    else:
        array = np.asarray(array).reshape(shape)
    if low is None:
        return array.astype(action_space.dtype, copy=False)
    if not isinstance(action_space, gym.spaces.Box):
        array = np.rint(array)
    return np.clip(array, low, high).astype(action_space.dtype, copy=False)

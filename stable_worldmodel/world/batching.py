"""Stacking per-env dicts into batched arrays (and back)."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np


def _placeholder(like: np.ndarray) -> np.ndarray:
    """A 'missing' value shaped like ``like``: NaN for floats, zeros otherwise."""
    if np.issubdtype(like.dtype, np.floating):
        return np.full(like.shape, np.nan, like.dtype)
    return np.zeros(like.shape, like.dtype)


def stack(arrays: Sequence[Any]) -> np.ndarray:
    """``np.stack(arrays)`` (same dtype, same result), 3-4x faster for the small per-step rows of a
    batch: ``np.array`` builds it in one pass. Arrays of different shapes get ``np.stack``'s error."""
    try:
        return np.array(arrays)
    except ValueError:
        return np.stack(arrays)


def stack_dicts(items: Sequence[dict[str, Any]]) -> dict[str, np.ndarray]:
    """Stack a list of per-env dicts into one dict of ``(n, ...)`` arrays.

    A key missing from some envs (e.g. ``variation.*`` requested for one env only) is filled
    with NaN (floats) or zeros so that every entry keeps one row per env.
    """
    if not items:
        return {}
    if len(items) == 1:  # one env: a view with a leading axis, no copy
        return {name: np.asarray(value)[None] for name, value in items[0].items()}
    names: dict[str, None] = {}
    for item in items:
        names.update(dict.fromkeys(item))
    out: dict[str, np.ndarray] = {}
    for name in names:
        present = [np.asarray(item[name]) for item in items if name in item]
        if len(present) == len(items):
            out[name] = stack(present)
        else:
            like = present[0]
            out[name] = stack([np.asarray(it[name]) if name in it else _placeholder(like) for it in items])
    return out


def concat_batches(batches: Sequence[dict[str, np.ndarray]]) -> dict[str, np.ndarray]:
    """Concatenate batched dicts along the env axis (keys missing in a batch are filled)."""
    if len(batches) == 1:
        return batches[0]
    names: dict[str, None] = {}
    for b in batches:
        names.update(dict.fromkeys(b))
    out = {}
    for name in names:
        like = next(b[name] for b in batches if name in b)
        parts = [
            b[name]
            if name in b
            else np.broadcast_to(_placeholder(like[0]), (len(next(iter(b.values()))),) + like.shape[1:])
            for b in batches
        ]
        out[name] = np.concatenate(parts)
    return out


def set_rows(
    target: dict[str, np.ndarray], rows: Sequence[int], update: dict[str, np.ndarray], n: int
) -> dict[str, np.ndarray]:
    """Return a copy of ``target`` (batched over ``n`` envs) whose ``rows`` come from ``update``.

    Arrays are copied, never written in place, so a batch a caller kept stays as it was.
    Keys of ``target`` that ``update`` lacks get placeholders in those rows; new keys get
    placeholders in the other rows.
    """
    rows = np.asarray(rows, dtype=np.intp)
    if len(rows) == n and np.array_equal(rows, np.arange(n)):
        return dict(update)
    out: dict[str, np.ndarray] = {}
    for name in {**dict.fromkeys(target), **dict.fromkeys(update)}:
        current = target.get(name)
        value = update.get(name)
        if value is None:
            fresh = current.copy()
            fresh[rows] = _placeholder(current[0])
        elif current is None or current.shape[1:] != value.shape[1:]:
            fresh = np.empty((n, *value.shape[1:]), value.dtype)
            fresh[:] = _placeholder(value[0])
            fresh[rows] = value
        else:
            fresh = current.astype(np.result_type(current.dtype, value.dtype), copy=True)
            fresh[rows] = value
        out[name] = fresh
    return out

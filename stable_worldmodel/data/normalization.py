"""Per-column scalers fitted on a dataset column, and the item transform that applies one.

A scaler has ``fit(X)`` (rows ``(N, D)``, or ``(N,)`` for a scalar column; rows holding a NaN
are ignored), ``transform`` / ``inverse_transform`` / ``fit_transform`` and ``__call__``.
Inputs are numpy arrays or torch tensors and come back as the same kind (``__call__`` gives
float32 tensors). Statistics are numpy arrays ``(D,)``, so scalers pickle without torch (what a
DataLoader with the ``spawn`` start method needs).

    method        fitted on rows x           maps x to
    ----------    -----------------------    ------------------------------------------
    "zscore"      mean, std per dim          (x - mean) / max(std, eps)
    "percentile"  q_low, q_high per dim      2 (x - q_low) / (q_high - q_low) - 1, clipped to [-1, 1]
    "none"        nothing                    x
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..errors import ConfigError, UnknownNameError, did_you_mean

__all__ = ["ColumnTransform", "IdentityScaler", "PercentileScaler", "ZScoreScaler", "get_scaler"]


def _is_tensor(x: Any) -> bool:
    return type(x).__module__.startswith("torch") and hasattr(x, "detach")


def _fit_rows(X: Any, owner: str) -> np.ndarray:
    """``X`` as float64 rows ``(N, D)`` without the rows holding a NaN."""
    arr = X.detach().cpu().numpy() if _is_tensor(X) else np.asarray(X)
    arr = arr.astype(np.float64).reshape(len(arr), -1) if arr.ndim != 1 else arr.astype(np.float64)[:, None]
    arr = arr[~np.isnan(arr).any(axis=1)]
    if not len(arr):
        raise ConfigError(f"{owner}.fit requires at least one row without NaN, got none")
    return arr


def _like(value: np.ndarray, x: Any) -> Any:
    """``value`` as a tensor of ``x``'s dtype and device when ``x`` is a tensor."""
    if _is_tensor(x):
        import torch

        return torch.as_tensor(value, dtype=x.dtype if x.is_floating_point() else torch.float32, device=x.device)
    return value


def _as_float(x: Any) -> Any:
    return x.float() if _is_tensor(x) else x


class IdentityScaler:
    """Leaves values as they are (``method="none"``)."""

    def fit(self, X: Any) -> IdentityScaler:
        return self

    def transform(self, X: Any) -> Any:
        return X

    inverse_transform = transform

    def fit_transform(self, X: Any) -> Any:
        return X

    def __call__(self, X: Any) -> Any:
        return X


class _Scaler:
    """``fit`` computes the statistics, ``transform`` uses them; ``__call__`` = float ``transform``."""

    def _stats(self) -> tuple[np.ndarray, np.ndarray]:
        raise NotImplementedError("_stats() -> (shift, scale) of a fitted scaler")

    def _check_fitted(self) -> None:
        if any(v is None for v in self._stats()):
            raise ConfigError(
                f"{type(self).__name__} requires fit(X) (or statistics given to the constructor) before transform"
            )

    def fit_transform(self, X: Any) -> Any:
        return self.fit(X).transform(X)

    def __call__(self, X: Any) -> Any:
        return _as_float(self.transform(X))


class ZScoreScaler(_Scaler):
    """``(x - mean) / std`` per dimension, ``std`` floored at ``eps``."""

    def __init__(self, mean: Any = None, std: Any = None, eps: float = 1e-8):
        self.mean = None if mean is None else np.asarray(mean, np.float64)
        self.std = None if std is None else np.asarray(std, np.float64)
        self.eps = float(eps)

    def _stats(self) -> tuple[np.ndarray, np.ndarray]:
        return self.mean, self.std

    def fit(self, X: Any) -> ZScoreScaler:
        rows = _fit_rows(X, type(self).__name__)
        self.mean, self.std = rows.mean(axis=0), rows.std(axis=0)
        return self

    def transform(self, X: Any) -> Any:
        self._check_fitted()
        return (X - _like(self.mean, X)) / _like(np.maximum(self.std, self.eps), X)

    def inverse_transform(self, X: Any) -> Any:
        self._check_fitted()
        return X * _like(np.maximum(self.std, self.eps), X) + _like(self.mean, X)


class PercentileScaler(_Scaler):
    """Maps the ``low``-th .. ``high``-th percentiles of each dimension to [-1, 1] and clips."""

    def __init__(self, low: float = 1.0, high: float = 99.0, q_low: Any = None, q_high: Any = None, eps: float = 1e-8):
        if not 0 <= low < high <= 100:
            raise ConfigError(f"PercentileScaler requires 0 <= low < high <= 100, got low={low}, high={high}")
        self.low, self.high, self.eps = float(low), float(high), float(eps)
        self.q_low = None if q_low is None else np.asarray(q_low, np.float64)
        self.q_high = None if q_high is None else np.asarray(q_high, np.float64)

    def _stats(self) -> tuple[np.ndarray, np.ndarray]:
        return self.q_low, self.q_high

    def fit(self, X: Any) -> PercentileScaler:
        rows = _fit_rows(X, type(self).__name__)
        self.q_low, self.q_high = np.percentile(rows, [self.low, self.high], axis=0)
        return self

    def _width(self) -> np.ndarray:
        return np.maximum(self.q_high - self.q_low, self.eps)

    def transform(self, X: Any) -> Any:
        self._check_fitted()
        out = 2 * (X - _like(self.q_low, X)) / _like(self._width(), X) - 1
        return out.clamp(-1, 1) if _is_tensor(out) else np.clip(out, -1, 1)

    def inverse_transform(self, X: Any) -> Any:
        self._check_fitted()
        return (X + 1) * _like(self._width(), X) / 2 + _like(self.q_low, X)


_SCALERS: dict[str, type] = {"zscore": ZScoreScaler, "percentile": PercentileScaler, "none": IdentityScaler}


def get_scaler(method: str = "zscore", **kwargs: Any) -> Any:
    """An unfitted scaler: ``"zscore"``, ``"percentile"`` or ``"none"`` (``kwargs`` go to its constructor)."""
    if method not in _SCALERS:
        raise ConfigError(
            f"get_scaler requires method to be one of {', '.join(map(repr, _SCALERS))}, "
            f"got {method!r}.{did_you_mean(str(method), _SCALERS)}"
        )
    return _SCALERS[method](**kwargs)


class ColumnTransform:
    """Item transform: ``item[target] = scaler(item[source])`` (the item is copied, not changed)."""

    def __init__(self, scaler: Any, source: str, target: str):
        self.scaler, self.source, self.target = scaler, source, target

    def __call__(self, item: dict[str, Any]) -> dict[str, Any]:
        if self.source not in item:
            raise UnknownNameError(
                f"column_normalizer column {self.source!r} not found in the item; it has {sorted(item)}"
            )
        out = dict(item)
        out[self.target] = self.scaler(item[self.source])
        return out

    def __repr__(self) -> str:
        return f"ColumnTransform({type(self.scaler).__name__}, source={self.source!r}, target={self.target!r})"

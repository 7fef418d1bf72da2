"""Leaf spaces (Box, Discrete, MultiDiscrete, RGBBox) and the mixin holding their shared value logic."""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any

import gymnasium as gym
import numpy as np

from ..errors import SpaceError
from ._report import warn

__all__ = ["Box", "Discrete", "MultiDiscrete", "RGBBox", "StatefulSpaceMixin", "rejection_sample", "short_repr"]

_FAST_INT_SPAN = 2**52  # integer boxes wider than this fall back to gymnasium's sampler


def rejection_sample(
    owner: Any,
    draw: Callable[[], Any],
    accept: Callable[[Any], bool] | None,
    max_tries: int = 1000,
    warn_after_s: float | None = 5.0,
) -> Any:
    """Call ``draw()`` until ``accept(candidate)`` holds and return that candidate.

    ``accept=None`` takes the first draw. Logs one warning per call once more than
    ``warn_after_s`` seconds have passed (``None`` disables it); raises ``RuntimeError``
    after ``max_tries`` rejected draws.
    """
    if not isinstance(max_tries, (int, np.integer)) or isinstance(max_tries, bool) or max_tries < 1:
        raise SpaceError(f"{type(owner).__name__}.sample requires max_tries >= 1, got {max_tries!r}")
    if accept is None:
        return draw()
    start = time.perf_counter()
    warned = warn_after_s is None
    for tries in range(1, int(max_tries) + 1):
        candidate = draw()
        if accept(candidate):
            return candidate
        if not warned and time.perf_counter() - start > warn_after_s:
            elapsed = time.perf_counter() - start
            warn(
                f"{type(owner).__name__}.sample: {tries} draws rejected by constrain_fn in {elapsed:.1f} s; "
                "the constraint may be too strict"
            )
            warned = True
    raise RuntimeError(
        f"{type(owner).__name__}.sample requires a constrain_fn that accepts some draw, got {max_tries} "
        f"rejections in a row for {owner!r} (constrain_fn not satisfied after {max_tries} draws); "
        "loosen the constraint or raise max_tries"
    )


def short_repr(x: Any) -> str:
    """Compact text of a value for messages and :meth:`Dict.to_str`."""
    if isinstance(x, np.ndarray):
        return np.array2string(x, precision=4, threshold=12, edgeitems=2, separator=", ")
    return repr(x.item()) if isinstance(x, np.generic) else repr(x)


def constraint_verdict(owner: str, fn: Callable[[Any], Any], result: Any) -> bool:
    """``result`` of ``constrain_fn`` as a bool; SpaceError unless it is a bool or a numpy bool scalar.

    A multi-element array has no truth value and a one-element one hides a shape bug, so both
    are refused rather than guessed at.
    """
    if isinstance(result, (bool, np.bool_)):
        return bool(result)
    name = getattr(fn, "__qualname__", None) or repr(fn)
    shape = f" with shape {result.shape}" if isinstance(result, np.ndarray) else ""
    raise SpaceError(
        f"{owner} requires constrain_fn to return a bool, got {short_repr(result)} ({type(result).__name__}{shape}) "
        f"from {name}; return bool(...) or reduce an array with np.all(...) / np.any(...)"
    )


def _arg(args: tuple, kwargs: dict, index: int, name: str) -> Any:
    """The constructor argument ``name`` (keyword, else positional ``index``), or None when absent."""
    if name in kwargs:
        return kwargs[name]
    return args[index] if len(args) > index else None


def _check_box_bounds(cls: str, low: Any, high: Any) -> None:
    """SpaceError for non-numeric or NaN bounds and for low > high anywhere (before gymnasium sees them)."""
    if low is None or high is None:
        return  # a missing argument: gymnasium's own TypeError says which
    try:
        lo, hi = np.asarray(low, dtype=np.float64), np.asarray(high, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise SpaceError(f"{cls} requires numeric low and high, got low={low!r}, high={high!r}") from exc
    for side, arr, raw in (("low", lo, low), ("high", hi, high)):
        if np.isnan(arr).any():
            raise SpaceError(
                f"{cls} requires {side} without NaN, got {side}={short_repr(raw)}; "
                "use -np.inf / np.inf for an unbounded side"
            )
    try:
        lo_b, hi_b = np.broadcast_arrays(lo, hi)
    except ValueError:
        return  # shapes that do not fit: reported by gymnasium, wrapped in __init__
    bad = lo_b > hi_b
    if bad.any():
        where = tuple(int(i) for i in np.argwhere(bad)[0])
        at = f" (at index {where}: {lo_b[where].item()!r} > {hi_b[where].item()!r})" if where else ""
        raise SpaceError(
            f"{cls} requires low <= high everywhere, got low={short_repr(low)} and high={short_repr(high)}{at}; "
            "swap or fix the bounds"
        )


def _gym_init(cls: str, init: Callable[..., None], args: tuple, kwargs: dict) -> None:
    """``init(*args, **kwargs)`` (the Gymnasium constructor) with its ValueErrors raised as SpaceError."""
    try:
        init(*args, **kwargs)
    except SpaceError:
        raise
    except ValueError as exc:
        shown = ", ".join([*(short_repr(a) for a in args), *(f"{k}={short_repr(v)}" for k, v in kwargs.items())])
        raise SpaceError(f"{cls} requires arguments that Gymnasium accepts, got ({shown}): {exc}") from exc


class StatefulSpaceMixin:
    """Value, init value, constraint and rejection sampling shared by the leaf spaces.

    Put it before the Gymnasium class in the bases; subclasses call :meth:`_setup_state` at the
    end of ``__init__`` and may override :meth:`_draw` and :meth:`_in_base`.
    """

    constrain_fn: Callable[[Any], bool] | None
    _scalar_value = False  # True: a shape-() value is kept as a numpy scalar, not a 0-d array

    # -- hooks --------------------------------------------------------------------------------
    def _draw(self, *args: Any, **kwargs: Any) -> Any:
        """One unconstrained draw (gymnasium's sampler)."""
        return super().sample(*args, **kwargs)  # type: ignore[misc]

    def _in_base(self, x: Any) -> bool:
        """Membership in the Gymnasium space (bounds, shape, dtype), without the constraint."""
        return bool(super().contains(x))  # type: ignore[misc]

    # -- state --------------------------------------------------------------------------------
    def _setup_state(self, init_value: Any, constrain_fn: Callable[[Any], bool] | None) -> None:
        """Store ``constrain_fn`` and ``init_value`` (None stays None; out of bounds is allowed here)."""
        if constrain_fn is not None and not callable(constrain_fn):
            raise SpaceError(f"{type(self).__name__} requires a callable constrain_fn, got {constrain_fn!r}")
        self.constrain_fn = constrain_fn
        self._init_value = None if init_value is None else self._coerce(init_value, "init_value", in_bounds=False)
        self._value = self._init_value

    def _coerce(self, v: Any, what: str = "value", in_bounds: bool = True) -> Any:
        """``v`` as an element of this space's dtype and shape; SpaceError if it does not fit.

        With ``in_bounds=False`` a value outside the bounds is kept (``check()`` reports it later);
        the shape and a lossless cast to the dtype are still required.
        """
        name = f"{self!r}"
        try:
            arr = np.asarray(v)
        except (TypeError, ValueError) as exc:
            raise SpaceError(f"{name} requires a numeric {what}, got {v!r}") from exc
        if arr.shape != self.shape:
            raise SpaceError(
                f"{name} requires {what} of shape {self.shape}, got {short_repr(v)} with shape {arr.shape}"
            )
        if arr.dtype != self.dtype:
            if not (np.issubdtype(arr.dtype, np.number) or arr.dtype == np.bool_):
                raise SpaceError(f"{name} requires a numeric {what}, got {short_repr(v)} of dtype {arr.dtype}")
            with np.errstate(invalid="ignore", over="ignore"):
                cast = arr.astype(self.dtype)
            if np.issubdtype(self.dtype, np.integer) and not np.array_equal(cast, arr):
                raise SpaceError(
                    f"{name} requires {what} of integers that {self.dtype} can hold exactly, got {short_repr(v)}"
                )
            arr = cast
        arr = arr[()] if self._scalar_value else np.array(arr, copy=True)
        if in_bounds and not self._in_base(arr):
            raise SpaceError(f"{name} requires {what} inside its bounds, got {short_repr(v)}")
        return arr

    @property
    def value(self) -> Any:
        """The current element, or None before one is set (a copy for arrays: change it with :meth:`set_value`)."""
        v = self._value
        return v.copy() if isinstance(v, np.ndarray) else v

    @value.setter
    def value(self, v: Any) -> None:
        self.set_value(v)

    @property
    def init_value(self) -> Any:
        """The element :meth:`reset` restores, or None when the space was built without one (a copy for arrays)."""
        v = self._init_value
        return v.copy() if isinstance(v, np.ndarray) else v

    @init_value.setter
    def init_value(self, v: Any) -> None:
        self.set_init_value(v)

    def set_value(self, v: Any) -> None:
        """Make ``v`` the current value (cast to the space dtype; SpaceError if it does not fit)."""
        self._value = self._coerce(v)

    def set_init_value(self, v: Any) -> None:
        """Make ``v`` the value :meth:`reset` restores; the current value is left as it is."""
        self._init_value = self._coerce(v, "init_value")

    def reset(self) -> None:
        """Set the current value back to ``init_value`` (None when the space was built without one)."""
        self._value = self._init_value

    # -- membership ---------------------------------------------------------------------------
    def _satisfies(self, x: Any) -> bool:
        if self.constrain_fn is None:
            return True
        return constraint_verdict(repr(self), self.constrain_fn, self.constrain_fn(x))

    def contains(self, x: Any) -> bool:
        """True when ``x`` is inside the bounds and satisfies ``constrain_fn`` (False for None)."""
        return x is not None and self._in_base(x) and self._satisfies(x)

    def _problem(self) -> str | None:
        """Why the current value is invalid (``"unset"``, ``"out of bounds"``, ``"constrain_fn"``), else None."""
        if self._value is None:
            return "unset"
        if not self._in_base(self._value):
            return "out of bounds"
        return None if self._satisfies(self._value) else "constrain_fn"

    def check(self) -> bool:
        """True when the current value is set, inside the bounds and satisfies ``constrain_fn``.

        Otherwise logs one warning (through ``stable_worldmodel.spaces.logging``) saying which.
        """
        problem = self._problem()
        if problem is None:
            return True
        shown = short_repr(self._value)
        warn(
            {
                "unset": f"{self!r}: value is None (no init_value); give one with set_value() or sample()",
                "out of bounds": f"{self!r}: value {shown} is outside the space bounds",
                "constrain_fn": f"{self!r}: value {shown} does not satisfy constrain_fn",
            }[problem]
        )
        return False

    def seed(self, seed: int | None = None) -> Any:
        """Seed the sampler (numpy integers are accepted)."""
        return super().seed(int(seed) if isinstance(seed, np.integer) else seed)  # type: ignore[misc]

    # -- sampling -----------------------------------------------------------------------------
    def _sample_in_place(
        self, selection: None, args: tuple, kwargs: dict, max_tries: int, warn_after_s: float | None
    ) -> Any:
        """Rejection-sample into ``self._value`` and return the accepted draw (value restored on failure).

        ``selection`` is unused (the same hook on :class:`Dict` takes a sub-selection).
        """
        previous = self._value

        def draw() -> Any:
            self._value = self._draw(*args, **kwargs)
            return self._value

        accept = None if self.constrain_fn is None else self._satisfies
        try:
            return rejection_sample(self, draw, accept, max_tries, warn_after_s)
        except BaseException:
            self._value = previous
            raise

    def sample(
        self,
        *args: Any,
        max_tries: int = 1000,
        warn_after_s: float | None = 5.0,
        set_value: bool = True,
        **kwargs: Any,
    ) -> Any:
        """Draw an element satisfying ``constrain_fn`` (rejection sampling).

        ``*args``/``**kwargs`` (``mask``, ``probability``) go to the Gymnasium sampler. While a
        candidate is tested it is the space's current value, so a ``constrain_fn`` may read it
        through a parent ``Dict.value``. With ``set_value=False`` the previous value is restored.
        Raises ``RuntimeError`` when ``max_tries`` draws are all rejected.
        """
        previous = self._value
        out = self._sample_in_place(None, args, kwargs, max_tries, warn_after_s)
        if not set_value:
            self._value = previous
            return out
        return out.copy() if isinstance(out, np.ndarray) else out


class Box(StatefulSpaceMixin, gym.spaces.Box):
    """A ``gymnasium.spaces.Box`` with a value (None until set when built without ``init_value``).

    Example (circle constraint)::

        space = Box(low=np.array([-1.0, -1.0]), high=np.array([1.0, 1.0]),
                    init_value=np.array([0.0, 0.0]), constrain_fn=lambda p: np.linalg.norm(p) <= 1.0)
        position = space.sample()  # only points inside the unit circle

    ``Box(low, high, shape=(), ...)`` gives scalar factors whose value is a 0-d array.
    Bounded boxes are sampled with one vectorized draw (no gymnasium bookkeeping per call).
    """

    def __init__(self, *args: Any, init_value: Any = None, constrain_fn: Callable | None = None, **kwargs: Any):
        _check_box_bounds(type(self).__name__, _arg(args, kwargs, 0, "low"), _arg(args, kwargs, 1, "high"))
        _gym_init(type(self).__name__, super().__init__, args, kwargs)
        self._fast: tuple[np.ndarray, np.ndarray] | None = None
        self._integer = bool(np.issubdtype(self.dtype, np.integer))
        if self.is_bounded("both") and np.issubdtype(self.dtype, np.number):
            low = self.low.astype(np.float64)
            span = self.high.astype(np.float64) - low
            if np.all(np.isfinite(span)) and (not self._integer or np.all(span < _FAST_INT_SPAN)):
                self._fast = (low, span + 1.0 if self._integer else span)  # integers: floor(u * (span + 1))
        self._setup_state(init_value, constrain_fn)

    def _draw(self, *args: Any, **kwargs: Any) -> np.ndarray:
        if self._fast is None or any(a is not None for a in args) or any(v is not None for v in kwargs.values()):
            return super()._draw(*args, **kwargs)
        low, span = self._fast
        u = self.np_random.random(self.shape)
        if self._integer:
            return np.asarray(low + np.floor(u * span), dtype=self.dtype)  # asarray keeps 0-d arrays for shape ()
        x = np.asarray(low + u * span, dtype=self.dtype)
        return np.minimum(x, self.high, out=x)  # float rounding must not step past high

    def _in_base(self, x: Any) -> bool:
        if not isinstance(x, np.ndarray):  # gymnasium warns on non-arrays; convert quietly
            try:
                x = np.asarray(x, dtype=self.dtype)
            except (TypeError, ValueError):
                return False
        return bool(gym.spaces.Box.contains(self, x))


class Discrete(StatefulSpaceMixin, gym.spaces.Discrete):
    """A ``gymnasium.spaces.Discrete`` with a value (an ``np.int64``, or None until set).

    Example::

        space = Discrete(n=10, init_value=0, constrain_fn=lambda x: x % 2 == 0)
        value = space.sample()  # an even number, also stored in space.value
        space.reset()           # space.value is 0 again
    """

    _scalar_value = True

    def __init__(self, *args: Any, init_value: Any = None, constrain_fn: Callable | None = None, **kwargs: Any):
        n = _arg(args, kwargs, 0, "n")
        if n is not None and (isinstance(n, (bool, np.bool_)) or not isinstance(n, (int, np.integer)) or n < 1):
            raise SpaceError(
                f"{type(self).__name__} requires n to be an integer >= 1 (the number of elements), got {n!r}"
            )
        _gym_init(type(self).__name__, super().__init__, args, kwargs)
        self._setup_state(init_value, constrain_fn)


class MultiDiscrete(StatefulSpaceMixin, gym.spaces.MultiDiscrete):
    """A ``gymnasium.spaces.MultiDiscrete`` with a value (an array, or None until set).

    ``constrain_fn`` receives the whole array. Example::

        space = MultiDiscrete(nvec=[5, 3, 10], init_value=np.array([2, 1, 5]))
        settings = space.sample()
        space.reset()  # back to [2, 1, 5]
    """

    def __init__(self, *args: Any, init_value: Any = None, constrain_fn: Callable | None = None, **kwargs: Any):
        nvec = _arg(args, kwargs, 0, "nvec")
        if nvec is not None:
            need = f"{type(self).__name__} requires nvec as an array of integers >= 1"
            try:
                arr = np.asarray(nvec)
            except (TypeError, ValueError) as exc:
                raise SpaceError(f"{need}, got {nvec!r}") from exc
            if not np.issubdtype(arr.dtype, np.number) or np.issubdtype(arr.dtype, np.complexfloating):
                raise SpaceError(f"{need}, got {short_repr(nvec)}")
            with np.errstate(invalid="ignore"):
                bad = ~(arr >= 1) | (arr != np.floor(arr))  # NaN fails both tests
            if bad.any():
                raise SpaceError(
                    f"{type(self).__name__} requires every nvec entry to be an integer >= 1 (the number of choices), "
                    f"got nvec={short_repr(arr)} with bad entries {short_repr(arr[bad])}"
                )
        _gym_init(type(self).__name__, super().__init__, args, kwargs)
        self._setup_state(init_value, constrain_fn)


class RGBBox(Box):
    """A uint8 ``Box`` in [0, 255] for colors or images; ``shape`` must have a dimension of size 3.

    ``low``, ``high`` and ``dtype`` are fixed (passing them raises SpaceError). Example::

        space = RGBBox(shape=(64, 64, 3), init_value=np.zeros((64, 64, 3), dtype=np.uint8))
    """

    def __init__(self, shape: tuple[int, ...] | int = (3,), *args: Any, init_value: Any = None, **kwargs: Any):
        try:
            shape = (int(shape),) if np.isscalar(shape) else tuple(int(s) for s in shape)
        except (TypeError, ValueError) as exc:
            raise SpaceError(f"RGBBox requires a shape tuple of ints, got {shape!r}") from exc
        if 3 not in shape:
            raise SpaceError(f"RGBBox requires a shape with a channel of size 3 (RGB), got {shape}")
        fixed = sorted({"low", "high", "dtype"} & kwargs.keys())
        if args or fixed:
            raise SpaceError(
                f"RGBBox requires only shape, init_value, constrain_fn and seed (low=0, high=255, dtype=uint8 "
                f"are fixed), got positional {args!r} and keywords {fixed}"
            )
        super().__init__(low=0, high=255, shape=shape, dtype=np.uint8, init_value=init_value, **kwargs)

    def __repr__(self) -> str:
        return f"RGBBox({self.shape})"

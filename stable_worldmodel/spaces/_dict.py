"""``Dict``: a tree of stateful spaces with ordered sampling and dotted names."""

from __future__ import annotations

from collections.abc import Callable, Iterable, Iterator, Mapping
from typing import Any

import gymnasium as gym
import numpy as np

from ..errors import SpaceError, did_you_mean, unknown_name
from ._leaf import StatefulSpaceMixin, constraint_verdict, rejection_sample, short_repr
from ._order import apply_sampling_order
from ._report import SpaceCheckError, warn

__all__ = ["Dict"]

# selection tree for partial resampling: key -> None (the whole subspace) or a nested selection
_Selection = dict[str, "_Selection | None"]


def _route(args: tuple, kwargs: dict, key: str) -> tuple[tuple, dict]:
    """Per-key ``mask``/``probability`` when given as mappings (Gymnasium's Dict convention)."""
    if not args and not kwargs:
        return args, kwargs

    def pick(v: Any) -> Any:
        return v.get(key) if isinstance(v, Mapping) else v

    return tuple(pick(a) for a in args), {n: pick(v) for n, v in kwargs.items()}


class Dict(gym.spaces.Dict):
    """A ``gymnasium.spaces.Dict`` of stateful spaces (leaves or nested ``Dict``).

    - Keys keep insertion order (no sorting) and must be strings without ``"."``.
    - ``sampling_order`` lists keys (or dotted paths) to sample first (dependencies: sample the
      world size before positions inside it); keys it omits are appended with one warning;
      unknown ones raise SpaceError. Nested ``Dict`` spaces keep their own order unless a path
      reaches into them. Reading it gives every node path in order, nested Dicts included
      (``["world", "world.width", ...]``); assigning it reorders sampling.
    - ``constrain_fn(value_dict) -> bool`` sees this Dict's complete nested value. While a
      candidate is tested it is also the space's current value, so a function that reads
      ``env.variation_space.value[...]`` at the top level sees the candidate too (prefer that
      over ``space["a"].value``, as the seed documents). It is enforced by rejection sampling
      in :meth:`sample` and :meth:`update`; a nested Dict's ``constrain_fn`` gets its own subtree.
    - ``init_value`` (nested or dotted, partial allowed) overrides the leaves' own; as for a
      leaf, a value out of bounds is accepted here and reported by :meth:`check`.
    - ``update(keys)`` resamples dotted names (a nested Dict name: its whole subtree); the name
      ``"all"`` is reserved and resamples everything. The space must pass ``check()`` afterwards.
    - ``set_value``/``set_init_value`` take nested or dotted dicts, partial ones too; like the
      leaves' setters they validate bounds, shapes and dtypes but do not call ``constrain_fn``.

    Example::

        config = Dict(
            {"difficulty": Discrete(n=3, init_value=0),
             "world": Dict({"width": Discrete(n=100, init_value=50), "height": Discrete(n=100, init_value=50)}),
             "player_pos": Box(low=np.array([0, 0]), high=np.array([99, 99]), init_value=np.array([25, 25]))},
            sampling_order=["difficulty", "world", "player_pos"],
        )
        state = config.sample()          # nested dict, also stored as config.value
        config.update({"world.width"})   # resample one factor, keep the others
        config.names()                   # ['difficulty', 'world.width', 'world.height', 'player_pos']
    """

    def __init__(
        self,
        *args: Any,
        init_value: Mapping[str, Any] | None = None,
        constrain_fn: Callable[[dict], bool] | None = None,
        sampling_order: Iterable[str] | None = None,
        **kwargs: Any,
    ):
        kwargs.setdefault("sort_keys", False)
        super().__init__(*args, **kwargs)
        for key, space in self.spaces.items():
            self._check_entry(key, space)
        if constrain_fn is not None and not callable(constrain_fn):
            raise SpaceError(f"Dict requires a callable constrain_fn, got {constrain_fn!r}")
        self.constrain_fn = constrain_fn
        self._order = list(self.spaces)
        if sampling_order is not None:
            self.sampling_order = sampling_order
        if init_value is not None:  # like the leaves' init_value: bounds are checked by check(), not here
            for leaf, val in self._resolve_values(init_value, "init_value", in_bounds=False):
                leaf._init_value = leaf._value = val

    # -- structure ------------------------------------------------------------------------------
    @staticmethod
    def _check_entry(key: Any, space: Any) -> None:
        if not isinstance(key, str) or not key or "." in key:
            raise SpaceError(f"Dict requires non-empty string keys without '.', got {key!r}")
        if not isinstance(space, (StatefulSpaceMixin, Dict)):
            raise SpaceError(
                f"Dict requires stable_worldmodel spaces (Box, Discrete, MultiDiscrete, RGBBox, Dict) as values, "
                f"got {type(space).__module__}.{type(space).__name__} for key {key!r}"
            )

    def __getitem__(self, key: str) -> Any:
        """The subspace at ``key``; dotted paths (``"agent.color"``) reach nested spaces."""
        node = self._lookup(key)
        if node is None:
            raise unknown_name("space key", key, self._node_paths())
        return node

    def __setitem__(self, key: str, value: Any) -> None:
        self._check_entry(key, value)
        super().__setitem__(key, value)
        if key not in self._order:
            self._order.append(key)

    def _lookup(self, path: Any) -> Any:
        """The space at dotted ``path`` or None."""
        if not isinstance(path, str):
            return None
        node: Any = self
        for part in path.split("."):
            if not isinstance(node, Dict) or part not in node.spaces:
                return None
            node = node.spaces[part]
        return node

    def _node_paths(self, prefix: str = "") -> Iterator[str]:
        """Dotted paths of every node (nested Dicts and leaves)."""
        for key, space in self.spaces.items():
            yield prefix + key
            if isinstance(space, Dict):
                yield from space._node_paths(f"{prefix}{key}.")

    def _leaves(self, prefix: str = "") -> Iterator[tuple[str, StatefulSpaceMixin]]:
        """(dotted path, leaf) pairs in insertion order."""
        for key, space in self.spaces.items():
            if isinstance(space, Dict):
                yield from space._leaves(f"{prefix}{key}.")
            else:
                yield prefix + key, space

    def _unknown(self, what: str, path: Any) -> SpaceError:
        candidates = list(self._node_paths())
        return SpaceError(
            f"Dict requires {what} naming a variable of this space, got {path!r}.{did_you_mean(str(path), candidates)}"
            f" Known: {candidates}"
        )

    def names(self) -> list[str]:
        """Dotted paths of all leaves, in insertion order (``"a.b"`` for key ``b`` of nested ``a``)."""
        return [path for path, _ in self._leaves()]

    @property
    def sampling_order(self) -> list[str]:
        """Dotted paths of every node in sampling order, nested Dicts included before their children.

        For ``{"a": .., "game": Dict({"world": Dict({"w": .., "h": ..}), "speed": ..})}`` sampled
        game first: ``["game", "game.world", "game.world.w", "game.world.h", "game.speed", "a"]``.
        A new list on every read. Set it to change the order in which :meth:`sample` and
        :meth:`update` draw (rules in :func:`~stable_worldmodel.spaces._order.apply_sampling_order`).
        """
        return list(self._ordered_paths())

    @sampling_order.setter
    def sampling_order(self, order: Iterable[str]) -> None:
        apply_sampling_order(self, order)

    @property
    def _sampling_order(self) -> list[str]:
        """The top-level keys in sampling order: the releases' private attribute, which research
        code reads and sets (setting it: unknown keys refused, missing keys appended)."""
        return list(self._order)

    @_sampling_order.setter
    def _sampling_order(self, keys: Iterable[str]) -> None:
        keys = list(keys)
        unknown = [k for k in keys if k not in self.spaces]
        if unknown:
            raise self._unknown("_sampling_order keys", unknown[0])
        self._order = keys + [k for k in self.spaces if k not in keys]

    def _get_sampling_order(self, parts: tuple[str, ...] | None = None) -> Iterator[str]:
        """Dotted paths in sampling order, each prefixed by ``parts`` (the releases' generator behind
        :attr:`sampling_order`)."""
        yield from self._ordered_paths("".join(f"{p}." for p in parts or ()))

    def _ordered_paths(self, prefix: str = "") -> Iterator[str]:
        for key in self._order:
            yield prefix + key
            space = self.spaces[key]
            if isinstance(space, Dict):
                yield from space._ordered_paths(f"{prefix}{key}.")

    # -- values -----------------------------------------------------------------------------------
    @property
    def value(self) -> dict[str, Any]:
        """Nested dict of the current values."""
        return {key: space.value for key, space in self.spaces.items()}

    @value.setter
    def value(self, v: Mapping[str, Any]) -> None:
        self.set_value(v)

    @property
    def init_value(self) -> dict[str, Any]:
        """Nested dict of the values :meth:`reset` restores (None for a leaf built without one)."""
        return {key: space.init_value for key, space in self.spaces.items()}

    @init_value.setter
    def init_value(self, v: Mapping[str, Any]) -> None:
        self.set_init_value(v)

    def set_value(self, v: Mapping[str, Any]) -> None:
        """Set the named leaves (nested or dotted dict, partial allowed); the others keep their values.

        All values are validated before any is written (SpaceError names the first bad one).
        """
        for leaf, val in self._resolve_values(v, "value"):
            leaf._value = val

    def set_init_value(self, v: Mapping[str, Any]) -> None:
        """Like :meth:`set_value` for the values :meth:`reset` restores (current values unchanged)."""
        for leaf, val in self._resolve_values(v, "init_value"):
            leaf._init_value = val

    def _resolve_values(self, v: Any, what: str, in_bounds: bool = True) -> list[tuple[StatefulSpaceMixin, Any]]:
        if not isinstance(v, Mapping):
            raise SpaceError(f"Dict requires a (nested or dotted) dict as {what}, got {short_repr(v)}")
        pending: list[tuple[StatefulSpaceMixin, Any]] = []
        stack: list[tuple[str, Mapping]] = [("", v)]
        while stack:
            prefix, mapping = stack.pop()
            for key, val in mapping.items():
                path = f"{prefix}{key}"
                node = self._lookup(path)
                if node is None:
                    raise self._unknown(f"{what} keys", path)
                if isinstance(node, Dict):
                    if not isinstance(val, Mapping):
                        raise SpaceError(f"Dict requires a dict for nested space {path!r}, got {short_repr(val)}")
                    stack.append((path + ".", val))
                elif isinstance(val, Mapping):
                    raise SpaceError(f"{node!r} requires an array-like {what} for {path!r}, got a dict")
                else:
                    pending.append((node, node._coerce(val, f"{what} for {path!r}", in_bounds)))
        return pending

    def reset(self) -> None:
        """Reset every leaf to its ``init_value``."""
        for space in self.spaces.values():
            space.reset()

    def seed(self, seed: int | dict | None = None) -> Any:
        """Seed this space; an int seeds every subspace deterministically (numpy ints accepted)."""
        return super().seed(int(seed) if isinstance(seed, np.integer) else seed)

    # -- membership --------------------------------------------------------------------------------
    def contains(self, x: Any) -> bool:
        """True for a dict with exactly these keys whose values are in their subspaces and pass ``constrain_fn``."""
        if not isinstance(x, Mapping) or set(x.keys()) != set(self.spaces):
            return False
        if not all(space.contains(x[key]) for key, space in self.spaces.items()):
            return False
        return self._satisfies(x)

    def _satisfies(self, value: Mapping[str, Any]) -> bool:
        """``constrain_fn(value)`` (True without one); SpaceError when it does not return a bool."""
        if self.constrain_fn is None:
            return True
        return constraint_verdict(f"Dict with keys {list(self.spaces)}", self.constrain_fn, self.constrain_fn(value))

    def _failures(self, prefix: str = "") -> Iterator[str]:
        """Dotted paths of invalid values, each with the reason: ``"a.b (unset)"``, ``"a (constrain_fn)"``.

        A Dict's ``constrain_fn`` is only called when every value below it is valid.
        """
        failed = False
        for key, space in self.spaces.items():
            if isinstance(space, Dict):
                for failure in space._failures(f"{prefix}{key}."):
                    failed = True
                    yield failure
            else:
                problem = space._problem()
                if problem is not None:
                    failed = True
                    yield f"{prefix}{key} ({problem})"
        if not failed and not self._satisfies(self.value):
            yield f"{prefix[:-1] or '<root>'} (constrain_fn)"

    def check(self, debug: bool = False) -> bool:
        """True when every value is set, in bounds and passes the constraints; ``debug`` logs which are not."""
        failed = list(self._failures())
        if failed and debug:
            warn(f"Dict: spaces {failed} failed check()")
        return not failed

    # -- sampling ----------------------------------------------------------------------------------
    def sample(
        self,
        *args: Any,
        max_tries: int = 1000,
        warn_after_s: float | None = 5.0,
        set_value: bool = True,
        **kwargs: Any,
    ) -> dict[str, Any]:
        """Sample every subspace in sampling order until ``constrain_fn`` holds; returns the nested dict.

        ``*args``/``**kwargs`` go to each subspace's ``sample`` (a mapping ``mask`` or
        ``probability`` is split per key). Raises ``RuntimeError`` after ``max_tries`` rejections,
        leaving all values as they were; ``set_value=False`` also restores them after sampling.
        """
        return self._resample(None, args, kwargs, max_tries, warn_after_s, set_value)

    def update(self, keys: Iterable[str] | str) -> None:
        """Resample only the variables named by ``keys`` (dotted paths), in sampling order.

        A key naming a nested Dict resamples its whole subtree; ``"all"`` resamples everything.
        Other leaves keep their values exactly. Unknown keys raise SpaceError (a ValueError).
        Afterwards the whole space must pass :meth:`check` (as in release 0.0.3): if a value
        elsewhere is unset or invalid, the failures are logged, the draws are undone and
        :class:`SpaceCheckError` (also an ``AssertionError``) is raised.
        """
        self._update(keys, require_valid=True)

    def _update(self, keys: Iterable[str] | str, require_valid: bool) -> None:
        keys = [keys] if isinstance(keys, str) else list(keys)
        for key in keys:
            if key != "all" and self._lookup(key) is None:
                raise self._unknown("update keys", key)
        selection = None if "all" in keys else self._selection(keys)
        snapshot = self._snapshot()
        if selection != {}:
            self._resample(selection, (), {}, 1000, 5.0, True, return_value=False)
        failed = list(self._failures()) if require_valid else []
        if failed:
            warn(f"Dict: spaces {failed} failed check()")
            self._restore(snapshot)
            raise SpaceCheckError(
                f"Dict.update requires the other values of the space to be valid, got {failed} after resampling "
                f"{keys}; give those spaces an init_value, or set_value()/sample() them first"
            )

    @staticmethod
    def _selection(keys: list[str]) -> _Selection:
        """The tree of dotted ``keys`` to resample: a key maps to None (whole subspace) or to its selected children."""
        selection: _Selection = {}
        for key in keys:
            *parents, leaf = key.split(".")
            node: _Selection | None = selection
            for part in parents:
                node = node.setdefault(part, {})
                if node is None:  # an ancestor is already resampled whole
                    break
            else:
                node[leaf] = None
        return selection

    def _resample(
        self,
        selection: _Selection | None,
        args: tuple,
        kwargs: dict,
        max_tries: int,
        warn_after_s: float | None,
        set_value: bool,
        return_value: bool = True,
    ) -> dict[str, Any] | None:
        """Resample ``selection`` (None: everything) atomically; return the new nested value."""
        snapshot = self._snapshot()
        try:
            self._sample_in_place(selection, args, kwargs, max_tries, warn_after_s)
        except BaseException:
            self._restore(snapshot)
            raise
        out = self.value if return_value else None
        if not set_value:
            self._restore(snapshot)
        return out

    def _sample_in_place(
        self, selection: _Selection | None, args: tuple, kwargs: dict, max_tries: int, warn_after_s: float | None
    ) -> None:
        """Rejection loop of this level: draw the selected children in order until ``constrain_fn`` holds."""

        def draw() -> None:
            for key in self._order:
                if selection is None:
                    sub = None
                elif key in selection:
                    sub = selection[key]
                else:
                    continue
                sub_args, sub_kwargs = _route(args, kwargs, key)
                self.spaces[key]._sample_in_place(sub, sub_args, sub_kwargs, max_tries, warn_after_s)

        accept = None if self.constrain_fn is None else (lambda _: self._satisfies(self.value))
        rejection_sample(self, draw, accept, max_tries, warn_after_s)

    def _snapshot(self) -> list[tuple[StatefulSpaceMixin, Any]]:
        return [(leaf, leaf._value) for _, leaf in self._leaves()]

    @staticmethod
    def _restore(snapshot: list[tuple[StatefulSpaceMixin, Any]]) -> None:
        for leaf, val in snapshot:
            leaf._value = val

    # -- display -----------------------------------------------------------------------------------
    def to_str(self, indent: int = 0) -> str:
        """The tree as 0.0.3 / 0.1.1 print it: ``name:`` for a Dict, ``name: Box(0, 255, (3,), uint8)`` for a leaf."""
        pad = "    " * indent
        lines = []
        for key, space in self.spaces.items():
            if isinstance(space, Dict):
                lines.append(f"{pad}{key}:")
                lines.append(space.to_str(indent + 1))
            else:
                lines.append(f"{pad}{key}: {_gym_repr(space)}")
        return "\n".join(line for line in lines if line)

    def describe(self, indent: int = 0) -> str:
        """Human-readable tree with more than :meth:`to_str`: sampling order, constraints,
        current and initial values."""
        pad = "  " * (indent + 1)
        head = f"Dict(sampling_order={self._order}{', constrained' if self.constrain_fn else ''})"
        lines = [head]
        for key, space in self.spaces.items():
            if isinstance(space, Dict):
                lines.append(f"{pad}{key}: {space.describe(indent + 1)}")
            else:
                flag = ", constrained" if space.constrain_fn else ""
                lines.append(
                    f"{pad}{key}: {space!r}{flag} = {short_repr(space._value)} (init {short_repr(space._init_value)})"
                )
        return "\n".join(lines)


def _gym_repr(space: Any) -> str:
    """Gymnasium's own text of a leaf (``Box(0, 255, (3,), uint8)``), as 0.0.3's ``to_str`` shows it."""
    for base in type(space).__mro__:
        if base.__module__.startswith("gymnasium.spaces") and "__repr__" in vars(base):
            return base.__repr__(space)
    return repr(space)

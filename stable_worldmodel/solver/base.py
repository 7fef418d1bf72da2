"""BaseSolver: the plumbing shared by every solver.

It owns configuration, dims, device and dtype, info expansion to ``(B, S, ...)`` views,
warm-start padding, seeding, Box bounds and batching over envs; an algorithm subclass
implements only :meth:`BaseSolver._optimize`.
"""

from __future__ import annotations

import contextlib
import logging
import math
import numbers
import os
from collections.abc import Iterator
from dataclasses import dataclass
from typing import Any, ClassVar

import gymnasium as gym
import numpy as np
import torch

from ..errors import ConfigError, SpaceError, check_int, did_you_mean
from ._heap import raise_trim_threshold

logger = logging.getLogger(__name__)

__all__ = ["AUTO_BATCH", "BaseSolver", "PlanKnobs"]


@dataclass(frozen=True)
class PlanKnobs:
    """How the knobs of a plan (``PlanSettings`` / ``swm eval``: samples, iterations, elites) reach
    a solver's constructor, declared once on the solver class (``knobs = PlanKnobs(...)``).

    Each of ``samples``, ``iterations`` and ``elites`` names the constructor argument it goes to,
    or is None when the solver has no such knob; ``fixed`` are constructor arguments it always
    gets; ``summary`` is its one-line description in the CLI's help.
    """

    samples: str | None = "num_samples"
    iterations: str | None = "n_steps"
    elites: str | None = None
    fixed: tuple[tuple[str, Any], ...] = ()
    summary: str = ""

    def kwargs(self, samples: int, iterations: int, elites: int | None) -> dict[str, Any]:
        """Constructor arguments for a plan of ``samples`` candidates, ``iterations`` and ``elites``
        (None: a tenth of the samples, at least 1)."""
        out: dict[str, Any] = dict(self.fixed)
        if self.samples:
            out[self.samples] = samples
        if self.iterations:
            out[self.iterations] = iterations
        if self.elites:
            out[self.elites] = elites if elites is not None else max(1, samples // 10)
        return out


class _AutoBatch(int):
    """Default ``batch_size`` of the sampling solvers.

    It equals 1 and prints as 1 (the original signature's default) but means "auto":
    all envs in one pass, halved on CUDA out-of-memory. Passing a plain ``1`` plans one
    env per pass, like the original.
    """

    def __repr__(self) -> str:
        return "1"

    def __reduce__(self) -> str:
        return "AUTO_BATCH"  # pickle/copy keep the singleton


AUTO_BATCH = _AutoBatch(1)
_OOM = getattr(torch, "OutOfMemoryError", torch.cuda.OutOfMemoryError)
_DEVICE_FORMS = '"cpu", "cuda", "cuda:0", "mps", a torch.device, or None (follow the model)'


#: a CPU plan whose ``get_cost`` calls do less work than this (rows x horizon x model parameters, a
#: stand-in for multiply-adds) runs on one intra-op thread when torch's OpenMP threads sleep between
#: operations (``OMP_WAIT_POLICY=PASSIVE``, which ``swm`` sets): waking them for every small
#: operation costs more than they save. A 1.2M-parameter LeWM planning 1 env x 300 samples x
#: horizon 5 (1.8e9) on 2 cores: 650 -> 360 ms per plan (390 -> 360 beside a busy process); at 4 envs
#: (7.2e9) one thread and two are even, at 10 envs two are 1.34x faster.
ONE_THREAD_WORK = 6e9
#: the least ``torch._dynamo.config.recompile_limit`` that :meth:`BaseSolver.compile_cost` sets: compiled
#: ``get_cost`` graphs kept per model class (one or two per model instance and input shape)
COMPILED_GRAPHS = 64


def _sleeping_omp_threads() -> bool:
    """torch's OpenMP threads were told to sleep between operations (read when they started)."""
    return os.environ.get("OMP_WAIT_POLICY", "").strip().upper() == "PASSIVE"


@contextlib.contextmanager
def _intra_op_threads(n: int | None):
    """Run the block on ``n`` torch intra-op threads (None: as configured), then restore them."""
    before = torch.get_num_threads()
    if n is None or n == before:
        yield
        return
    torch.set_num_threads(n)
    try:
        yield
    finally:
        torch.set_num_threads(before)


def _model_tensor(model: Any) -> torch.Tensor | None:
    """First floating parameter (or buffer) of ``model``, if it is a module."""
    if isinstance(model, torch.nn.Module):
        for tensor in (*model.parameters(), *model.buffers()):
            if tensor.is_floating_point():
                return tensor
    return None


class BaseSolver:
    """Plumbing shared by every solver; subclasses implement :meth:`_optimize`.

    - ``batch_size``: most envs planned in one pass. ``None`` or the default
      :data:`AUTO_BATCH` (which prints as 1) plan all envs together; an explicit int caps
      the chunk. Noise is drawn per env row, so any chunking gives the same plans.
    - ``device``: where tensors live; ``None`` follows the model's parameters (else CPU).
      The dtype follows the model's floating parameters (float32 for parameter-free models).
    - ``seed``: seeds a private ``torch.Generator``; the same seed gives the same sequence
      of plans. :meth:`set_seed` restarts the stream.

    Solvers that set ``_inference_mode`` (CEM, iCEM, MPPI, random shooting) call
    ``get_cost`` under ``torch.inference_mode()``; :meth:`solve` still returns ordinary tensors.
    """

    #: name under which the class is registered (set by ``@register_solver``)
    name: str = ""
    #: run :meth:`_optimize` under ``torch.inference_mode()`` (no autograd bookkeeping, cheaper
    #: per op than ``no_grad``); for solvers that never differentiate through the model
    _inference_mode: bool = False
    #: ``topk`` is the number of elites and cannot be None (CEM, iCEM, MPPI)
    _uses_topk: bool = False
    #: how a plan's samples / iterations / elites reach the constructor (``swm eval --solver``)
    knobs: ClassVar[PlanKnobs] = PlanKnobs()

    def __init__(
        self,
        model: Any,
        batch_size: int | None = AUTO_BATCH,
        num_samples: int = 1,
        var_scale: float = 1.0,
        device: str | torch.device | None = "cpu",
        seed: int = 1234,
        n_steps: int = 1,
        topk: int | None = None,
        *,
        callbacks: Any = None,
    ):
        if not callable(getattr(model, "get_cost", None)):
            raise ConfigError(f"{type(self).__name__} requires a model with get_cost(info, candidates), got {model!r}")
        self._check_common(batch_size=batch_size, num_samples=num_samples, n_steps=n_steps, topk=topk, device=device)
        var_scale = self._check_number("var_scale", var_scale, minimum=0.0)  # 0: no noise
        self.model = model
        self.batch_size = batch_size
        self.num_samples = int(num_samples)
        self.var_scale = var_scale
        self.n_steps = int(n_steps)
        self.topk = int(topk) if topk is not None else None
        self._device_arg = device
        self.seed = seed
        self._seed_rng = np.random.default_rng(seed)
        self._gen: torch.Generator | None = None
        self._space: gym.Space | None = None
        self._config: Any = None
        self._n_envs: int | None = None
        self._auto_chunk: int | None = None
        self._rows = (0, 0)
        self._draw = 0
        self._row_starts: tuple = (None, None)
        self._solve_seed = 0
        self.callbacks = self._check_callbacks(callbacks)
        self._cost_fn: Any = None  # compile_cost's torch.compile of model.get_cost

    # -- callbacks (stable_worldmodel.solver.callbacks) ---------------------------------------
    def _check_callbacks(self, callbacks: Any) -> list:
        if callbacks is None:
            return []
        items = list(callbacks) if isinstance(callbacks, (list, tuple)) else None
        bad = (
            [callbacks]
            if items is None
            else [c for c in items if not (callable(c) and all(hasattr(c, m) for m in ("reset", "start_batch")))]
        )
        if bad:
            raise ConfigError(
                f"{type(self).__name__} requires callbacks to be a list of stable_worldmodel.solver.callbacks.Callback "
                f"instances, got {bad[0]!r}"
            )
        return items

    def _notify(self, **state: Any) -> bool:
        """Call every callback with the iteration's state; True when one asks to stop."""
        stop = False
        for cb in self.callbacks:
            cb(**state)
            stop = stop or bool(getattr(cb, "stop", False))
        return stop

    # -- validation helpers (constructors of every solver) --------------------------------
    def _check_positive(self, **values: Any) -> None:
        """ConfigError unless every value is an integer >= 1 (bools refused)."""
        for key, value in values.items():
            check_int(type(self).__name__, key, value)

    def _check_number(
        self,
        name: str,
        value: Any,
        *,
        minimum: float | None = None,
        strict: bool = False,
        maximum: float | None = None,
        strict_max: bool = True,
    ) -> float:
        """``value`` as a float; ConfigError unless it is a finite real number in the given range.

        ``minimum``/``maximum`` bound it (``strict`` excludes the minimum, ``strict_max`` the maximum).
        Bools, strings, NaN and infinities are refused; one-element tensors are read.
        """
        number: Any = value
        if isinstance(value, torch.Tensor) and value.numel() == 1 and value.dtype != torch.bool:
            number = value.item()
        if minimum is None:
            rule = "" if maximum is None else f" {'<' if strict_max else '<='} {maximum:g}"
        elif maximum is None:
            rule = f" {'>' if strict else '>='} {minimum:g}"
        else:
            rule = f" in {'(' if strict else '['}{minimum:g}, {maximum:g}{')' if strict_max else ']'}"
        ok = isinstance(number, numbers.Real) and not isinstance(number, (bool, np.bool_)) and math.isfinite(number)
        if ok:
            number = float(number)
            if minimum is not None and (number < minimum or (strict and number == minimum)):
                ok = False
            if maximum is not None and (number > maximum or (strict_max and number == maximum)):
                ok = False
        if not ok:
            raise ConfigError(f"{type(self).__name__} requires {name} to be a finite number{rule}, got {value!r}")
        return number

    def _check_common(self, *, batch_size: Any, num_samples: Any, n_steps: Any, topk: Any, device: Any) -> None:
        """The arguments every solver shares: counts, ``topk <= num_samples``, ``batch_size`` and ``device``."""
        name = type(self).__name__
        self._check_positive(num_samples=num_samples, n_steps=n_steps)
        if topk is not None or self._uses_topk:
            self._check_positive(topk=topk)
            if topk > num_samples:
                raise ConfigError(
                    f"{name} requires topk <= num_samples (the elites are drawn from the samples), got "
                    f"topk={topk!r} and num_samples={num_samples!r}; pass topk={num_samples} or less, "
                    "or raise num_samples"
                )
        if batch_size is not None and batch_size is not AUTO_BATCH:
            integer = isinstance(batch_size, (int, np.integer)) and not isinstance(batch_size, (bool, np.bool_))
            if not integer or batch_size < 1:
                raise ConfigError(
                    f"{name} requires batch_size to be an integer >= 1 or None (all envs in one pass), "
                    f"got {batch_size!r}"
                )
        if device is None or isinstance(device, torch.device):
            return
        if isinstance(device, (int, np.integer)) and not isinstance(device, (bool, np.bool_)) and device >= 0:
            return  # an accelerator index; torch.device(0) itself already needs the accelerator
        try:
            if not isinstance(device, str):
                raise TypeError(f"{type(device).__name__} is not a device")
            torch.device(device)  # parses only: a CUDA device without CUDA fails later, in configure
        except (RuntimeError, ValueError, TypeError) as exc:
            hint = ""
            if isinstance(device, str):
                hint = did_you_mean(device.lower(), ("cpu", "cuda", "mps", "xpu", "meta"), n=1)
            hint = "." + hint if hint else ""
            raise ConfigError(f"{name} requires device as {_DEVICE_FORMS}, got {device!r}{hint}") from exc

    # -- configuration -----------------------------------------------------------------
    def configure(self, *, action_space: gym.Space, n_envs: int, config: Any) -> None:
        """Set the batched ``action_space`` (leading dim ``n_envs``) and the ``PlanConfig``. One env's
        ``Box`` (a first dim other than ``n_envs``) is batched to ``n_envs`` envs, as 0.0.3 accepted it."""
        self._check_positive(n_envs=n_envs)
        for attr in ("horizon", "action_block"):
            if not isinstance(getattr(config, attr, None), (int, np.integer)):
                raise ConfigError(f"{type(self).__name__} requires a PlanConfig with {attr}, got {config!r}")
        shape = getattr(action_space, "shape", None)
        if isinstance(action_space, gym.spaces.Box) and shape and shape[0] != n_envs:
            # one env's space (release 0.0.3's examples pass it): every env gets the same bounds
            from gymnasium.vector.utils import batch_space

            action_space = batch_space(action_space, int(n_envs))
            shape = action_space.shape
        if not shape or shape[0] != n_envs:
            raise SpaceError(
                f"{type(self).__name__} requires the batched action space with leading dim n_envs={n_envs}, "
                f"got {action_space!r}"
            )
        self._check_space(action_space)
        self._space, self._config, self._n_envs = action_space, config, int(n_envs)
        ref = _model_tensor(self.model)
        if self._device_arg is None:
            self.device = ref.device if ref is not None else torch.device("cpu")
        else:
            self.device = torch.device(self._device_arg)
        if ref is not None and ref.device.type != self.device.type:
            raise ConfigError(
                f"{type(self).__name__} requires the model on its device {self.device}, got parameters on "
                f"{ref.device}; pass device={str(ref.device)!r} (or device=None) or move the model"
            )
        self.dtype = ref.dtype if ref is not None else torch.float32
        self._gen = torch.Generator(device=self.device)
        if self.device.type == "cpu":
            raise_trim_threshold()  # batched get_cost activations stay in the heap (see _heap.py)
        module = isinstance(self.model, torch.nn.Module)
        self._model_size = sum(p.numel() for p in self.model.parameters()) if module else 0  # see _threads_for
        self._auto_chunk = None
        low, high = self._bounds_arrays(action_space)
        self._low = torch.as_tensor(low, dtype=self.dtype, device=self.device)
        self._high = torch.as_tensor(high, dtype=self.dtype, device=self.device)
        self._bounded = bool(np.isfinite(low).any() or np.isfinite(high).any())
        # one low and one high for every coordinate: clamp with scalars (a broadcast clamp is 4x slower on the CPU)
        low_t, high_t = self._low.cpu().flatten().tolist(), self._high.cpu().flatten().tolist()
        uniform = len(set(low_t)) == 1 and len(set(high_t)) == 1
        self._scalar_bounds = (low_t[0], high_t[0]) if uniform else None
        self._dense_bounds: tuple = (None, None, None)

    def _check_space(self, action_space: gym.Space) -> None:
        """Subclasses restrict the accepted action spaces here (default: Box)."""
        if not isinstance(action_space, gym.spaces.Box):
            raise SpaceError(f"{type(self).__name__} requires a Box action space, got {action_space!r}")

    def _bounds_arrays(self, action_space: gym.Space) -> tuple[np.ndarray, np.ndarray]:
        """Per-env bounds ``(B, A)``: the Box bounds flattened and tiled over ``action_block``."""
        if not isinstance(action_space, gym.spaces.Box):
            inf = np.full((self.n_envs, self.action_dim), np.inf)
            return -inf, inf
        block = self._config.action_block
        low = np.tile(action_space.low.reshape(self.n_envs, -1), (1, block)).astype(np.float64)
        high = np.tile(action_space.high.reshape(self.n_envs, -1), (1, block)).astype(np.float64)
        return low, high

    def _require_configured(self) -> None:
        if self._space is None:
            raise ConfigError(
                f"{type(self).__name__} requires configure(action_space=..., n_envs=..., config=...) before solve; "
                "WorldModelPolicy.set_env does it"
            )

    @property
    def action_space(self) -> gym.Space | None:
        """The batched action space given to :meth:`configure` (None before)."""
        return self._space

    @property
    def config(self) -> Any:
        """The ``PlanConfig`` given to :meth:`configure` (None before)."""
        return self._config

    @property
    def n_envs(self) -> int | None:
        """Number of envs (B); None before :meth:`configure`."""
        return self._n_envs

    @property
    def horizon(self) -> int | None:
        """Planned action blocks (H); None before :meth:`configure`."""
        return None if self._config is None else int(self._config.horizon)

    @property
    def action_dim(self) -> int | None:
        """``prod(single action shape) * action_block`` (A); None before :meth:`configure`."""
        if self._space is None:
            return None
        return int(math.prod(self._space.shape[1:])) * int(self._config.action_block)

    def set_seed(self, seed: int) -> None:
        """Restart the random stream: the next plans repeat those after construction."""
        self.seed = seed
        self._seed_rng = np.random.default_rng(seed)

    # -- solving ------------------------------------------------------------------------
    def __call__(self, info_dict: dict, init_action: torch.Tensor | None = None) -> dict:
        return self.solve(info_dict, init_action=init_action)

    def solve(self, info_dict: dict, init_action: torch.Tensor | None = None) -> dict:
        """Plan for every env.

        ``info_dict`` entries are ``(B, ...)`` (tensors or numpy arrays; numeric ones are
        moved to the solver's device, floating ones cast to its dtype, strings left alone).
        ``init_action: (B, k, A)`` with ``k <= H`` warm-starts the plan (the last ``H - k``
        blocks are padded). Returns ``actions: (B, H, A)`` and ``costs: (B,)`` on the CPU,
        plus what the algorithm adds.
        """
        self._require_configured()
        info = {key: self._to_device(value) for key, value in info_dict.items()}
        init = self._pad_init(init_action)
        self._solve_seed = int(self._seed_rng.integers(0, 2**62))
        while True:
            for cb in self.callbacks:
                cb.reset()
            try:
                parts = [self._optimize_rows(info, init, start, stop) for start, stop in self._chunks()]
                break
            except _OOM:
                chunk = self._chunk_size()
                if not self._auto_batch or chunk == 1:
                    raise
                self._auto_chunk = max(chunk // 2, 1)
                logger.warning("%s ran out of memory; planning %d envs per pass", type(self).__name__, self._auto_chunk)
                if self.device.type == "cuda":
                    torch.cuda.empty_cache()
        out = {}
        for key in parts[0]:
            values = [part[key] for part in parts]
            out[key] = torch.cat(values).cpu() if torch.is_tensor(values[0]) else values
        if self.callbacks:
            out["callbacks"] = {}
            for cb in self.callbacks:
                cb.end_solve()
                out["callbacks"][cb.output_key] = cb.history
        return out

    def _optimize_rows(self, info: dict, init: torch.Tensor | None, start: int, stop: int) -> dict:
        self._rows, self._draw = (start, stop), 0
        for cb in self.callbacks:
            cb.start_batch()
        rows = {key: self._slice(value, start, stop) for key, value in info.items()}
        sub_init = None if init is None else init[start:stop]
        with _intra_op_threads(self._threads_for(stop - start)):
            if not self._inference_mode:
                return self._optimize(rows, sub_init)
            with torch.inference_mode():
                return self._optimize(rows, sub_init)

    def _threads_for(self, envs: int) -> int | None:
        """1 for a small CPU plan of ``envs`` envs while OpenMP threads sleep between operations
        (see :data:`ONE_THREAD_WORK`); None (as configured) otherwise."""
        if self.device.type != "cpu" or not self._model_size or not _sleeping_omp_threads():
            return None
        work = envs * self.num_samples * self.horizon * self._model_size
        return 1 if work < ONE_THREAD_WORK else None

    def _optimize(self, info: dict, init_action: torch.Tensor | None) -> dict:
        """The algorithm: ``info`` rows ``(b, ...)``, ``init_action: (b, H, A)`` or None.

        Returns a dict with ``actions: (b, H, A)``, ``costs: (b,)`` and optional extras,
        all tensors with leading dim b (kept on the device; the base moves them to the CPU).
        """
        raise NotImplementedError("_optimize(info, init_action) -> {'actions': (b, H, A), 'costs': (b,)}")

    @property
    def _auto_batch(self) -> bool:
        """True when all envs go in one pass (``batch_size`` None or the default :data:`AUTO_BATCH`)."""
        return self.batch_size is None or self.batch_size is AUTO_BATCH

    def _chunk_size(self) -> int:
        if self._auto_batch:
            return self._auto_chunk or self.n_envs
        return min(int(self.batch_size), self.n_envs)

    def _chunks(self) -> Iterator[tuple[int, int]]:
        size = self._chunk_size()
        for start in range(0, self.n_envs, size):
            yield start, min(start + size, self.n_envs)

    # -- tensors --------------------------------------------------------------------------
    def _to_device(self, value: Any) -> Any:
        if isinstance(value, np.ndarray) and value.dtype.kind in "biuf":
            value = torch.from_numpy(np.ascontiguousarray(value))
        if torch.is_tensor(value):
            dtype = self.dtype if value.is_floating_point() else value.dtype
            return value.to(device=self.device, dtype=dtype, non_blocking=True)
        return value

    def _slice(self, value: Any, start: int, stop: int) -> Any:
        if (start, stop) == (0, self.n_envs) or not self._is_batched(value):
            return value
        return value[start:stop]

    def _is_batched(self, value: Any) -> bool:
        return isinstance(value, (torch.Tensor, np.ndarray)) and value.ndim >= 1 and value.shape[0] == self.n_envs

    def _expand(self, info: dict, num_samples: int) -> dict:
        """Rows ``(b, ...)`` -> ``(b, S, ...)`` views (torch ``expand`` / numpy ``broadcast_to``)."""
        b = self._rows[1] - self._rows[0]
        out = {}
        for key, value in info.items():
            if torch.is_tensor(value) and value.ndim >= 1 and value.shape[0] == b:
                value = value.unsqueeze(1).expand(b, num_samples, *value.shape[1:])
            elif isinstance(value, np.ndarray) and value.ndim >= 1 and value.shape[0] == b:
                value = np.broadcast_to(value[:, None], (b, num_samples, *value.shape[1:]))
            out[key] = value
        return out

    def compile_cost(self, **options: Any) -> BaseSolver:
        """Score candidates through ``torch.compile(model.get_cost, dynamic=False, **options)``; returns the solver.

        The first plan compiles ``get_cost`` once per shape of its inputs (tens of seconds on a CPU; for a LeWM
        one graph that encodes the context on a plan's first call, one for the calls that reuse it), later plans run
        the compiled code: the model's elementwise operations fused around its matrix products, with less
        Python per call. The costs equal the eager ones up to float rounding (a LeWM's within 1e-5). It pays
        when a run plans many times (``swm eval`` over many episodes); ``swm eval --compile`` turns it on.

        Compiled graphs are kept per ``get_cost`` code: each model instance and input shape adds its own, and
        torch falls back to eager code past ``torch._dynamo.config.recompile_limit`` (8 by default) of them;
        this raises that limit to at least :data:`COMPILED_GRAPHS` (a sweep planning with several checkpoints
        of one model class in one process)."""
        import torch._dynamo

        config = torch._dynamo.config
        config.recompile_limit = max(config.recompile_limit, COMPILED_GRAPHS)
        self._cost_fn = torch.compile(self.model.get_cost, dynamic=False, **options)
        return self

    def _cost(self, info: dict, candidates: torch.Tensor) -> torch.Tensor:
        """``model.get_cost`` on ``candidates: (b, S, H, A)`` -> ``(b, S)`` (shape-checked)."""
        costs = (self._cost_fn or self.model.get_cost)(info, candidates)
        b, s = candidates.shape[:2]
        if tuple(costs.shape) != (b, s):
            if costs.numel() != b * s:
                raise ConfigError(
                    f"{type(self).__name__} requires get_cost to return costs of shape {(b, s)}, "
                    f"got {tuple(costs.shape)}"
                )
            costs = costs.reshape(b, s)
        return costs

    def _pad_init(self, init_action: Any) -> torch.Tensor | None:
        """``(B, k, A)`` with ``k <= H`` -> ``(B, H, A)`` on the device, zero-padded and clamped."""
        if init_action is None:
            return None
        init = torch.as_tensor(init_action).to(device=self.device, dtype=self.dtype)
        b, h, a = self.n_envs, self.horizon, self.action_dim
        if init.ndim != 3 or init.shape[0] != b or init.shape[2] != a or init.shape[1] > h:
            raise ConfigError(
                f"{type(self).__name__} requires init_action of shape ({b}, k <= {h}, {a}), got {tuple(init.shape)}"
            )
        if init.shape[1] < h:
            init = torch.cat([init, init.new_zeros(b, h - init.shape[1], a)], dim=1)
        return self._clamp(init, (0, b))

    def _initial_mean(self, init_action: torch.Tensor | None) -> torch.Tensor:
        """Warm start, else zeros clamped into the bounds, for the current rows: ``(b, H, A)``."""
        if init_action is not None:
            return init_action.clone()
        start, stop = self._rows
        return self._clamp(
            torch.zeros(stop - start, self.horizon, self.action_dim, device=self.device, dtype=self.dtype)
        )

    def _bounds_like(self, x: torch.Tensor, rows: tuple[int, int] | None) -> tuple[torch.Tensor, torch.Tensor]:
        """Bounds of ``rows`` (default: the current rows) shaped to broadcast against ``x: (b, ..., A)``."""
        start, stop = rows or self._rows
        shape = (x.shape[0],) + (1,) * (x.ndim - 2) + (x.shape[-1],)
        return self._low[start:stop].reshape(shape), self._high[start:stop].reshape(shape)

    def _clamp(self, x: torch.Tensor, rows: tuple[int, int] | None = None) -> torch.Tensor:
        """Clamp ``(b, ..., A)`` into the Box bounds of ``rows`` (default: the current rows)."""
        if not self._bounded:
            return x
        return torch.clamp(x, *(self._scalar_bounds or self._bounds_like(x, rows)))

    def _clamp_(self, x: torch.Tensor) -> torch.Tensor:
        """In-place :meth:`_clamp` for the current rows (for freshly made tensors)."""
        if not self._bounded:
            return x
        if self._scalar_bounds is not None:
            return x.clamp_(*self._scalar_bounds)
        if x.device.type != "cpu":
            return x.clamp_(*self._bounds_like(x, None))
        key = (self._rows, x.shape)
        if self._dense_bounds[0] != key:  # a broadcast clamp is 4x slower on the CPU: dense bounds, cached
            with torch.inference_mode(False):  # usable in and out of inference mode
                low, high = self._bounds_like(x, None)
                self._dense_bounds = (key, low.expand(x.shape).contiguous(), high.expand(x.shape).contiguous())
        return x.clamp_(*self._dense_bounds[1:])

    def _reseed(self) -> torch.Generator:
        """The generator for the next draw, seeded by (solve, draw index): chunking-invariant."""
        self._gen.manual_seed((self._solve_seed * 1_000_003 + self._draw) % (2**63))
        self._draw += 1
        return self._gen

    def _randn(self, *tail: int) -> torch.Tensor:
        """Standard normal noise for the current rows: ``(b, *tail)``."""
        gen = self._reseed()
        full = torch.randn((self.n_envs, *tail), generator=gen, device=self.device, dtype=self.dtype)
        start, stop = self._rows
        return full if (start, stop) == (0, self.n_envs) else full[start:stop]

    def _rand(self, *tail: int) -> torch.Tensor:
        """Uniform ``[0, 1)`` noise for the current rows: ``(b, *tail)``."""
        gen = self._reseed()
        full = torch.rand((self.n_envs, *tail), generator=gen, device=self.device, dtype=self.dtype)
        start, stop = self._rows
        return full if (start, stop) == (0, self.n_envs) else full[start:stop]

    def _elites(self, candidates: torch.Tensor, costs: torch.Tensor, k: int) -> tuple[torch.Tensor, torch.Tensor]:
        """The ``k`` cheapest candidates, cheapest first: costs ``(b, k)`` and plans ``(b, k, H, A)``."""
        elite_costs, idx = torch.topk(costs, k, dim=1, largest=False, sorted=True)
        b, s = costs.shape
        if self._row_starts[0] != (b, s, idx.device):  # (b, 1) offsets of each env's first candidate
            with torch.inference_mode(False):
                self._row_starts = ((b, s, idx.device), torch.arange(0, b * s, s, device=idx.device).unsqueeze(1))
        rows = (idx + self._row_starts[1]).view(-1)  # flat candidate index
        elites = candidates.reshape(b * s, -1).index_select(0, rows)  # 2x faster than gather on the CPU
        return elite_costs, elites.view(b, k, *candidates.shape[2:])

    @staticmethod
    def _mean_std(elites: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        """Mean and (biased) std of ``elites: (b, k, H, A)`` over k (faster than ``Tensor.std`` on CPU)."""
        mean = elites.mean(dim=1)
        return mean, (elites - mean.unsqueeze(1)).square_().mean(dim=1).sqrt_()

    def _gaussian_start(self, info: dict, init_action: torch.Tensor | None) -> tuple[torch.Tensor, torch.Tensor, dict]:
        """Start of a sampling solver: ``mean (b, H, A)``, ``std = var_scale`` and the info expanded to S."""
        mean = self._initial_mean(init_action)
        return mean, torch.full_like(mean, self.var_scale), self._expand(info, self.num_samples)

    def _sample_elites(
        self, info_s: dict, mean: torch.Tensor, std: torch.Tensor, k: int
    ) -> tuple[torch.Tensor, torch.Tensor]:
        """One Gaussian round: sample ``num_samples`` around ``mean``, score, return the ``k`` elites."""
        candidates = self._sample_around(mean, std, self.num_samples)
        return self._elites(candidates, self._cost(info_s, candidates), k)

    def _sample_around(self, mean: torch.Tensor, std: torch.Tensor, num_samples: int) -> torch.Tensor:
        """Gaussian candidates ``(b, S, H, A)`` around ``mean: (b, H, A)``; candidate 0 is the mean."""
        noise = self._randn(num_samples, self.horizon, self.action_dim)
        noise[:, 0].zero_()
        candidates = torch.addcmul(mean.unsqueeze(1), std.unsqueeze(1), noise, out=noise)
        return self._clamp_(candidates)

    def __repr__(self) -> str:
        return (
            f"{type(self).__name__}(num_samples={self.num_samples}, "
            f"batch_size={'auto' if self.batch_size is AUTO_BATCH else self.batch_size!r}, "
            f"device={self._device_arg!r}, seed={self.seed})"
        )

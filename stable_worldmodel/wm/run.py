"""A trained run, opened once: what ``swm eval``, ``AutoCostModel``, the planners, the frame
decoder and ``swm show model`` hold of a checkpoint.

``Run.open("wm:NAME" | "gc:NAME" | "NAME" | path)`` parses the name once, resolves its weights file
once (:func:`~stable_worldmodel.wm.utils.resolve_checkpoint`), and reads ``protocol.json`` once into
a typed, validated :class:`RunProtocol`; opening the same unchanged run again in the same process
returns the same :class:`Run`. :meth:`Run.load_model` builds the model (every ``_target_`` checked,
weights read with ``weights_only=True`` and checked, :func:`~stable_worldmodel.wm.utils.load_checkpoint`),
reading the files once per run. :func:`lock_run` is the one-writer lock of a run folder (``swm train``).

``protocol.json`` (ours; upstream checkpoints have none and get upstream's defaults)::

    version            int     layout of this file (absent: written before versioning, read the same)
    model, preset      str     registry name of the model, preset it was trained with
    config             dict    the model config's fields
    dataset            str     dataset name;  dataset_path: where it was;  env: its env id (when recorded)
    train_episodes     [int]   the seeded split;  val_episodes: [int]
    image_size         int     side of the model's input;  image_mean / image_std: per channel
    dataset_image_shape [H, W, C] of the dataset's frames
    action_dim         int     numbers in one env action;  frameskip: env steps per action block
    history_size       int     context frames;  num_preds: predicted frames per sample
    normalizers        dict    column -> {"mean": [...], "std": [...]} (action, proprio, ...)
    steps, steps_done  int     planned and done training steps
    final              dict    {"train_loss", "val_loss"} once the run ended; null while partial
    weights_sha256     str     of the weights file beside it (checked on load)
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from ..errors import CheckpointError, ConfigError, RunBusyError

__all__ = ["PROTOCOL_VERSION", "PREFIXES", "Run", "RunProtocol", "lock_run", "split_spec"]

#: the version :func:`~stable_worldmodel.train.train` writes
PROTOCOL_VERSION = 1
#: ``wm:RUN`` plans with a run, ``gc:RUN`` acts with it
PREFIXES = ("wm", "gc")
#: what an upstream checkpoint (no protocol.json) was trained with: 224 px, ImageNet statistics
_UPSTREAM_IMAGE = (224, (0.485, 0.456, 0.406), (0.229, 0.224, 0.225))


def split_spec(spec: str | os.PathLike) -> tuple[str | None, str]:
    """``"wm:NAME"`` -> ``("wm", "NAME")``; a name or path without a prefix -> ``(None, name)``."""
    text = os.fspath(spec)
    prefix, sep, rest = text.partition(":")
    if sep and prefix in PREFIXES:
        if not rest:
            raise ConfigError(f"A run requires a name after {prefix}:, got {text!r} (e.g. {prefix}:tworoom-lewm)")
        return prefix, rest
    return None, text


def _opt_int(data: Mapping[str, Any], key: str, source: str, minimum: int = 0) -> int | None:
    value = data.get(key)
    if value is None:
        return None
    if isinstance(value, bool) or not isinstance(value, int) or value < minimum:
        raise CheckpointError(f"{source} requires {key} to be an integer >= {minimum} or null, got {value!r}")
    return value


def _opt_str(data: Mapping[str, Any], key: str, source: str) -> str | None:
    value = data.get(key)
    if value is not None and not isinstance(value, str):
        raise CheckpointError(f"{source} requires {key} to be a string or null, got {value!r}")
    return value


def _floats(data: Mapping[str, Any], key: str, source: str, default: tuple[float, ...]) -> tuple[float, ...]:
    value = data.get(key)
    if value is None:
        return default
    try:
        out = tuple(float(v) for v in value)
    except (TypeError, ValueError):
        raise CheckpointError(f"{source} requires {key} to be a list of numbers, got {value!r}") from None
    if not out:
        raise CheckpointError(f"{source} requires {key} to be a non-empty list of numbers, got {value!r}")
    return out


def _ints(data: Mapping[str, Any], key: str, source: str) -> tuple[int, ...] | None:
    value = data.get(key)
    if value is None:
        return None
    if not isinstance(value, (list, tuple)) or not all(isinstance(v, int) and not isinstance(v, bool) for v in value):
        raise CheckpointError(f"{source} requires {key} to be a list of integers, got {str(value)[:80]}")
    return tuple(value)


def _mapping(data: Mapping[str, Any], key: str, source: str) -> dict[str, Any]:
    value = data.get(key)
    if value is None:
        return {}
    if not isinstance(value, Mapping):
        raise CheckpointError(f"{source} requires {key} to be a mapping, got {str(value)[:80]}")
    return dict(value)


@dataclass(frozen=True)
class RunProtocol:
    """``protocol.json``, typed and validated (see the module docstring for the keys).

    ``raw`` keeps the file's mapping as read (``to_dict()``), so keys this version does not know
    travel on unchanged. An upstream checkpoint has no protocol: :meth:`from_dict` of ``{}`` gives
    its defaults (224 px, ImageNet statistics, one frame, frameskip 1).
    """

    version: int = 0
    model: str | None = None
    preset: str | None = None
    config: dict[str, Any] = field(default_factory=dict)
    dataset: str | None = None
    dataset_path: str | None = None
    env: str | None = None
    train_episodes: tuple[int, ...] | None = None
    val_episodes: tuple[int, ...] | None = None
    image_size: int = _UPSTREAM_IMAGE[0]
    image_mean: tuple[float, ...] = _UPSTREAM_IMAGE[1]
    image_std: tuple[float, ...] = _UPSTREAM_IMAGE[2]
    dataset_image_shape: tuple[int, ...] | None = None
    action_dim: int | None = None
    frameskip: int = 1
    history_size: int | None = None
    num_preds: int | None = None
    normalizers: dict[str, Any] = field(default_factory=dict)
    steps: int | None = None
    steps_done: int | None = None
    final: dict[str, Any] | None = None
    weights_sha256: str | None = None
    raw: dict[str, Any] = field(default_factory=dict, repr=False, compare=False)

    @classmethod
    def from_dict(cls, data: Mapping[str, Any], source: str = "protocol.json") -> RunProtocol:
        """Validate ``data`` (a ``protocol.json`` mapping); a bad entry is a
        :class:`~stable_worldmodel.errors.CheckpointError` naming ``source`` and the key."""
        if not isinstance(data, Mapping):
            raise CheckpointError(f"{source} requires a JSON object, got {type(data).__name__}")
        version = _opt_int(data, "version", source) or 0
        if version > PROTOCOL_VERSION:
            raise CheckpointError(
                f"{source} has protocol version {version}, "
                f"newer than this stable-worldmodel reads ({PROTOCOL_VERSION}); "
                "upgrade stable-worldmodel"
            )
        final = data.get("final")
        if final is not None and not isinstance(final, Mapping):
            raise CheckpointError(f"{source} requires final to be a mapping or null, got {final!r}")
        return cls(
            version=version,
            model=_opt_str(data, "model", source),
            preset=_opt_str(data, "preset", source),
            config=_mapping(data, "config", source),
            dataset=_opt_str(data, "dataset", source),
            dataset_path=_opt_str(data, "dataset_path", source),
            env=_opt_str(data, "env", source) or _opt_str(data, "env_id", source),
            train_episodes=_ints(data, "train_episodes", source),
            val_episodes=_ints(data, "val_episodes", source),
            image_size=_opt_int(data, "image_size", source, minimum=1) or _UPSTREAM_IMAGE[0],
            image_mean=_floats(data, "image_mean", source, _UPSTREAM_IMAGE[1]),
            image_std=_floats(data, "image_std", source, _UPSTREAM_IMAGE[2]),
            dataset_image_shape=_ints(data, "dataset_image_shape", source),
            action_dim=_opt_int(data, "action_dim", source, minimum=1),
            frameskip=_opt_int(data, "frameskip", source, minimum=1) or 1,
            history_size=_opt_int(data, "history_size", source, minimum=1),
            num_preds=_opt_int(data, "num_preds", source, minimum=0),
            normalizers=_mapping(data, "normalizers", source),
            steps=_opt_int(data, "steps", source, minimum=0),
            steps_done=_opt_int(data, "steps_done", source, minimum=0),
            final=dict(final) if final is not None else None,
            weights_sha256=_opt_str(data, "weights_sha256", source),
            raw=dict(data),
        )

    def to_dict(self) -> dict[str, Any]:
        """The mapping as read (what older code and the JSON records take)."""
        return dict(self.raw)

    @property
    def trained_here(self) -> bool:
        """Whether ``swm train`` wrote it (an upstream checkpoint has no protocol)."""
        return bool(self.raw)

    @property
    def partial(self) -> bool:
        """A run stopped before its last step: ``final`` is null and fewer steps are done than planned."""
        if self.final is not None or self.steps is None or self.steps_done is None:
            return False
        return self.steps_done < self.steps

    @property
    def frame_size(self) -> tuple[int, int]:
        """``(H, W)`` of the frames the run saw: its dataset's, else its model's input."""
        shape = self.dataset_image_shape
        return (int(shape[0]), int(shape[1])) if shape and len(shape) >= 2 else (self.image_size, self.image_size)


#: (weights path, its stamp, the protocol's stamp) -> (protocol, shared model cache) of the runs opened
_OPENED: dict[tuple, tuple[RunProtocol, dict]] = {}


def _stamp(path: Path) -> tuple[int, int] | None:
    try:
        stat = path.stat()
    except FileNotFoundError:
        return None
    return stat.st_mtime_ns, stat.st_size


@dataclass(eq=False)
class Run:
    """A checkpoint of ``$STABLEWM_HOME/checkpoints`` (or a path), opened by :meth:`open`."""

    spec: str
    prefix: str | None
    name: str
    weights: Path
    protocol: RunProtocol
    #: the model built from the files, per trust setting (shared by every Run of the same unchanged files)
    _models: dict = field(default_factory=dict, repr=False)

    @classmethod
    def open(cls, spec: str | os.PathLike | Run, cache_dir: str | os.PathLike | None = None) -> Run:
        """The run ``spec`` names (``wm:NAME``, ``gc:NAME``, ``NAME``, ``user/repo[@revision]`` or a path;
        ``user/repo`` is looked up in our cache, then in the Hugging Face cache, see
        :func:`~stable_worldmodel.wm.utils.resolve_checkpoint`).

        Missing: ``FileNotFoundError`` naming where it looked, with "did you mean". A damaged
        ``protocol.json``: :class:`~stable_worldmodel.errors.CheckpointError`.
        """
        if isinstance(spec, Run):
            return spec
        from .utils import PROTOCOL_NAME, _read_json, resolve_checkpoint

        prefix, name = split_spec(spec)
        found = resolve_checkpoint(name, cache_dir)
        # the folder made absolute, the file name kept: in the Hugging Face cache the files of a snapshot
        # are links into blobs/, and config.json / protocol.json are beside the link, not its target
        weights = found.parent.resolve() / found.name
        protocol_path = weights.parent / PROTOCOL_NAME
        key = (str(weights), _stamp(weights), _stamp(protocol_path))
        if key not in _OPENED:
            data = _read_json(protocol_path, "the protocol file") if protocol_path.is_file() else {}
            if len(_OPENED) >= 8:  # a long-lived process opening many runs: forget the oldest (and its model)
                _OPENED.pop(next(iter(_OPENED)))
            _OPENED[key] = (RunProtocol.from_dict(data, str(protocol_path)), {})
        protocol, models = _OPENED[key]
        return cls(os.fspath(spec), prefix, name, weights, protocol, models)

    @property
    def folder(self) -> Path:
        return self.weights.parent

    @property
    def policy_name(self) -> str:
        """``wm:NAME`` / ``gc:NAME``: how ``swm eval --policy`` names it (its model's use when unprefixed)."""
        return f"{self.prefix or self.model_prefix}:{self.name}"

    @property
    def model_prefix(self) -> str:
        """How its model is used: ``gc`` for the goal-conditioned policies, ``wm`` for the others."""
        from ._registry import get_config_class, list_models

        model = self.protocol.model
        return get_config_class(model).eval_prefix if model in list_models() else "wm"

    def _read(self, trusted_targets: Any) -> Any:
        from .utils import load_checkpoint

        # config and weights are read, checked and built once per (files, trust); callers get copies
        trust = tuple(trusted_targets) if isinstance(trusted_targets, (list, tuple)) else trusted_targets
        if trust not in self._models:
            loaded = load_checkpoint(self.weights, trusted_targets=trusted_targets, protocol=self.protocol.raw)
            self._models[trust] = loaded[0]
        return self._models[trust]

    def load_model(self, *, trusted_targets: Any = None) -> Any:
        """The run's model in eval mode on the CPU (:func:`~stable_worldmodel.wm.utils.load_checkpoint`).

        The files are read and checked once per run; each call returns its own copy, which the
        caller may move or change."""
        import copy

        return copy.deepcopy(self._read(trusted_targets))


def lock_run(folder: Path, run: str) -> Any:
    """Hold the one-writer lock of run folder ``folder`` (``checkpoints/.<run>.lock``; see
    :mod:`stable_worldmodel.data._lock`: it dies with its holder) or raise
    :class:`~stable_worldmodel.errors.RunBusyError` naming the holder. Release it with ``.release()``."""
    from ..data._lock import WriterLock

    def busy(holder: str) -> RunBusyError:
        return RunBusyError(
            f"Run {run!r} requires a single trainer, got one already training it: {holder}; "
            f"let it finish (or stop it), or train under another --name"
        )

    folder.parent.mkdir(parents=True, exist_ok=True)
    return WriterLock(folder, busy=busy).acquire()

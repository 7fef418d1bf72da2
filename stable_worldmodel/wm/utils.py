"""Checkpoints in upstream 0.1.1's ``save_pretrained`` layout, loaded without hydra::

    $STABLEWM_HOME/checkpoints/<run>/
        weights.pt      the model's state_dict (torch.save; loaded with weights_only=True)
        config.json     the model as a ``_target_`` tree (hydra's instantiate format)
        protocol.json   ours only: what planning needs (normalizers, action block, image
                        preprocessing, dataset, split, training recipe)

``load_pretrained(name)`` accepts a ``.pt`` file (``config.json`` beside it), a folder
holding exactly one ``.pt``, or ``<user>/<repo>``, looked up only in
``checkpoints/models--<user>--<repo>/`` (nothing is ever downloaded). Relative paths are
taken under ``checkpoints/``. :func:`instantiate` resolves upstream's ``_target_`` names
(``stable_worldmodel.wm.lewm.LeWM``, ``stable_pretraining.backbone.utils.vit_hf``, ...)
to our classes; ``_partial_`` gives a ``functools.partial``. A checkpoint never runs code it
carries: ``_target_`` names outside the trusted prefixes are refused before anything is
imported (:mod:`stable_worldmodel.wm.trust`), and weights are read with ``weights_only=True``.
"""

from __future__ import annotations

import functools
import hashlib
import io
import json
import logging
import os
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from ..errors import CheckpointError, ConfigError, DiskFullError, is_disk_full

logger = logging.getLogger(__name__)

__all__ = [
    "checkpoint_root",
    "instantiate",
    "load_checkpoint",
    "load_pretrained",
    "read_protocol",
    "resolve_checkpoint",
    "save_pretrained",
    "write_checkpoint",
]

CONFIG_NAME = "config.json"
PROTOCOL_NAME = "protocol.json"
WEIGHTS_NAME = "weights.pt"

#: ``_target_`` names of upstream's configs that live elsewhere here
TARGET_ALIASES = {
    "stable_pretraining.backbone.utils.vit_hf": "stable_worldmodel.wm.encoders.vit_hf",
    "stable_pretraining.backbone.vit_hf": "stable_worldmodel.wm.encoders.vit_hf",
    # the wrappers upstream's goal-conditioned scripts put around heads and encoders
    **{
        f"stable_pretraining.{where}{name}": f"stable_worldmodel.wm.gcrl.module.{name}"
        for where in ("", "backbone.", "backbone.utils.")
        for name in ("TeacherStudentWrapper", "EvalOnly")
    },
}


def checkpoint_root(cache_dir: str | os.PathLike | None = None) -> Path:
    """``<cache_dir or $STABLEWM_HOME>/checkpoints`` (not created)."""
    if cache_dir is None:
        from ..data import get_cache_dir

        cache_dir = get_cache_dir()
    return Path(cache_dir).expanduser() / "checkpoints"


# -- instantiate ------------------------------------------------------------------------------
def _locate(target: str, trusted_targets: Any = None) -> Any:
    """The callable a ``_target_`` names, if a checkpoint may call it (see :mod:`.trust`)."""
    from .trust import resolve_targets

    return resolve_targets({"_target_": target}, trusted_targets=trusted_targets, aliases=TARGET_ALIASES)[target]


def _build(config: Any, resolved: Mapping[str, Any]) -> Any:
    if isinstance(config, Mapping):
        if "_target_" not in config:
            return {k: _build(v, resolved) for k, v in config.items()}
        target = config["_target_"]
        fn = resolved[target]
        args = [_build(v, resolved) for v in config.get("_args_", [])]
        kwargs = {k: _build(v, resolved) for k, v in config.items() if not k.startswith("_")}
        if config.get("_partial_", False):
            return functools.partial(fn, *args, **kwargs)
        try:
            return fn(*args, **kwargs)
        except TypeError as exc:
            raise ConfigError(f"instantiate could not call {target} with {sorted(kwargs)}: {exc}") from exc
    if isinstance(config, (list, tuple)):
        return [_build(v, resolved) for v in config]
    return config


def instantiate(config: Any, *, trusted_targets: Any = None, source: str | os.PathLike | None = None) -> Any:
    """Build objects from a ``_target_`` tree (a subset of hydra's ``instantiate``).

    Dicts with ``_target_`` are called with their other keys (built depth first; keys
    starting with ``_`` other than ``_args_`` are ignored); ``_partial_: true`` returns a
    ``functools.partial``; lists and plain dicts are walked. Every ``_target_`` of the tree is
    checked first (:mod:`stable_worldmodel.wm.trust`): outside ``stable_worldmodel`` modules,
    ``torch.nn`` and transformers models, and the prefixes in ``trusted_targets`` /
    ``$STABLEWM_TRUSTED_TARGETS``, it is an
    :class:`~stable_worldmodel.errors.UntrustedCheckpointError` (naming ``source``) before
    anything is imported or called.
    """
    from .trust import resolve_targets

    resolved = resolve_targets(config, source=source, trusted_targets=trusted_targets, aliases=TARGET_ALIASES)
    return _build(config, resolved)


# -- save -------------------------------------------------------------------------------------


def _fsync_dir(folder: Path) -> None:
    try:
        fd = os.open(folder, os.O_RDONLY)
    except OSError:  # a platform without directory fds: the rename is still atomic
        return
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


def _atomic_write(path: Path, write: Any) -> None:
    """``write(tmp)`` then fsync and rename over ``path``: a crash leaves the old file or the new one.
    A full disk (or a file-size limit) is a :class:`~stable_worldmodel.errors.DiskFullError`."""
    tmp = path.with_name(f".{path.name}.tmp{os.getpid()}")
    try:
        write(tmp)
        with open(tmp, "rb+") as f:
            os.fsync(f.fileno())
        os.replace(tmp, path)
        _fsync_dir(path.parent)
    except OSError as exc:
        if is_disk_full(exc):
            raise DiskFullError(
                f"Could not write {path}: {os.strerror(exc.errno)}; the file it would replace is intact. "
                "Free some space and try again (swm train: --resume continues from the last checkpoint)."
            ) from exc
        raise
    finally:
        if tmp.exists():
            tmp.unlink()


def _write_bytes(data: Any) -> Any:
    def write(p: Path) -> None:
        with open(p, "wb") as f:
            f.write(data)

    return write


def serialize_state(state: Mapping[str, Any]) -> bytes:
    """``torch.save`` of ``state`` into memory (written by us, so a full disk is an OSError with its errno)."""
    import torch

    buf = io.BytesIO()
    torch.save(dict(state), buf)
    return buf.getvalue()


def _json_ready(config: Any) -> Any:
    if hasattr(config, "_content") and type(config).__module__.startswith("omegaconf"):
        from omegaconf import OmegaConf  # an OmegaConf config: resolve it like upstream

        return OmegaConf.to_container(config, resolve=True)
    return config


def _write_json(path: Path, data: Any) -> None:
    text = json.dumps(data, indent=2, default=lambda o: o.tolist() if hasattr(o, "tolist") else str(o))
    _atomic_write(path, lambda p: p.write_text(text + "\n"))


def write_checkpoint(
    model: Any,
    folder: Path,
    config: Mapping[str, Any] | None,
    protocol: Mapping[str, Any] | None = None,
    filename: str = WEIGHTS_NAME,
) -> Path:
    """Write ``folder/<filename>`` (the state dict), ``config.json`` and ``protocol.json`` (each
    when given), every file through a temporary name, fsynced, then renamed. The protocol records
    the weights' sha256 (``weights_sha256``), which :func:`load_checkpoint` checks. Returns the
    weights path."""
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / filename
    data = serialize_state({k: v.detach().cpu() for k, v in model.state_dict().items()})
    _atomic_write(path, _write_bytes(data))
    if config is not None:
        _write_json(folder / CONFIG_NAME, _json_ready(config))
    if protocol is not None:
        _write_json(
            folder / PROTOCOL_NAME,
            {**protocol, "weights_file": filename, "weights_sha256": hashlib.sha256(data).hexdigest()},
        )
    return path


def save_pretrained(
    model: Any,
    run_name: str,
    config: Mapping[str, Any] | None = None,
    config_key: str | None = None,
    filename: str = WEIGHTS_NAME,
    cache_dir: str | os.PathLike | None = None,
) -> Path:
    """Write ``model.state_dict()`` to ``<cache>/checkpoints/<run_name>/<filename>`` and, when
    given, ``config`` (or ``config[config_key]``) as ``config.json``. Files are written to
    a temporary name and renamed, so a crash never leaves half a checkpoint. Returns the
    weights path."""
    if not run_name or not isinstance(run_name, str):
        raise ConfigError(f"save_pretrained requires a run name, got {run_name!r}")
    folder = checkpoint_root(cache_dir) / run_name
    path = write_checkpoint(model, folder, None, filename=filename)
    if config is None:
        logger.warning(
            "save_pretrained(%r) got no config: load_pretrained will not be able to rebuild the model", run_name
        )
        return path
    config = _json_ready(config)
    if config_key is not None and config_key in config:
        config = config[config_key]
    _write_json(folder / CONFIG_NAME, _json_ready(config))
    logger.info("model saved to %s", path)
    return path


# -- resolve and load --------------------------------------------------------------------------
def _where_to_put(repo: str, root: Path) -> str:
    folder = root / f"models--{repo.replace('/', '--')}"
    return f"put its {WEIGHTS_NAME} and {CONFIG_NAME} in {folder}/ (nothing is downloaded)"


def _folder_weights(folder: Path) -> Path:
    pts = sorted(folder.glob("*.pt"))
    if not pts:
        raise FileNotFoundError(f"load_pretrained requires a .pt file in {folder}, found none")
    if len(pts) > 1:
        raise ConfigError(
            f"load_pretrained requires exactly one .pt file in {folder}, got {len(pts)}: "
            f"{', '.join(p.name for p in pts)}; pass the file itself, e.g. {folder / pts[0].name}"
        )
    return pts[0]


def resolve_checkpoint(name: str | os.PathLike, cache_dir: str | os.PathLike | None = None) -> Path:
    """The weights file of ``name`` (a ``.pt`` file, a folder with one, or ``<user>/<repo>``)."""
    root = checkpoint_root(cache_dir)
    path = Path(name).expanduser()
    local = path if path.is_absolute() else root / path
    if local.suffix == ".pt":
        if not local.is_file():
            raise FileNotFoundError(f"load_pretrained requires an existing checkpoint file, got {local}")
        return local
    if local.is_dir():
        return _folder_weights(local)
    text = str(name)
    if text.count("/") == 1 and not path.is_absolute():
        hub = root / f"models--{text.replace('/', '--')}"
        if hub.is_dir():
            return _folder_weights(hub)
        raise FileNotFoundError(f"Checkpoint {text!r} is not in the local cache: {_where_to_put(text, root)}")
    from ..errors import did_you_mean

    runs = list_checkpoints(cache_dir)
    raise FileNotFoundError(
        f"load_pretrained requires a .pt file, a checkpoint folder or <user>/<repo>, got {text!r} "
        f"(looked in {local}).{did_you_mean(text, runs)} Checkpoints in {root}: {', '.join(runs) or '(none)'}"
    )


def list_checkpoints(cache_dir: str | os.PathLike | None = None) -> list[str]:
    """Folders under ``checkpoints/`` that hold a ``config.json`` and a ``.pt`` file."""
    root = checkpoint_root(cache_dir)
    if not root.is_dir():
        return []
    found = []
    for cfg in root.rglob(CONFIG_NAME):
        if any(cfg.parent.glob("*.pt")):
            found.append(cfg.parent.relative_to(root).as_posix())
    return sorted(found)


def _read_json(path: Path, what: str) -> Any:
    if not path.is_file():
        raise FileNotFoundError(f"load_pretrained requires {what} {path}, which does not exist")
    try:
        return json.loads(path.read_text())
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise ConfigError(f"load_pretrained requires valid JSON in {path}, got a corrupt file ({exc})") from exc


def read_protocol(weights: Path) -> dict[str, Any]:
    """``protocol.json`` beside ``weights`` (empty for upstream checkpoints)."""
    path = weights.parent / PROTOCOL_NAME
    return _read_json(path, "the protocol file") if path.is_file() else {}


#: ViT layer parameters: (transformers 4.x name, 5.x name) inside ``encoder.layer.<i>.`` / ``layers.<i>.``
_VIT_RENAMES = [
    ("attention.attention.query", "attention.q_proj"),
    ("attention.attention.key", "attention.k_proj"),
    ("attention.attention.value", "attention.v_proj"),
    ("attention.output.dense", "attention.o_proj"),
    ("intermediate.dense", "mlp.fc1"),
    ("output.dense", "mlp.fc2"),
    ("layernorm_before", "layernorm_before"),
    ("layernorm_after", "layernorm_after"),
]


def _vit_rules() -> list[tuple[Any, str]]:
    import re

    rules = []
    for old, new in _VIT_RENAMES:
        rules.append((re.compile(rf"encoder\.layer\.(\d+)\.{re.escape(old)}\."), rf"layers.\1.{new}."))
        rules.append((re.compile(rf"layers\.(\d+)\.{re.escape(new)}\."), rf"encoder.layer.\1.{old}."))
    return rules


def convert_vit_keys(state: Mapping[str, Any], expected: set[str]) -> dict[str, Any]:
    """Rename ViT parameters between the transformers 4.x layout (published checkpoints) and
    the 5.x one, whichever way makes them match ``expected`` (the model's own keys)."""
    if all(k in expected for k in state):
        return dict(state)
    rules = _vit_rules()
    out = {}
    for key, value in state.items():
        if key not in expected:
            for pattern, repl in rules:
                cand = pattern.sub(repl, key, count=1)
                if cand != key and cand in expected:
                    key = cand
                    break
        out[key] = value
    return out


def _apply_overrides(config: dict, extra_args: Mapping[str, Any] | None) -> None:
    for key, value in (extra_args or {}).items():
        node = config
        *parents, leaf = str(key).split(".")
        for part in parents:
            child = node.get(part)
            if not isinstance(child, dict):
                child = node[part] = {}
            node = child
        node[leaf] = value


def _read_weights(weights: Path, protocol: Mapping[str, Any]) -> Mapping[str, Any]:
    """The state dict in ``weights``, checked against the sha256 the run recorded and for NaN/inf."""
    import pickle

    import torch

    try:
        data = weights.read_bytes()
    except OSError as exc:
        raise CheckpointError(f"load_pretrained could not read the weights {weights}: {exc}") from exc
    recorded = protocol.get("weights_sha256")
    if recorded and protocol.get("weights_file", WEIGHTS_NAME) == weights.name:
        actual = hashlib.sha256(data).hexdigest()
        if actual != recorded:
            raise CheckpointError(
                f"load_pretrained: {weights} is damaged: its sha256 is {actual[:16]}..., the run recorded "
                f"{str(recorded)[:16]}... in {PROTOCOL_NAME} when it wrote it ({len(data)} bytes now). "
                "Use another checkpoint of the run (step_<N>/) or train it again."
            )
    try:
        state = torch.load(io.BytesIO(data), map_location="cpu", weights_only=True)
    except pickle.UnpicklingError as exc:
        raise CheckpointError(
            f"load_pretrained refuses {weights}: it holds pickled Python objects, not only tensors, and pickles are "
            f"never loaded from {WEIGHTS_NAME} ({str(exc).splitlines()[0][:200]}). Save the model's state_dict with "
            "stable_worldmodel.wm.utils.save_pretrained."
        ) from exc
    except Exception as exc:  # a damaged zip: torch raises RuntimeError, EOFError, ...
        raise CheckpointError(
            f"load_pretrained: {weights} is damaged or truncated ({len(data)} bytes; "
            f"{type(exc).__name__}: {str(exc).splitlines()[0][:200] if str(exc) else ''})"
        ) from exc
    if not isinstance(state, Mapping):
        raise CheckpointError(f"load_pretrained requires a state_dict in {weights}, got {type(state).__name__}")
    for key, value in state.items():
        if (
            torch.is_tensor(value)
            and (value.is_floating_point() or value.is_complex())
            and not bool(torch.isfinite(value).all())
        ):
            bad = int((~torch.isfinite(value)).sum())
            raise CheckpointError(
                f"load_pretrained: {weights} holds non-finite weights: tensor {key!r} has {bad} NaN/inf value(s) "
                f"of {value.numel()} (the first such tensor); the run diverged or the file was damaged"
            )
    return state


def load_checkpoint(
    name: str | os.PathLike,
    cache_dir: str | os.PathLike | None = None,
    extra_args: Mapping[str, Any] | None = None,
    *,
    trusted_targets: Any = None,
    protocol: Mapping[str, Any] | None = None,
) -> tuple[Any, dict[str, Any]]:
    """``(model, protocol)``: :func:`load_pretrained` plus the ``protocol.json`` of our runs
    (``protocol``: the one already read, as :class:`~stable_worldmodel.wm.run.Run` passes it)."""
    weights = resolve_checkpoint(name, cache_dir)
    config_path = weights.parent / CONFIG_NAME
    config = _read_json(config_path, "the model config")
    if not isinstance(config, dict) or "_target_" not in config:
        raise ConfigError(f"load_pretrained requires a config.json with a top-level _target_, got {config_path}")
    _apply_overrides(config, extra_args)
    from .trust import resolve_targets

    resolved = resolve_targets(config, source=config_path, trusted_targets=trusted_targets, aliases=TARGET_ALIASES)
    protocol = dict(protocol) if protocol is not None else read_protocol(weights)
    state = _read_weights(weights, protocol)
    model = _build(config, resolved)
    state = convert_vit_keys(state, set(model.state_dict()))
    try:
        missing, unexpected = model.load_state_dict(state, strict=False)
    except RuntimeError as exc:  # same keys, other shapes: the config does not describe these weights
        raise CheckpointError(
            f"load_pretrained: the weights {weights} do not fit the model of {CONFIG_NAME} beside them: {exc}"
        ) from exc
    if missing or unexpected:
        raise CheckpointError(
            f"load_pretrained: the weights {weights} do not fit the model of {CONFIG_NAME}: "
            f"missing keys {list(missing)[:8]}, unexpected keys {list(unexpected)[:8]}"
        )
    model.eval()
    return model, protocol


def load_pretrained(
    name: str | os.PathLike,
    cache_dir: str | os.PathLike | None = None,
    extra_args: Mapping[str, Any] | None = None,
    *,
    trusted_targets: Any = None,
) -> Any:
    """Build the model of ``config.json`` and load its weights (see the module docstring).

    ``extra_args`` overrides dotted config keys before building (``{"predictor.dropout": 0}``).
    ``trusted_targets`` (``("mylab.models.",)``) lets the config call more than the built-in
    trusted ``_target_`` prefixes (:mod:`stable_worldmodel.wm.trust`; also
    ``$STABLEWM_TRUSTED_TARGETS``). The weights are read with ``weights_only=True``, checked
    against the sha256 of ``protocol.json`` (runs of ours) and for NaN/inf. The model is
    returned in eval mode.
    """
    return load_checkpoint(name, cache_dir, extra_args, trusted_targets=trusted_targets)[0]

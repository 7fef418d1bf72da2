"""Checkpoints in upstream 0.1.1's ``save_pretrained`` layout, loaded without hydra::

    $STABLEWM_HOME/checkpoints/<run>/
        weights.pt      the model's state_dict (torch.save; loaded with weights_only=True)
        config.json     the model as a ``_target_`` tree (hydra's instantiate format)
        protocol.json   ours only: what planning needs (normalizers, action block, image
                        preprocessing, dataset, split, training recipe)

``load_pretrained(name)`` accepts a ``.pt`` file (``config.json`` beside it), a folder
holding exactly one ``.pt``, or ``<user>/<repo>[@<revision>]``, looked up in
``checkpoints/models--<user>--<repo>/`` first, then in the Hugging Face hub cache
(``$HF_HUB_CACHE``, else ``$HF_HOME/hub``, else ``~/.cache/huggingface/hub``:
``models--<user>--<repo>/snapshots/<commit>/``, the commit named by ``refs/<revision>``, default
``main``). Nothing is downloaded there; :func:`from_pretrained` downloads into the Hugging Face
cache and :func:`push_to_hub` uploads a run (both need ``pip install "stable-worldmodel[hub]"``).
Relative paths are taken under ``checkpoints/``. :func:`instantiate` resolves upstream's ``_target_`` names
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
import re
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from ..errors import CheckpointError, ConfigError, DiskFullError, is_disk_full

logger = logging.getLogger(__name__)

__all__ = [
    "checkpoint_root",
    "from_pretrained",
    "hf_hub_cache",
    "instantiate",
    "load_checkpoint",
    "load_pretrained",
    "push_to_hub",
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
#: a Hub repo id ``<user>/<repo>``: each part letters, digits, ``_ . -`` (starting and ending with
#: a letter, digit or ``_``), at most 96 characters, no ``--`` or ``..`` (huggingface_hub's rules)
_REPO_ID = re.compile(r"(\w|\w[\w.-]{0,94}\w)/(\w|\w[\w.-]{0,94}\w)", re.ASCII)
_COMMIT = re.compile(r"[0-9a-f]{40}")
_HF_FOLDER_PREFIX = "models--"


def _is_repo_id(text: str) -> bool:
    return bool(_REPO_ID.fullmatch(text)) and "--" not in text and ".." not in text


def _check_revision(revision: Any, name: str, who: str = "load_pretrained") -> str:
    """``revision`` when it can name a branch, tag or commit (``main``, ``v1.0``, ``refs/pr/1``, 40 hex digits)."""
    parts = revision.split("/") if isinstance(revision, str) else []
    if not parts or any(p in ("", ".", "..") or p != p.strip() or "\\" in p for p in parts):
        raise ConfigError(
            f"{who} requires a revision (a branch, tag or commit hash such as 'main', 'v1.0' or 40 hex digits) "
            f"after '@', got {revision!r} in {name!r}"
        )
    return revision


def _hub_name(text: str, who: str = "load_pretrained") -> tuple[str, str | None] | None:
    """``(repo_id, revision)`` of ``<user>/<repo>`` or ``<user>/<repo>@<revision>``; None for other names."""
    repo, sep, revision = text.partition("@")
    if not _is_repo_id(repo):
        return None
    return repo, (_check_revision(revision, text, who) if sep else None)


def _hf_home() -> Path:
    home = os.environ.get("HF_HOME") or os.path.join(os.environ.get("XDG_CACHE_HOME") or "~/.cache", "huggingface")
    return Path(os.path.expandvars(home)).expanduser()


def hf_hub_cache() -> Path:
    """The Hugging Face hub cache, as huggingface_hub finds it, read from the environment now:
    ``$HF_HUB_CACHE``, else ``$HUGGINGFACE_HUB_CACHE``, else ``$HF_HOME/hub``, else
    ``$XDG_CACHE_HOME/huggingface/hub``, else ``~/.cache/huggingface/hub`` (not created)."""
    for var in ("HF_HUB_CACHE", "HUGGINGFACE_HUB_CACHE"):
        if os.environ.get(var):
            return Path(os.path.expandvars(os.environ[var])).expanduser()
    return _hf_home() / "hub"


def _hf_repo_folder(repo_id: str, hub_cache: Path | None = None) -> Path:
    return (hub_cache if hub_cache is not None else hf_hub_cache()) / f"{_HF_FOLDER_PREFIX}{repo_id.replace('/', '--')}"


def _hf_snapshot(repo_id: str, revision: str | None, hub_cache: Path | None = None) -> Path | None:
    """``models--<user>--<repo>/snapshots/<commit>/`` of the hub cache, the commit being ``revision``
    itself (40 hex digits) or the one ``refs/<revision>`` names (default ``main``); None when absent.
    What ``snapshot_download(..., local_files_only=True)`` returns, read by hand (nothing imported)."""
    folder = _hf_repo_folder(repo_id, hub_cache)
    revision = revision or "main"
    commit = revision if _COMMIT.fullmatch(revision) else None
    ref = folder / "refs" / revision
    if commit is None and ref.is_file():
        try:
            commit = ref.read_text().strip()
        except (OSError, UnicodeDecodeError):
            commit = None
    if not commit or not _COMMIT.fullmatch(commit):
        return None
    snapshot = folder / "snapshots" / commit
    return snapshot if snapshot.is_dir() else None


def _hf_contents(folder: Path) -> str:
    """What the hub-cache folder of a repo holds (its refs and snapshots), for a not-found message."""
    if not folder.is_dir():
        return "no such folder"
    refs = folder / "refs"
    names = sorted(p.relative_to(refs).as_posix() for p in refs.rglob("*") if p.is_file()) if refs.is_dir() else []
    snaps = folder / "snapshots"
    commits = sorted(p.name[:12] for p in snaps.iterdir() if p.is_dir()) if snaps.is_dir() else []
    return f"refs: {', '.join(names) or '(none)'}; snapshots: {', '.join(commits) or '(none)'}"


def _hub_not_found(repo_id: str, revision: str | None, root: Path) -> str:
    from .._optional import is_available

    name = f"{repo_id}@{revision}" if revision else repo_id
    own = root / f"{_HF_FOLDER_PREFIX}{repo_id.replace('/', '--')}"
    hf = _hf_repo_folder(repo_id)
    rev = revision or "main"
    commit = rev if _COMMIT.fullmatch(rev) else f"<commit of refs/{rev}>"
    own_note = " (it holds no revisions: a pinned revision is looked up in the Hugging Face cache only)"
    own_note = own_note if revision and own.is_dir() else ""
    extra = "" if is_available("huggingface_hub") else ' (pip install "stable-worldmodel[hub]")'
    cli_rev = f" --revision {revision}" if revision else ""
    call_rev = f", revision={revision!r}" if revision else ""
    return (
        f"Checkpoint {name!r} is not on disk, and nothing is downloaded here: looked in the stable-worldmodel cache "
        f"{own}/{own_note} and in the Hugging Face cache {hf}/snapshots/{commit}/ ({_hf_contents(hf)}). "
        f"When online, download it with stable_worldmodel.wm.utils.from_pretrained({repo_id!r}{call_rev}){extra} "
        f"or `hf download {repo_id}{cli_rev}` (`huggingface-cli download` in older huggingface_hub); "
        f"or put its {WEIGHTS_NAME} and {CONFIG_NAME} in {own}/."
    )


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
    """The weights file of ``name``: a ``.pt`` file, a folder with one, or ``<user>/<repo>[@<revision>]``
    (``checkpoints/models--<user>--<repo>/`` first, then the Hugging Face hub cache; see the module
    docstring). Nothing is downloaded. Missing: a ``FileNotFoundError`` naming where it looked."""
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
    hub = None if path.is_absolute() else _hub_name(text)
    if hub is not None:
        repo_id, revision = hub
        own = root / f"{_HF_FOLDER_PREFIX}{repo_id.replace('/', '--')}"
        if revision is None and own.is_dir():  # ours first (a flat folder: it holds no revisions)
            return _folder_weights(own)
        snapshot = _hf_snapshot(repo_id, revision)
        if snapshot is not None:
            logger.debug("%s found in the Hugging Face cache: %s", text, snapshot)
            return _folder_weights(snapshot)
        raise FileNotFoundError(_hub_not_found(repo_id, revision, root))
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


# -- the Hugging Face Hub ----------------------------------------------------------------------
#: ``protocol.json`` entries of this machine only (paths, host name, command line): not uploaded
_LOCAL_ONLY = (("dataset_path",), ("feature_cache", "file"), ("provenance", "host"), ("provenance", "command"))
#: where a Hub call's own errors come from (huggingface_hub and the HTTP clients it has used)
_HUB_MODULES = ("huggingface_hub", "httpx", "httpx2", "requests", "urllib3")
HUB_INSTALL = 'pip install "stable-worldmodel[hub]"'


def _require_hub(who: str) -> Any:
    from .._optional import require

    return require("huggingface_hub", "hub", who)


def _check_repo_id(repo_id: Any, who: str) -> str:
    if not isinstance(repo_id, str) or not _is_repo_id(repo_id):
        raise ConfigError(
            f"{who} requires a Hub repo id '<user>/<repo>' (letters, digits, '_', '.', '-'; no '--' or '..'; "
            f"at most 96 characters each side), got {repo_id!r}"
        )
    return repo_id


def _from_the_hub(exc: BaseException) -> bool:
    """An error of huggingface_hub or of the network (not a bug of ours)."""
    return type(exc).__module__.split(".")[0] in _HUB_MODULES or isinstance(exc, (ConnectionError, TimeoutError))


def _first_line(exc: BaseException) -> str:
    text = str(exc).strip()
    return f"{type(exc).__name__}: {text.splitlines()[0][:300]}" if text else type(exc).__name__


def _offline() -> bool:
    """``$HF_HUB_OFFLINE`` (or ``$TRANSFORMERS_OFFLINE``) set to 1/ON/YES/TRUE, read now."""
    value = os.environ.get("HF_HUB_OFFLINE") or os.environ.get("TRANSFORMERS_OFFLINE") or ""
    return value.strip().upper() in ("1", "ON", "YES", "TRUE")


def _shareable_protocol(protocol: Mapping[str, Any]) -> dict[str, Any]:
    """``protocol`` without what only made sense on this machine (:data:`_LOCAL_ONLY`)."""
    out = json.loads(json.dumps(dict(protocol), default=str))  # a deep copy
    for path in _LOCAL_ONLY:
        node = out
        for key in path[:-1]:
            node = node.get(key) if isinstance(node, dict) else None
        if isinstance(node, dict):
            node.pop(path[-1], None)
    return out


def _targets(config: Any) -> list[str]:
    found: list[str] = []
    if isinstance(config, Mapping):
        if isinstance(config.get("_target_"), str):
            found.append(config["_target_"])
        for value in config.values():
            found += _targets(value)
    elif isinstance(config, (list, tuple)):
        for value in config:
            found += _targets(value)
    return found


def _cell(value: Any) -> str:
    return str(value).replace("|", "\\|").replace("\n", " ")


def model_card(run: Any, repo_id: str, config: Mapping[str, Any]) -> str:
    """The ``README.md`` :func:`push_to_hub` uploads with ``run`` (a :class:`~stable_worldmodel.wm.run.Run`):
    what the model is, what it was trained on, and how to load it."""
    from .trust import BUILTIN_PREFIXES

    p = run.protocol
    model = p.model or str(config.get("_target_", "?")).rsplit(".", 1)[-1]
    rows = [("Model", model + (f" (preset {p.preset})" if p.preset else ""))]
    rows.append(("Model class", f"`{config.get('_target_')}`"))
    if p.dataset:
        rows.append(("Dataset", p.dataset))
    if p.env:
        rows.append(("Environment", p.env))
    if p.steps is not None or p.steps_done is not None:
        done = p.steps_done if p.steps_done is not None else p.steps
        rows.append(
            ("Training steps", f"{done}" + (f" of {p.steps}" if p.steps is not None and done != p.steps else ""))
        )
    if p.final:
        rows.append(
            (
                "Final losses",
                ", ".join(f"{k} {v:.4g}" if isinstance(v, float) else f"{k} {v}" for k, v in p.final.items()),
            )
        )
    for label, value in (
        ("Action dim", p.action_dim),
        ("Frameskip", p.frameskip if "frameskip" in p.raw else None),
        ("History", p.history_size),
        ("Image size", p.image_size if "image_size" in p.raw else None),
    ):
        if value is not None:
            rows.append((label, value))
    if not p.trained_here:
        rows.append(("Protocol", "none (an upstream checkpoint: 224 px, ImageNet statistics)"))
    table = "\n".join(f"| {_cell(k)} | {_cell(v)} |" for k, v in rows)
    foreign = sorted({t for t in _targets(config) if not t.startswith(BUILTIN_PREFIXES) and t not in TARGET_ALIASES})
    trust = ""
    if foreign:
        prefixes = sorted({t.split(".")[0] + "." for t in foreign})
        trust = (
            f"\nIts config builds {', '.join(f'`{t}`' for t in foreign)}, outside what stable-worldmodel trusts by "
            f"default: install that package and pass `trusted_targets={tuple(prefixes)!r}` when loading.\n"
        )
    prefix = run.model_prefix
    env = p.env or "ENV"
    tag = f"\n- {model}" if re.fullmatch(r"[a-z0-9][a-z0-9_-]*", model) else ""
    return f"""---
library_name: stable-worldmodel
tags:
- stable-worldmodel
- world-model{tag}
---

# {repo_id}

A {model} world model trained with [stable-worldmodel](https://pypi.org/project/stable-worldmodel/).

| | |
|---|---|
{table}

## Load it

```python
from stable_worldmodel.wm.utils import from_pretrained

model = from_pretrained("{repo_id}")  # downloads into the Hugging Face cache, then loads it
```

Once downloaded (also with `hf download {repo_id}`), it loads offline from the Hugging Face cache:

```python
from stable_worldmodel.wm.utils import load_pretrained

model = load_pretrained("{repo_id}")  # or "{repo_id}@<revision>"
```

```bash
swm eval {env} --policy {prefix}:{repo_id}
```
{trust}
Loading checks every `_target_` of `config.json` against the trusted prefixes before anything is
imported, and reads the weights with `weights_only=True`.

## Files

- `{run.weights.name}`: the model's state dict (tensors only)
- `{CONFIG_NAME}`: the model, as a `_target_` tree
""" + (
        f"- `{PROTOCOL_NAME}`: how it was trained and how to plan with it (normalizers, image size, ...)\n"
        if p.trained_here
        else ""
    )


def _stage(source: Path, dest: Path) -> None:
    """``dest`` as a hard link to ``source`` (its target, for a link), else a copy."""
    import shutil

    try:
        os.link(source.resolve(), dest)
    except OSError:
        shutil.copyfile(source, dest)


def push_to_hub(
    run: Any,
    repo_id: str,
    *,
    private: bool = False,
    revision: str | None = None,
    commit_message: str | None = None,
    token: str | None = None,
    cache_dir: str | os.PathLike | None = None,
) -> Any:
    """Upload a run to the Hugging Face Hub repo ``repo_id`` (``<user>/<repo>``, created when missing).

    ``run`` is a run name in ``<cache_dir or $STABLEWM_HOME>/checkpoints``, ``wm:NAME`` / ``gc:NAME``,
    ``<user>/<repo>`` or a path (:meth:`~stable_worldmodel.wm.run.Run.open`). Uploaded in one commit: its
    weights ``.pt`` (checked first: tensors only, its recorded sha256, no NaN/inf), ``config.json``,
    ``protocol.json`` when it has one (without this machine's paths, host name and command line) and a
    generated ``README.md`` model card. Nothing else of the run folder (no ``train_state.ckpt``, optimizer,
    pickled ``*_object.ckpt`` or ``step_<N>/``). ``revision``: the branch to commit to (created from
    ``main`` when missing). ``token``: a Hub token with write access (default: huggingface_hub's, from
    ``$HF_TOKEN`` or ``hf auth login``). Returns huggingface_hub's ``CommitInfo`` (a ``str``: the commit URL;
    ``.repo_url``, ``.oid``). Needs ``pip install "stable-worldmodel[hub]"``.
    """
    import tempfile

    from .run import Run

    repo_id = _check_repo_id(repo_id, "push_to_hub")
    if revision is not None:
        revision = _check_revision(revision, f"{repo_id}@{revision}", "push_to_hub")
    hub = _require_hub("push_to_hub")
    opened = Run.open(run, cache_dir)
    weights = opened.weights
    config_path = weights.parent / CONFIG_NAME
    if not config_path.is_file():
        raise FileNotFoundError(
            f"push_to_hub requires {CONFIG_NAME} beside {weights} (load_pretrained rebuilds the model from it), "
            "found none: save the model with save_pretrained(model, name, config=...)"
        )
    config = _read_json(config_path, "the model config")
    if not isinstance(config, dict) or "_target_" not in config:
        raise ConfigError(f"push_to_hub requires a {CONFIG_NAME} with a top-level _target_, got {config_path}")
    _read_weights(weights, opened.protocol.raw)  # tensors only (a pickle is refused), intact, finite
    protocol = None
    if opened.protocol.trained_here:
        protocol = _shareable_protocol(opened.protocol.raw)
        if not protocol.get("env"):
            from ..planning.run_fit import RunFacts

            env = RunFacts.from_protocol(opened.name, opened.protocol).env  # from the dataset's manifest
            if env:
                protocol["env"] = env
    label = weights.parent.name if Path(opened.name).expanduser().is_absolute() else opened.name
    message = commit_message or f"Upload {label} with stable-worldmodel"
    with tempfile.TemporaryDirectory(prefix="swm-push-") as tmp:
        stage = Path(tmp)
        _stage(weights, stage / weights.name)
        _stage(config_path, stage / CONFIG_NAME)
        if protocol is not None:
            (stage / PROTOCOL_NAME).write_text(json.dumps(protocol, indent=2) + "\n")
        (stage / "README.md").write_text(model_card(opened, repo_id, config))
        api = hub.HfApi(token=token)
        try:
            api.create_repo(repo_id, private=private, exist_ok=True)
            if revision is not None and revision != "main":
                api.create_branch(repo_id, branch=revision, exist_ok=True)
            info = api.upload_folder(repo_id=repo_id, folder_path=str(stage), commit_message=message, revision=revision)
        except Exception as exc:
            if not _from_the_hub(exc):
                raise
            raise ConfigError(
                f"push_to_hub could not push {opened.spec!r} to {repo_id!r}: {_first_line(exc)}. It requires the "
                "network (HF_HUB_OFFLINE unset) and a token that may write to that repo: token=..., $HF_TOKEN "
                "or `hf auth login`"
            ) from exc
    logger.info("pushed %s to %s", weights.parent, getattr(info, "commit_url", info))
    return info


def _fetch_error(
    exc: BaseException,
    name: str,
    repo_id: str,
    revision: str | None,
    hf_cache: Path,
    offline: bool,
    local_files_only: bool | None,
) -> Exception:
    """The error :func:`from_pretrained` raises for ``exc`` of ``snapshot_download``."""
    where = _hf_repo_folder(repo_id, hf_cache)
    kind = type(exc).__name__
    if kind in ("RepositoryNotFoundError", "GatedRepoError"):
        why = "the Hub has no such repo, or it is private or gated (pass token=... or log in: `hf auth login`)"
    elif kind == "RevisionNotFoundError":
        why = f"the repo has no revision {revision!r}"
    elif offline:
        how = "local_files_only=True" if local_files_only else "HF_HUB_OFFLINE is set"
        why = f"it is not in the Hugging Face cache ({_hf_contents(where)}) and {how}"
    elif isinstance(exc, FileNotFoundError):
        why = _first_line(exc)
    else:
        return ConfigError(
            f"from_pretrained could not fetch {name!r}: {_first_line(exc)}; it requires the network "
            f"(or a snapshot in {where}/ and HF_HUB_OFFLINE=1)"
        )
    cli = f"`hf download {repo_id}" + (f" --revision {revision}`" if revision else "`")
    return FileNotFoundError(
        f"from_pretrained could not get {name!r}: {why}. Looked in {where}/. Online, {cli} fetches it "
        f"(`huggingface-cli download` in older huggingface_hub); or put the files there yourself"
    )


def from_pretrained(
    repo_id: str,
    *,
    revision: str | None = None,
    cache_dir: str | os.PathLike | None = None,
    token: str | None = None,
    local_files_only: bool | None = None,
    **load_kwargs: Any,
) -> Any:
    """Download ``repo_id`` (``<user>/<repo>``, or ``<user>/<repo>@<revision>``) into the Hugging Face
    cache and load it like :func:`load_pretrained` (the model, in eval mode).

    ``cache_dir``: the Hugging Face cache to use (default :func:`hf_hub_cache`: ``$HF_HUB_CACHE``, else
    ``$HF_HOME/hub``). Only the ``.pt``, ``config.json``, ``protocol.json`` and ``README.md`` files are
    fetched. ``local_files_only`` (default: ``$HF_HUB_OFFLINE``) uses the cache only, without the network.
    ``load_kwargs``: ``extra_args`` and ``trusted_targets`` of :func:`load_pretrained`; every ``_target_``
    of the downloaded ``config.json`` is checked before anything is imported
    (:class:`~stable_worldmodel.errors.UntrustedCheckpointError`). Not found: a ``FileNotFoundError``
    saying where it looked. Needs ``pip install "stable-worldmodel[hub]"``.
    """
    from ..errors import ArgumentTypeError

    unknown = sorted(set(load_kwargs) - {"extra_args", "trusted_targets"})
    if unknown:
        raise ArgumentTypeError(
            f"from_pretrained got unexpected keyword argument(s) {', '.join(unknown)}; accepted: revision, "
            "cache_dir, token, local_files_only, extra_args, trusted_targets"
        )
    spec = _hub_name(repo_id, "from_pretrained") if isinstance(repo_id, str) else None
    if spec is None:
        raise ConfigError(
            f"from_pretrained requires a Hub repo id '<user>/<repo>' or '<user>/<repo>@<revision>', got {repo_id!r}"
        )
    repo_id, pinned = spec
    if revision is not None:
        if pinned is not None and pinned != revision:
            raise ConfigError(
                f"from_pretrained requires one revision, got {pinned!r} in {repo_id}@{pinned} and revision={revision!r}"
            )
        pinned = _check_revision(revision, f"{repo_id}@{revision}", "from_pretrained")
    hub = _require_hub("from_pretrained")
    offline = _offline() if local_files_only is None else bool(local_files_only)
    hf_cache = Path(cache_dir).expanduser() if cache_dir is not None else hf_hub_cache()
    name = f"{repo_id}@{pinned}" if pinned else repo_id
    try:
        folder = hub.snapshot_download(
            repo_id,
            revision=pinned,
            cache_dir=str(hf_cache),
            token=token,
            local_files_only=offline,
            allow_patterns=["*.pt", CONFIG_NAME, PROTOCOL_NAME, "README.md"],
        )
    except Exception as exc:
        if not _from_the_hub(exc) and not isinstance(exc, FileNotFoundError):
            raise
        raise _fetch_error(exc, name, repo_id, pinned, hf_cache, offline, local_files_only) from exc
    logger.info("%s is in %s", name, folder)
    return load_pretrained(Path(folder), **load_kwargs)

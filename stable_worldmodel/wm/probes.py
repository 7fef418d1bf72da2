"""Probes attached to a world model: small ``nn.Module`` heads (a linear layer, an MLP) that read
a model's embeddings, kept on the model so they move, save and switch mode with it.

Upstream 0.1.1's ``stable_worldmodel.wm.probes``, same names and signatures; behaviour follows
that release as observed (see ``tests/wm/test_probes.py``):

- :func:`attach_probe` stores ``probe`` in ``model._probes`` (an ``nn.ModuleDict`` created on
  first use), replacing any probe under the same key. On an ``nn.Module`` the probes are then
  sub-modules: ``model.state_dict()`` holds ``_probes.<key>.*`` and ``model.to(...)`` moves them.
- :func:`get_probe` returns the probe under ``key``, or ``None`` when there is none.
- :func:`load_probe` reads ``path`` on the CPU: a whole pickled module is attached under ``key``;
  a state dict is loaded (strictly) into the probe already attached under ``key``.

Differences from upstream, each where upstream failed late or silently: a probe that is not an
``nn.Module`` raises :class:`ProbeTypeError` (a ``TypeError``, and an ``AssertionError`` like
upstream's ``assert``, also under ``python -O``); a key ``nn.ModuleDict`` refuses raises
:class:`ProbeKeyError` (a ``KeyError``) before the model is touched; a file holding neither a module
nor a state dict raises :class:`~stable_worldmodel.errors.CheckpointError` (upstream ignored it). A
state dict is read with ``weights_only=True``; a pickled module is loaded with a warning, or refused
when ``STABLEWM_REFUSE_PICKLE=1`` (:mod:`stable_worldmodel.wm.trust`).

    >>> import torch
    >>> from stable_worldmodel.wm.probes import attach_probe, get_probe
    >>> model = torch.nn.Linear(4, 8)
    >>> attach_probe(model, "position", torch.nn.Linear(8, 2))
    >>> get_probe(model, "position")
    Linear(in_features=8, out_features=2, bias=True)
    >>> get_probe(model, "velocity") is None
    True
"""

from __future__ import annotations

import os
import pickle
import warnings
from collections.abc import Mapping
from typing import Any

import torch
from torch import nn

from ..errors import ArgumentTypeError, CheckpointError, ConfigError

__all__ = ["attach_probe", "get_probe", "load_probe"]

#: the attribute of the model that holds its probes (upstream's name: checkpoints carry ``_probes.<key>.*``)
PROBES_ATTR = "_probes"


class ProbeTypeError(ArgumentTypeError, AssertionError):
    """A probe that is not an ``nn.Module`` (a ``TypeError``; an ``AssertionError`` as upstream's ``assert``)."""


class ProbeKeyError(ConfigError, KeyError):
    """A probe key that ``nn.ModuleDict`` cannot hold (empty, dotted, or the name of one of its attributes)."""

    def __str__(self) -> str:  # KeyError quotes its message; we want plain text
        return str(self.args[0]) if self.args else ""


class ProbeNotFoundError(ConfigError):
    """A state dict to load into a probe that is not attached (a ``ValueError``, as upstream)."""


class ProbeStateError(CheckpointError, RuntimeError):
    """A state dict that does not fit the attached probe (a ``RuntimeError``, as torch's ``load_state_dict``)."""


def _probes_of(model: Any) -> Any:
    """``model._probes``, or ``None`` when the model has none yet."""
    return getattr(model, PROBES_ATTR, None)


def attach_probe(model, key, probe):
    """Attach ``probe`` (an ``nn.Module``) to ``model`` under ``key``, replacing any probe there.

    The probes live in ``model._probes``, an ``nn.ModuleDict`` created on first use, so on an
    ``nn.Module`` they are sub-modules: they appear in ``model.state_dict()`` as
    ``_probes.<key>.*``, follow ``model.to(...)`` and ``model.eval()``. Returns ``None``.

    ``key`` is a string that an ``nn.ModuleDict`` accepts (not empty, no ``.``, not the name of a
    ``ModuleDict`` attribute such as ``"keys"``): otherwise :class:`ProbeKeyError`; a ``key`` that is
    not a string is an :class:`~stable_worldmodel.errors.ArgumentTypeError`. A ``probe`` that is not
    an ``nn.Module`` raises :class:`ProbeTypeError`. Nothing is changed when an error is raised.
    """
    if not isinstance(probe, nn.Module):
        raise ProbeTypeError(
            f"attach_probe requires the probe to be a torch.nn.Module, got {type(probe).__name__}: {probe!r:.80}"
        )
    probes = _probes_of(model)
    created = probes is None
    if created:
        probes = nn.ModuleDict()
    elif not hasattr(type(probes), "__setitem__"):
        raise ArgumentTypeError(
            f"attach_probe requires model.{PROBES_ATTR} to be a torch.nn.ModuleDict (or a dict), "
            f"got {type(probes).__name__}; remove that attribute to let attach_probe create it"
        )
    try:
        probes[key] = probe
    except TypeError as exc:
        raise ArgumentTypeError(
            f"attach_probe requires the key to be a str, got {type(key).__name__}: {key!r}"
        ) from exc
    except KeyError as exc:
        raise ProbeKeyError(
            f"attach_probe requires a key that torch.nn.ModuleDict accepts (not empty, without '.', not one of its "
            f"attribute names), got {key!r} ({exc.args[0] if exc.args else exc})"
        ) from exc
    if created:
        setattr(model, PROBES_ATTR, probes)


def get_probe(model, key):
    """The probe attached to ``model`` under ``key``, or ``None`` when there is none (no probes
    at all, or none under that key)."""
    probes = _probes_of(model)
    if probes is None:
        return None
    try:
        return probes[key] if key in probes else None
    except TypeError:  # an unhashable key names no probe
        return None


def _read(path: Any) -> Any:
    """The object saved in ``path``, on the CPU: a state dict without unpickling code, a pickled
    module with a warning (or refused by ``STABLEWM_REFUSE_PICKLE``)."""
    from .trust import PICKLE_ENV, pickles_refused

    where = os.fspath(path) if isinstance(path, (str, os.PathLike)) else repr(path)
    if isinstance(path, (str, os.PathLike)) and not os.path.isfile(path):
        raise FileNotFoundError(f"load_probe requires an existing probe file, got {where!r}, which does not exist")
    seekable = hasattr(path, "seek") and hasattr(path, "tell")
    start = path.tell() if seekable else None
    try:
        return torch.load(path, map_location="cpu", weights_only=True)
    except pickle.UnpicklingError:
        pass  # a pickled module (or not a torch file at all): decided below
    except Exception as exc:
        raise CheckpointError(
            f"load_probe requires a readable torch file, got a damaged or truncated {where} "
            f"({type(exc).__name__}: {str(exc).splitlines()[0][:160] if str(exc) else ''})"
        ) from exc
    if pickles_refused():
        raise CheckpointError(
            f"load_probe refuses the pickled probe {where} ({PICKLE_ENV} is set); save its state_dict instead "
            "(torch.save(probe.state_dict(), path)) and attach_probe a probe of the same shape before loading it"
        )
    warnings.warn(
        f"{where} is a pickled probe: loading it runs code stored in the file; load only files you trust "
        f"(set {PICKLE_ENV}=1 to refuse pickles)",
        UserWarning,
        stacklevel=3,
    )
    if seekable:
        path.seek(start)
    try:
        return torch.load(path, map_location="cpu", weights_only=False)
    except (AttributeError, ImportError) as exc:
        raise ConfigError(
            f"load_probe requires the classes pickled in {where} to be importable, got {type(exc).__name__}: {exc}; "
            "install or import the package that defines them"
        ) from exc
    except Exception as exc:
        raise CheckpointError(
            f"load_probe requires a torch file holding a module or a state dict, got {where} that cannot be read "
            f"({type(exc).__name__}: {str(exc).splitlines()[0][:160] if str(exc) else ''})"
        ) from exc


def load_probe(model, key, path):
    """Load the probe saved in ``path`` (on the CPU) onto ``model`` under ``key``. Returns ``None``.

    - A whole module (``torch.save(probe, path)``) is attached under ``key`` (:func:`attach_probe`),
      replacing any probe there. Unpickling it runs code from the file: it is loaded with a
      ``UserWarning``, or refused (:class:`~stable_worldmodel.errors.CheckpointError`) when
      ``STABLEWM_REFUSE_PICKLE=1``.
    - A state dict (``torch.save(probe.state_dict(), path)``, read with ``weights_only=True``) is
      loaded strictly into the probe already attached under ``key``: none there raises
      :class:`ProbeNotFoundError` (a ``ValueError``), keys or shapes that differ raise
      :class:`ProbeStateError` (a ``RuntimeError``).

    A missing file raises ``FileNotFoundError``; a damaged one, or one holding anything else (a
    tensor, a list), a :class:`~stable_worldmodel.errors.CheckpointError`.
    """
    payload = _read(path)
    where = os.fspath(path) if isinstance(path, (str, os.PathLike)) else repr(path)
    if isinstance(payload, nn.Module):
        attach_probe(model, key, payload)
        return
    if not isinstance(payload, Mapping):
        raise CheckpointError(
            f"load_probe requires {where} to hold a torch.nn.Module or a state dict, got {type(payload).__name__}"
        )
    probe = get_probe(model, key)
    if probe is None:
        probes = _probes_of(model)
        attached = sorted(map(str, probes.keys())) if hasattr(probes, "keys") else []
        raise ProbeNotFoundError(
            f"load_probe requires a probe attached under {key!r} to load the state dict in {where} into, got none "
            f"(attached: {', '.join(attached) or '(none)'}); call attach_probe(model, {key!r}, probe) first"
        )
    try:
        probe.load_state_dict(payload)
    except RuntimeError as exc:
        raise ProbeStateError(
            f"load_probe requires the state dict in {where} to fit the probe under {key!r}, got: "
            + " ".join(str(exc).split())[:400]
        ) from exc

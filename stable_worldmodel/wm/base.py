"""The world-model contract: what every model config has, and what a model or config may be able to do.

Every model is registered by its config class (:mod:`stable_worldmodel.wm._registry`), a
:class:`WorldModelConfig` subclass: the fields every model shares (the data protocol and the
training recipe), its presets, and :meth:`~WorldModelConfig.target_tree`, the ``_target_`` tree that
builds the model (what a checkpoint's ``config.json`` holds). The trainer and planning ask a model
or a config what it can do through the capabilities below, never by its class or name:

=========================  ======  ==============================================================
capability                 of      what it means
=========================  ======  ==============================================================
``GoalConditioned``        config  training batches carry hindsight goals (``goal_pixels``)
``DerivedFromRun``         config  built on another run (its dataset, default name, weights)
``needs_reward``           config  the dataset must have a ``reward`` column (a class attribute)
``extra_columns``          config  dataset columns the model reads besides pixels and actions
``subgoal_graph``          config  planning may aim at waypoints of the training data
``HasFrozenEncoder``       model   a frozen encoder whose features the trainer caches
``HasValidationLoss``      model   the loss term the validation reports (else ``loss``)
``SupportsSubgoalGraph``   model   the info keys a waypoint embedding replaces
``DecodesFrames``          model   a decoder that turns its latents back into frames
``Actor``                  model   ``get_action(info)``: acts without planning (``gc:RUN``)
``CostModel``              model   ``get_cost(info, candidates)``: solvers plan through it
=========================  ======  ==============================================================
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, ClassVar, Protocol, runtime_checkable

from ..errors import ConfigError, check_int, did_you_mean

__all__ = [
    "Actor",
    "CostModel",
    "DecodesFrames",
    "DerivedFromRun",
    "GoalConditioned",
    "HasFrozenEncoder",
    "HasValidationLoss",
    "SupportsSubgoalGraph",
    "WorldModelConfig",
    "check_positive_int",
]


#: the package's one integer check (:func:`stable_worldmodel.errors.check_int`), under the configs' name
check_positive_int = check_int


@dataclass
class WorldModelConfig:
    """What every world-model config has: the data protocol and the training recipe.

    Data protocol: ``image_size`` (square frames), ``history_size`` context frames and
    ``num_preds`` predicted frames per sample (``num_steps``), ``frameskip`` env steps per frame
    (the action block), ``image_mean`` / ``image_std`` (per channel, on pixels in [0, 1]).
    Training: ``batch_size``, ``lr``, ``weight_decay``, ``warmup_steps``, ``steps``, ``grad_clip``,
    ``val_fraction`` (episodes held out), ``encoder_lr_scale`` (learning-rate factor of the
    parameters under ``encoder.``).

    A subclass sets ``model_name``, ``target`` (the model class's dotted path), ``presets`` and
    implements :meth:`target_tree`; it declares its capabilities (module docstring).
    """

    model_name: ClassVar[str] = ""
    target: ClassVar[str] = ""
    presets: ClassVar[dict[str, dict[str, Any]]] = {}
    #: how ``swm eval --policy <prefix>:RUN`` uses a checkpoint: ``wm`` plans with it, ``gc`` acts with it
    eval_prefix: ClassVar[str] = "wm"
    #: :class:`~stable_worldmodel.train.data.TrainData` serves ``reward (B, T)`` and refuses a dataset without one
    needs_reward: ClassVar[bool] = False
    #: planning may aim at waypoints of the training data (``--subgoals graph|auto``)
    subgoal_graph: ClassVar[bool] = False

    #: one line per field: what it means (``swm show model TYPE`` prints it; :meth:`field_help` merges
    #: the classes' tables, a subclass's entry replacing its base's). Every field has one (a test checks).
    FIELD_HELP: ClassVar[dict[str, str]] = {
        "image_size": "Side of the square frames the model sees, in pixels.",
        "history_size": "Context frames per training sample (the frames the model conditions on).",
        "num_preds": "Frames predicted per training sample after the context.",
        "frameskip": "Env steps per model step: each model action is a block of frameskip env actions.",
        "image_mean": "Per-channel mean subtracted from the pixels (in [0, 1]).",
        "image_std": "Per-channel scale dividing the pixels (in [0, 1], after the mean).",
        "batch_size": "Samples per optimizer step (the global batch under torchrun).",
        "lr": "Peak learning rate of AdamW (linear warmup, then cosine decay to 0).",
        "weight_decay": "AdamW weight decay of the weight matrices (none on biases, norms and embeddings).",
        "warmup_steps": "Steps of linear learning-rate warmup.",
        "steps": "Optimizer steps of a run (--steps / --epochs override it).",
        "grad_clip": "Largest gradient norm; larger gradients are scaled down (0: no clipping).",
        "val_fraction": "Fraction of the dataset's episodes held out for the validation loss.",
        "encoder_lr_scale": "Learning-rate factor of the parameters under encoder. (1: the same as the rest).",
    }

    image_size: int = 64
    history_size: int = 1
    num_preds: int = 1
    frameskip: int = 5
    image_mean: tuple[float, ...] = (0.5, 0.5, 0.5)
    image_std: tuple[float, ...] = (0.5, 0.5, 0.5)
    batch_size: int = 64
    lr: float = 1e-3
    weight_decay: float = 1e-3
    warmup_steps: int = 100
    steps: int = 2000
    grad_clip: float = 1.0
    val_fraction: float = 0.1
    encoder_lr_scale: float = 1.0

    def __post_init__(self) -> None:
        name = type(self).__name__
        for key in ("image_size", "history_size", "num_preds", "frameskip", "batch_size", "steps"):
            check_positive_int(name, key, getattr(self, key))
        check_positive_int(name, "warmup_steps", self.warmup_steps, minimum=0)
        if not 0.0 < self.lr < 1.0 or self.weight_decay < 0 or self.grad_clip < 0:
            raise ConfigError(
                f"{name} requires 0 < lr < 1, weight_decay >= 0 and grad_clip >= 0, "
                f"got {self.lr}, {self.weight_decay}, {self.grad_clip}"
            )
        if not 0.0 <= self.val_fraction < 1.0:
            raise ConfigError(f"{name} requires 0 <= val_fraction < 1, got {self.val_fraction!r}")
        self.image_mean, self.image_std = tuple(self.image_mean), tuple(self.image_std)

    @property
    def num_steps(self) -> int:
        """Frames per training sample: ``history_size + num_preds``."""
        return self.history_size + self.num_preds

    @property
    def extra_columns(self) -> dict[str, int]:
        """Dataset columns the model reads besides pixels and actions, with their widths (none here)."""
        return {}

    @property
    def reads_pixels(self) -> bool:
        """Whether the model observes images (False: a state-input model, which reads its
        :attr:`extra_columns` and never the dataset's pixels)."""
        return True

    @classmethod
    def field_help(cls) -> dict[str, str]:
        """``{field: meaning}`` of every field of this config, from the ``FIELD_HELP`` tables of its
        classes (a subclass's entry replaces its base's)."""
        merged: dict[str, str] = {}
        for klass in reversed(cls.__mro__):
            merged.update(klass.__dict__.get("FIELD_HELP") or {})
        return {f.name: merged.get(f.name, "") for f in dataclasses.fields(cls) if f.init}

    @classmethod
    def field_default(cls, name: str) -> Any:
        """The default of field ``name`` as declared on the class (``dataclasses.MISSING`` when it has none)."""
        for f in dataclasses.fields(cls):
            if f.name == name:
                if f.default_factory is not dataclasses.MISSING:
                    return f.default_factory()
                return f.default
        raise KeyError(name)

    @classmethod
    def unknown_key(cls, key: str) -> str | None:
        """Why ``key`` is not an override of this config (``None``: it is), with a "did you mean".

        A key is a field name, or ``FIELD.KEY[.KEY...]`` into a field that holds a mapping
        (``vit_overrides.num_hidden_layers``, ``loss_weights.std_loss``)."""
        names = [f.name for f in dataclasses.fields(cls) if f.init]
        if key in names:
            return None
        head, dot, _ = key.partition(".")
        if dot and head in names and isinstance(cls.field_default(head), Mapping):
            return None
        leaf = key.rpartition(".")[2]  # predictor.depth: the field is depth
        hint = f" Did you mean {leaf!r}?" if dot and leaf in names else did_you_mean(key, names)
        return f"{cls.__name__} has no field {key!r}.{hint} Fields: {', '.join(sorted(names))}"

    @classmethod
    def from_preset(cls, preset: str = "tiny", **overrides: Any) -> WorldModelConfig:
        """The config of ``preset`` with ``overrides`` (unknown fields get a "did you mean" error).

        A dotted key sets one entry of a field that holds a mapping, on top of the preset's value
        (``**{"vit_overrides.num_hidden_layers": 4}``); a plain key replaces the field."""
        if preset not in cls.presets:
            raise ConfigError(
                f"{cls.model_name} requires preset in {sorted(cls.presets)}, got "
                f"{preset!r}.{did_you_mean(preset, cls.presets)}"
            )
        for key in overrides:
            problem = cls.unknown_key(key)
            if problem:
                raise ConfigError(problem)
        values = dict(cls.presets[preset])
        for key, value in overrides.items():
            if "." not in key:
                values[key] = value
                continue
            head, *path, leaf = key.split(".")
            base = values[head] if head in values else cls.field_default(head)
            if not isinstance(base, Mapping):
                raise ConfigError(f"{cls.__name__} requires a mapping in {head!r} to set {key!r}, got {base!r}")
            root = node = dict(base)
            for part in path:
                child = node.get(part, {})
                if not isinstance(child, Mapping):
                    raise ConfigError(f"{cls.__name__} requires a mapping at {part!r} to set {key!r}, got {child!r}")
                node[part] = node = dict(child)
            node[leaf] = value
            values[head] = root
        return cls(**values)

    @classmethod
    def subgoal_graph_unavailable(cls, config: Mapping[str, Any]) -> str | None:
        """Why a run of this model with config ``config`` (its ``protocol.json`` ``config``) cannot
        plan towards waypoints (None: it can)."""
        return None if cls.subgoal_graph else f"model {cls.model_name!r} does not support a subgoal graph"

    def to_dict(self) -> dict[str, Any]:
        return dataclasses.asdict(self)

    def target_tree(self, action_dim: int) -> dict[str, Any]:
        raise NotImplementedError("target_tree(action_dim) -> the model's _target_ tree (config.json)")


# -- capabilities of configs -----------------------------------------------------------------------
@runtime_checkable
class GoalConditioned(Protocol):
    """A model config whose training batches carry hindsight goals (``GCRLConfig``)."""

    goal_probabilities: Mapping[str, float]
    actor_goal_probabilities: Mapping[str, float]
    goal_gamma: float
    history_size: int
    frameskip: int


@runtime_checkable
class DerivedFromRun(Protocol):
    """A config built on another run (the frame decoder): it trains on that run's dataset by
    default, names itself after it, and loads its weights into the model before training."""

    @property
    def source_dataset(self) -> str | None: ...

    @property
    def default_run(self) -> str: ...

    def prepare_model(self, model: Any) -> None: ...


# -- capabilities of models ------------------------------------------------------------------------
@runtime_checkable
class HasFrozenEncoder(Protocol):
    """A model whose encoder is frozen (PreJEPA): the trainer fits and caches its features."""

    def frozen_encoder(self) -> Any: ...


@runtime_checkable
class HasValidationLoss(Protocol):
    """A model whose validation reports one term of its loss (TD-MPC2: ``model_loss``, without the actor's)."""

    validation_loss: str


@runtime_checkable
class SupportsSubgoalGraph(Protocol):
    """A model whose goal embedding a waypoint of the training data can replace."""

    def encode_pixels(self, pixels: Any) -> Any: ...

    def subgoal_keys(self) -> tuple[str | None, str]:
        """``(context key, goal key)``: the info keys the model caches its context embeddings (None: it
        does not) and its goal embedding under; raises :class:`ConfigError` when this instance cannot."""
        ...


@runtime_checkable
class DecodesFrames(Protocol):
    """A model with its own decoder of latents into frames (Dreamer)."""

    decodes_frames: bool


@runtime_checkable
class Actor(Protocol):
    """A model that acts without planning (``swm eval --policy gc:RUN``)."""

    def get_action(self, info: Any) -> Any: ...


@runtime_checkable
class CostModel(Protocol):
    """A model the solvers plan through."""

    def get_cost(self, info: Any, action_candidates: Any) -> Any: ...

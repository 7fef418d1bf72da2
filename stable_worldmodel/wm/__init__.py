"""World models: one folder per model (light config + torch module + its loss), a registry,
checkpoints in upstream 0.1.1's ``save_pretrained`` layout.

Importing this package is cheap; torch is imported when a model class is first used.

    >>> import stable_worldmodel as swm
    >>> swm.wm.list_models()
    ['dinowm', 'dreamer', 'dummy', 'frame', 'gcbc', 'gciql', 'gcivl', 'lewm', 'pldm', 'prejepa', 'tdmpc2']
    >>> model = swm.wm.make("lewm", preset="tiny", action_dim=2)      # doctest: +SKIP

The contract every model follows (shapes: ``B`` envs, ``S`` candidates, ``T`` history,
``H`` horizon, ``A`` action block, ``D`` embedding) is written in :mod:`stable_worldmodel.wm.jepa`:
``encode(info) -> info`` (adds ``emb``, ``act_emb``), ``predict(emb, act_emb) -> emb``,
``rollout(info, candidates) -> info`` (adds ``predicted_emb``), ``get_cost(info, candidates)
-> (B, S)`` and ``loss(batch) -> {"loss": ..., named terms}``. The goal-conditioned baselines
(``gcbc``, ``gcivl``, ``gciql``: :class:`~stable_worldmodel.wm.gcrl.GCRL`) act instead of
planning: ``get_action(info) -> (B, A)`` and ``loss(batch)`` (see :mod:`stable_worldmodel.wm.gcrl`).
``make("gcbc")`` builds that ``GCRL``; ``GCBC`` (:mod:`stable_worldmodel.wm.gcbc`) is release 0.0.3's
class of the same name (one action per window), kept for its checkpoints: each refuses the
other's weights with a CheckpointError naming the right class.
``prejepa`` (alias ``dinowm``: :class:`~stable_worldmodel.wm.prejepa.PreJEPA`, DINO-WM) plans on
the patch tokens of a frozen encoder (:func:`~stable_worldmodel.wm.backbones.create_backbone`),
whose features the trainer caches on disk (:mod:`stable_worldmodel.train.features`). ``frame``
(:mod:`stable_worldmodel.wm.frame`) decodes another run's latents back into frames.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from .._lazy import lazy_getattr
from ._registry import get_config, get_config_class, list_models, make, register_model

_ATTRS = {
    "LeWM": ".lewm",
    "PLDM": ".pldm",
    "PreJEPA": ".prejepa",
    "DINOWM": ".dinowm",
    "create_backbone": ".backbones",
    "DummyWorldModel": ".dummy",
    "GCRL": ".gcrl",
    "GCBC": ".gcbc",
    "TDMPC2": ".tdmpc2",
    "Dreamer": ".dreamer",
    "JEPA": ".jepa",
    "SIGReg": ".loss",
    "VCReg": ".loss",
    "PLDMLoss": ".loss",
    "TemporalStraighteningLoss": ".loss",
    "save_pretrained": ".utils",
    "load_pretrained": ".utils",
    "from_pretrained": ".utils",
    "push_to_hub": ".utils",
    "instantiate": ".utils",
    "ConvEncoder": ".encoders",
    "vit_hf": ".encoders",
    "LeWMConfig": ".lewm.config",
    "PLDMConfig": ".pldm.config",
    "PreJEPAConfig": ".prejepa.config",
    "DummyConfig": ".dummy_config",
    "GCBCConfig": ".gcrl.config",
    "GCIVLConfig": ".gcrl.config",
    "GCIQLConfig": ".gcrl.config",
}

__all__ = ["get_config", "get_config_class", "list_models", "make", "register_model", *_ATTRS]

__getattr__ = lazy_getattr(__name__, _ATTRS)


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))


if TYPE_CHECKING:  # pragma: no cover
    from .dummy import DummyWorldModel  # noqa: F401
    from .encoders import ConvEncoder, vit_hf  # noqa: F401
    from .gcbc import GCBC  # noqa: F401
    from .gcrl import GCRL  # noqa: F401
    from .lewm import LeWM  # noqa: F401
    from .loss import PLDMLoss, SIGReg, TemporalStraighteningLoss, VCReg  # noqa: F401
    from .pldm import PLDM  # noqa: F401
    from .utils import from_pretrained, instantiate, load_pretrained, push_to_hub, save_pretrained  # noqa: F401

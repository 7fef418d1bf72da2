"""Goal-conditioned baselines (upstream 0.1.1 path ``stable_worldmodel.wm.gcrl``): ``GCRL`` and, from
``.module``, ``Predictor``, ``QPredictor``, ``MetricValuePredictor``, ``ExpectileLoss``, ``Embedder``
and friends; the registry configs ``GCBCConfig`` / ``GCIVLConfig`` / ``GCIQLConfig``. Names resolve
lazily (``.config`` needs no torch)."""

from ..._lazy import lazy_getattr

_MODULE = (
    "Attention",
    "ConvLogitsEncoder",
    "DoublePredictorWrapper",
    "Embedder",
    "EvalOnly",
    "ExpectileLoss",
    "MetricValuePredictor",
    "Predictor",
    "QPredictor",
    "SelfAttentionTransformer",
    "TeacherStudentWrapper",
    "Transformer",
)
_CONFIG = ("GCRLConfig", "GCBCConfig", "GCIVLConfig", "GCIQLConfig", "GOAL_SAMPLING")
_WHERE = {"GCRL": ".gcrl", **{n: ".module" for n in _MODULE}, **{n: ".config" for n in _CONFIG}}

__all__ = sorted(_WHERE)
__getattr__ = lazy_getattr(__name__, _WHERE)

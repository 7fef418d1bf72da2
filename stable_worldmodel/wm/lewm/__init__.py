"""LeWM (upstream 0.1.1 path ``stable_worldmodel.wm.lewm``): ``LeWM`` and, in ``.module``,
``Predictor``, ``Embedder`` and ``MLP``. Names resolve lazily (``.config`` needs no torch)."""

from ..._lazy import lazy_getattr

__all__ = ["LeWM", "MLP", "Embedder", "Predictor", "LeWMConfig"]
__getattr__ = lazy_getattr(
    __name__,
    {"LeWM": ".lewm", "MLP": ".module", "Embedder": ".module", "Predictor": ".module", "LeWMConfig": ".config"},
)

"""PLDM (upstream 0.1.1 path ``stable_worldmodel.wm.pldm``). Names resolve lazily."""

from ..._lazy import lazy_getattr

__all__ = ["PLDM", "MLP", "Embedder", "Predictor", "PLDMConfig"]
__getattr__ = lazy_getattr(
    __name__,
    {"PLDM": ".pldm", "MLP": ".module", "Embedder": ".module", "Predictor": ".module", "PLDMConfig": ".config"},
)

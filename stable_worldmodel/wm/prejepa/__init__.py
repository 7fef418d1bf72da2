"""PreJEPA / DINO-WM (upstream 0.1.1 path ``stable_worldmodel.wm.prejepa``): ``PreJEPA``,
``create_backbone`` and, in ``.module``, ``CausalPredictor`` and ``Embedder``. Names resolve
lazily (``.config`` needs no torch)."""

from ..._lazy import lazy_getattr

_ATTRS = {
    "PreJEPA": ".prejepa",
    "CausalPredictor": ".module",
    "Embedder": ".module",
    "PatchConvEncoder": ".module",
    "AntialiasedPatchCNN": ".module",
    "BlurPatchEncoder": ".module",
    "PreJEPAConfig": ".config",
    "create_backbone": "stable_worldmodel.wm.backbones",
    "BACKBONE_ALIASES": "stable_worldmodel.wm.backbones",
}
__all__ = list(_ATTRS)
__getattr__ = lazy_getattr(__name__, _ATTRS)

"""TD-MPC2 (upstream 0.1.1 path ``stable_worldmodel.wm.tdmpc2``): ``TDMPC2`` and, in ``.module``,
``SimNorm``, ``NormedLinear``, ``RunningScale`` and the two-hot maths. Names resolve lazily
(``.config`` needs no torch)."""

from ..._lazy import lazy_getattr

_ATTRS = {
    "TDMPC2": ".tdmpc2",
    "TDMPC2Config": ".config",
    "SimNorm": ".module",
    "NormedLinear": ".module",
    "RunningScale": ".module",
    "two_hot": ".module",
    "two_hot_inv": ".module",
    "symlog": ".module",
    "symexp": ".module",
}
__all__ = list(_ATTRS)
__getattr__ = lazy_getattr(__name__, _ATTRS)

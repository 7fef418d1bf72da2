"""Dreamer (``wm.dreamer``): an RSSM world model (GRU deterministic state + Gaussian stochastic
state, KL balancing, image decoder) that plans on the latent distance to the encoded goal.
Names resolve lazily (``.config`` needs no torch)."""

from ..._lazy import lazy_getattr

_ATTRS = {
    "Dreamer": ".dreamer",
    "RSSM": ".module",
    "gaussian_kl": ".module",
    "DreamerConfig": ".config",
}
__all__ = list(_ATTRS)
__getattr__ = lazy_getattr(__name__, _ATTRS)

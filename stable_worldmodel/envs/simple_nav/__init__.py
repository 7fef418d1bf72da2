"""Release 0.0.3's SimpleNavigation (``swm/SimpleNavigation-v0``): a MiniGrid maze (:mod:`.env`,
needs the ``minigrid`` extra), its maze generator (:mod:`.maze`) and its expert (:mod:`.expert`;
0.0.3's name :class:`ExpertPolicy` in :mod:`.expert_policy`).

Names resolve lazily: importing this package imports neither minigrid nor pygame; using
``SimpleNavigationEnv`` without minigrid installed raises
:class:`~stable_worldmodel.errors.DependencyNotInstalled` naming the extra.
"""

from __future__ import annotations

from ..._lazy import lazy_getattr

__all__ = ["ExpertPolicy", "SimpleNavigationEnv", "SimpleNavigationExpert", "ellers_maze", "maze_walls"]

__getattr__ = lazy_getattr(
    __name__,
    {
        "SimpleNavigationEnv": ".env",
        "ExpertPolicy": ".expert_policy",
        "SimpleNavigationExpert": ".expert",
        "ellers_maze": ".maze",
        "maze_walls": ".maze",
    },
)

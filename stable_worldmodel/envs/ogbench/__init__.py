"""OGBench manipulation: ``swm/OGBCube-v0`` (:mod:`.cube_env`), ``swm/OGBScene-v0``
(:mod:`.scene_env`) and their expert (:mod:`.expert`), on top of the ``ogbench`` package.

Names resolve lazily, so importing this package imports neither mujoco nor ogbench.
"""

from __future__ import annotations

from ..._lazy import lazy_getattr

__all__ = ["CubeEnv", "ExpertPolicy", "OGBenchExpert", "SceneEnv"]

__getattr__ = lazy_getattr(
    __name__,
    {
        "CubeEnv": ".cube_env",
        "SceneEnv": ".scene_env",
        "OGBenchExpert": ".expert",
        "ExpertPolicy": ".expert_policy",  # upstream 0.1.1's name
    },
)

"""Release 0.0.3's module path of the OGBench manipulation envs (they live in :mod:`..ogbench`).

``from stable_worldmodel.envs.ogbench_manip import CubeEnv, SceneEnv, ExpertPolicy`` gives the
same objects as :mod:`stable_worldmodel.envs.ogbench`; names resolve lazily, so importing this
package imports neither mujoco nor ogbench.
"""

from __future__ import annotations

from ..._lazy import lazy_getattr

__all__ = ["CubeEnv", "ExpertPolicy", "SceneEnv"]

__getattr__ = lazy_getattr(
    __name__,
    {
        "CubeEnv": "stable_worldmodel.envs.ogbench.cube_env",
        "SceneEnv": "stable_worldmodel.envs.ogbench.scene_env",
        "ExpertPolicy": "stable_worldmodel.envs.ogbench.expert_policy",
    },
)

"""Release 0.0.3's module path of the OGBench Scene env (it lives in :mod:`..ogbench.scene_env`)."""

from ..ogbench.scene_env import SceneEnv

__all__ = ["SceneEnv"]

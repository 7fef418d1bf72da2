"""Release 0.0.3's module path of the OGBench Cube env (it lives in :mod:`..ogbench.cube_env`)."""

from ..ogbench.cube_env import CubeEnv

__all__ = ["CubeEnv"]

"""Release 0.0.3's module path of the OGBench expert (it lives in :mod:`..ogbench.expert_policy`)."""

from ..ogbench.expert_policy import ExpertPolicy

__all__ = ["ExpertPolicy"]

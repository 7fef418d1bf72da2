"""The seed's module name for TD-MPC2: ``TDMPC`` is :class:`~stable_worldmodel.wm.tdmpc2.TDMPC2`."""

from .tdmpc2.module import NormedLinear, RunningScale, SimNorm, symexp, symlog, two_hot, two_hot_inv
from .tdmpc2.tdmpc2 import TDMPC2

TDMPC = TDMPC2

__all__ = ["TDMPC", "TDMPC2", "NormedLinear", "RunningScale", "SimNorm", "symexp", "symlog", "two_hot", "two_hot_inv"]

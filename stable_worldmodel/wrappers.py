"""Seed 000 spelling of :mod:`stable_worldmodel.wrapper`."""

from .wrapper import *  # noqa: F401,F403
from .wrapper import __all__  # noqa: F401

"""Upstream 0.1.1's module path of the DMControl expert (``ExpertPolicy``, see :mod:`.expert`)."""

from .expert import ExpertPolicy

__all__ = ["ExpertPolicy"]

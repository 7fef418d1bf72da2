"""Release 0.0.3's expert name: ``stable_worldmodel.envs.simple_nav.expert_policy.ExpertPolicy``."""

from __future__ import annotations

from typing import Any

from .expert import SimpleNavigationExpert

__all__ = ["ExpertPolicy"]


class ExpertPolicy(SimpleNavigationExpert):
    """:class:`~.expert.SimpleNavigationExpert` under 0.0.3's name and signature (``**kwargs``)."""

    def __init__(self, **kwargs: Any):
        super().__init__(**kwargs)

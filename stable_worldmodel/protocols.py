"""The structural interfaces planning works against (upstream's ``stable_worldmodel.protocols``;
0.1.1 has ``Costable``, ``Transformable``, ``Actionable``, its main adds ``Constrainable``,
``Dynamics`` and ``Objective``). Anything with the methods satisfies them: no base class to
inherit. The runtime-checkable ones work with ``isinstance``. Importing this module is cheap.

Shapes: ``B`` envs, ``S`` candidates, ``H`` horizon, ``A`` action block, ``C`` constraints.
"""

from __future__ import annotations

from typing import Any, Protocol, runtime_checkable

__all__ = ["Actionable", "Constrainable", "Costable", "Dynamics", "Objective", "Transformable"]


@runtime_checkable
class Costable(Protocol):
    """What every solver optimizes: ``get_cost(info, candidates (B, S, H, A)) -> (B, S)``; world
    models, :class:`~stable_worldmodel.planning.ShootingCostEvaluator` and any cost object."""

    def criterion(self, info_dict: dict, action_candidates: Any) -> Any:
        """The cost of candidates whose rollout is already in ``info_dict``."""
        ...

    def get_cost(self, info_dict: dict, action_candidates: Any) -> Any:
        """Roll the candidates out and score them: ``(B, S)``."""
        ...


@runtime_checkable
class Constrainable(Protocol):
    """A cost object under inequality constraints (what ``LagrangianSolver`` looks for):
    ``get_constraints(info, candidates) -> (B, S, C)``, constraint ``i`` satisfied where ``<= 0``."""

    def get_constraints(self, info_dict: dict, action_candidates: Any) -> Any: ...


@runtime_checkable
class Dynamics(Protocol):
    """What :class:`~stable_worldmodel.planning.ShootingCostEvaluator` needs of a world model:
    ``encode(info) -> info`` (adds embeddings) and ``rollout(info, candidates) -> info`` (adds
    ``predicted_emb``)."""

    def encode(self, x: dict) -> dict: ...

    def rollout(self, info_dict: dict, action_candidates: Any) -> dict: ...


@runtime_checkable
class Objective(Protocol):
    """Scores an already rolled-out ``info_dict`` (``predicted_emb``, ``goal_emb``, and the
    ``action_candidates`` the evaluator stores there): ``(B, S)``. No rollout of its own."""

    def __call__(self, info_dict: dict) -> Any: ...


class Transformable(Protocol):
    """A reversible transform of arrays (the normalizers)."""

    def transform(self, x: Any) -> Any: ...

    def inverse_transform(self, x: Any) -> Any: ...


@runtime_checkable
class Actionable(Protocol):
    """A model that acts: ``get_action(info, horizon=1, prefix_actions=None)`` gives ``(..., A)``
    (``(..., horizon, A)`` for ``horizon > 1``), after applying ``prefix_actions`` first."""

    def get_action(self, info: dict, horizon: int = 1, prefix_actions: Any = None) -> Any: ...

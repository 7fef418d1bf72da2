"""``ShootingCostEvaluator`` (upstream main): a world model's ``encode`` / ``rollout`` composed with
a swappable :class:`~stable_worldmodel.protocols.Objective` into a cost the solvers take.

Single shooting: the whole candidate plan is rolled out at once, then scored. The goal is
encoded once per solve (kept in ``info["goal_emb"]``), the candidates are stored under
``info["action_candidates"]`` for action-space objectives, and constraint objectives (each
``(B, S)``, satisfied where ``<= 0``) are exposed as ``get_constraints`` for ``LagrangianSolver``.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

import torch

from .. import keys
from ..errors import ConfigError, UnknownNameError

__all__ = ["ShootingCostEvaluator", "default_goal_encode"]

GOAL_EMB = "goal_emb"
CANDIDATES = "action_candidates"


def default_goal_encode(model: Any, info_dict: dict) -> torch.Tensor:
    """The goal's embeddings ``(B, T, D)`` from ``info_dict["goal"]`` (and ``goal_<key>`` extras).

    Our JEPA-family models encode it as their own ``get_cost`` does; another model gets upstream's
    recipe: the first candidate's copy of each tensor, ``goal`` as ``pixels``, ``goal_<k>`` as
    ``<k>``, without actions, through ``model.encode(...)["emb"]``.
    """
    if keys.GOAL not in info_dict:
        raise UnknownNameError(f"ShootingCostEvaluator requires info['goal'] to encode, got keys {sorted(info_dict)}")
    context = getattr(model, "_context", None)
    goal = info_dict[keys.GOAL]
    if callable(context) and torch.is_tensor(goal):
        b = goal.shape[0]
        s = goal.shape[1] if goal.ndim == 6 else None
        emb = context(info_dict, keys.GOAL, "_evaluator_goal", b, s)
        info_dict.pop("_evaluator_goal", None)
        return emb
    first = {k: v[:, 0] for k, v in info_dict.items() if torch.is_tensor(v)}
    first[keys.PIXELS] = first.pop(keys.GOAL)
    for k in [k for k in first if k.startswith(keys.goal_key(""))]:
        first[k[len(keys.goal_key("")) :]] = first.pop(k)
    first.pop(keys.ACTION, None)
    first.pop("action_history", None)
    return model.encode(first)["emb"]


class ShootingCostEvaluator(torch.nn.Module):
    """``(model, objective)`` as a :class:`~stable_worldmodel.protocols.Costable`.

    Args:
        model: a world model with ``encode`` and ``rollout`` (registered as a submodule, so the
            solvers find its device and dtype through ``parameters()``).
        objective: scores the rolled-out info, ``(B, S)`` (e.g. :class:`~.objective.GoalMSE`).
        constraints: objectives used as constraints (each ``(B, S)``, satisfied where ``<= 0``);
            when given, ``get_constraints`` returns them stacked ``(B, S, C)``.
        encode_goal: ``fn(model, info) -> goal_emb``; None skips goal encoding (the caller put
            ``goal_emb`` in the info).
    """

    def __init__(
        self,
        model: Any,
        objective: Callable[[dict], torch.Tensor],
        constraints: Sequence[Callable[[dict], torch.Tensor]] | None = None,
        encode_goal: Callable[[Any, dict], torch.Tensor] | None = default_goal_encode,
    ) -> None:
        super().__init__()
        missing = [m for m in ("encode", "rollout") if not callable(getattr(model, m, None))]
        if missing:
            raise ConfigError(
                f"ShootingCostEvaluator requires a model with encode and rollout (the Dynamics protocol), "
                f"got {type(model).__name__} without {', '.join(missing)}"
            )
        if not callable(objective):
            raise ConfigError(
                f"ShootingCostEvaluator requires a callable objective (info -> (B, S)), got {objective!r}"
            )
        self.model = model
        self.objective = objective
        self.constraints = list(constraints) if constraints else None
        self.encode_goal = encode_goal
        if self.constraints:
            self.get_constraints = self._get_constraints

    def _rollout(self, info_dict: dict, action_candidates: torch.Tensor) -> dict:
        if self.encode_goal is not None and GOAL_EMB not in info_dict:
            info_dict[GOAL_EMB] = self.encode_goal(self.model, info_dict)
        info_dict = self.model.rollout(info_dict, action_candidates)
        info_dict[CANDIDATES] = action_candidates
        return info_dict

    def criterion(self, info_dict: dict, action_candidates: torch.Tensor | None = None) -> torch.Tensor:
        """The objective on an already rolled-out ``info_dict``."""
        if action_candidates is not None:
            info_dict[CANDIDATES] = action_candidates
        return self.objective(info_dict)

    def get_cost(self, info_dict: dict, action_candidates: torch.Tensor) -> torch.Tensor:
        """Encode the goal (once), roll the candidates out, score them: ``(B, S)``."""
        return self.objective(self._rollout(info_dict, action_candidates))

    def _get_constraints(self, info_dict: dict, action_candidates: torch.Tensor) -> torch.Tensor:
        info_dict = self._rollout(info_dict, action_candidates)
        return torch.stack([term(info_dict) for term in self.constraints], dim=-1)

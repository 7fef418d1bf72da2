"""Upstream 0.1.1's expert name: ``stable_worldmodel.envs.ogbench.expert_policy.ExpertPolicy``."""

from __future__ import annotations

from typing import Any

from ...errors import ConfigError
from .expert import OGBenchExpert

__all__ = ["ExpertPolicy"]


class ExpertPolicy(OGBenchExpert):
    """:class:`~.expert.OGBenchExpert` under upstream's signature. Only ``policy_type="markov_oracle"``
    exists here; ``action_noise`` is the Gaussian noise std; ``noise_smoothing`` (upstream: for the
    plan oracles) is accepted and unused."""

    def __init__(
        self,
        policy_type: str = "markov_oracle",
        action_noise: float = 0.1,
        p_random_action: float = 0.0,
        noise_smoothing: float = 0.5,
        min_norm: float = 0.4,
        seed: int | None = None,
        **kwargs: Any,
    ):
        if policy_type != "markov_oracle":
            raise ConfigError(f"ExpertPolicy requires policy_type 'markov_oracle', got {policy_type!r}")
        kwargs.setdefault("env_id", "swm/OGBCube-v0")
        super().__init__(noise=action_noise, p_random_action=p_random_action, min_norm=min_norm, seed=seed, **kwargs)
        self.noise_smoothing = noise_smoothing

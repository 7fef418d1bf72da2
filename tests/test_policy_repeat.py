"""``RepeatActionPolicy``: sticky actions over any batched policy (upstream's TwoRoom collector
``ExpertPolicy(action_repeat_prob=...)`` made generic)."""

from __future__ import annotations

import numpy as np
import pytest

from stable_worldmodel.errors import ConfigError
from stable_worldmodel.planning.policies import make_policy
from stable_worldmodel.policy import BasePolicy, RepeatActionPolicy


class Counter(BasePolicy):
    """Action of env i at call t: (t, i), so a repeat is visible."""

    def __init__(self):
        super().__init__()
        self.t = 0

    def get_action(self, obs, **kwargs):
        self.t += 1
        return np.stack([np.full(4, self.t, np.float32), np.arange(4, dtype=np.float32)], axis=1)


def actions(policy: BasePolicy, steps: int) -> np.ndarray:
    return np.stack([policy.get_action({}) for _ in range(steps)])


@pytest.mark.parametrize("p", [0.0, 0.3, 1.0])
def test_each_env_repeats_its_previous_action_with_probability_p(p):
    policy = RepeatActionPolicy(Counter(), p, seed=0)
    out = actions(policy, 400)
    repeated = out[1:, :, 0] == out[:-1, :, 0]  # (steps, envs): the env kept its last action
    assert abs(repeated.mean() - p) < 0.05
    assert (out[:, :, 1] == np.arange(4)).all()  # each env keeps its own action
    if p == 1.0:
        assert (out[:, :, 0] == 1).all()  # the first action, forever
    assert (out[0, :, 0] == 1).all()  # nothing to repeat at the first call


def test_seeded_repeats_replay_and_the_inner_policy_gets_the_seed():
    a = RepeatActionPolicy(Counter(), 0.5, seed=7)
    b = RepeatActionPolicy(Counter(), 0.5, seed=7)
    np.testing.assert_array_equal(actions(a, 50), actions(b, 50))
    inner = Counter()
    inner.rng = np.random.default_rng(0)
    policy = RepeatActionPolicy(inner, 0.5)
    policy.set_seed(3)
    assert inner.seed == 3 and policy.seed == 3
    first = actions(policy, 30)
    policy.policy.t = 0
    policy.set_seed(3)
    np.testing.assert_array_equal(actions(policy, 30), first)  # a new seed forgets the last action too


@pytest.mark.parametrize("bad", [-0.1, 1.5, "0.5", True, None])
def test_bad_probabilities_are_config_errors(bad):
    with pytest.raises(ConfigError, match="repeat_prob"):
        RepeatActionPolicy(Counter(), bad)


def test_make_policy_builds_upstreams_collectors_by_name():
    from stable_worldmodel.envs.pusht.weak import WeakPolicy

    weak = make_policy("weak", "swm/PushT-v1", seed=1)
    assert isinstance(weak, WeakPolicy) and weak.dist_constraint == 100.0
    assert make_policy("weak", "swm/PushT-v1", dist_constraint=20).dist_constraint == 20.0
    sticky = make_policy("expert", "swm/TwoRoom-v1", seed=2, noise=2.0, repeat_prob=0.05)
    assert isinstance(sticky, RepeatActionPolicy) and sticky.repeat_prob == 0.05
    with pytest.raises(ConfigError, match="requires a PushT environment"):
        make_policy("weak", "swm/TwoRoom-v1")
    with pytest.raises(ConfigError, match="--dist-constraint requires --policy weak"):
        make_policy("random", "swm/PushT-v1", dist_constraint=5)

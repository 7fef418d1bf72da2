"""DMC task variants of upstream 0.1.1: Cheetah ``run-backward`` and Hopper ``hop-backward``."""

from __future__ import annotations

import numpy as np
import pytest

from stable_worldmodel._optional import is_available

if not (is_available("mujoco") and is_available("dm_control")):
    pytest.skip("extra 'mujoco' not installed", allow_module_level=True)

import gymnasium as gym  # noqa: E402

import stable_worldmodel as swm  # noqa: E402, F401  (registers the ids)
from stable_worldmodel.envs.dmcontrol.cheetah import CheetahDMControlWrapper  # noqa: E402
from stable_worldmodel.envs.dmcontrol.hopper import HopperDMControlWrapper  # noqa: E402
from stable_worldmodel.errors import UnknownNameError  # noqa: E402

# upstream 0.1.1, observed: gym.make(id, task=...), reset(seed=3), 25 steps of
# np.random.default_rng(0).uniform(-1, 1, action_shape): (return, final info["speed"], obs[:4])
UPSTREAM_ROLLOUTS = {
    ("swm/CheetahDMControl-v0", "run-backward"): (
        1.5523200946,
        -0.2987712453,
        [-0.097772978246212, 0.0467512384057045, 0.3460412323474884, -0.07976973801851273],
    ),
    ("swm/HopperDMControl-v0", "hop-backward"): (
        0.0153709764,
        0.1619171452,
        [-0.9308980107307434, -1.4957106113433838, -0.5274050235748291, 0.17620201408863068],
    ),
}


def _reward_at_speed(env, speed: float) -> float:
    """The task's reward with the body at its reference pose sliding along x at ``speed``."""
    physics = env.unwrapped._physics
    qvel = np.zeros(env.unwrapped.model.nv)
    qvel[physics.named.model.jnt_dofadr["rootx"]] = speed
    env.unwrapped.set_state(env.unwrapped.model.qpos0, qvel)
    return float(env.unwrapped._task.get_reward(physics))


@pytest.mark.parametrize(("env_id", "task"), sorted(UPSTREAM_ROLLOUTS))
def test_dmc_backward_task_rollout_matches_upstream(env_id, task):
    env = gym.make(env_id, task=task, render_quality="low")
    env.unwrapped.set_render_size((16, 16))
    env.reset(seed=3)
    rng = np.random.default_rng(0)
    total = 0.0
    for _ in range(25):
        obs, reward, terminated, truncated, info = env.step(rng.uniform(-1, 1, env.action_space.shape))
        total += reward
        assert not terminated and not truncated
    ret, speed, head = UPSTREAM_ROLLOUTS[(env_id, task)]
    assert total == pytest.approx(ret, abs=1e-8)
    assert info["speed"] == pytest.approx(speed, abs=1e-8)
    np.testing.assert_allclose(obs[:4], head, atol=1e-6)
    env.close()


def test_dmc_cheetah_run_backward_rewards_negative_velocity():
    fwd = CheetahDMControlWrapper(task="run", render_quality="low")
    back = CheetahDMControlWrapper(task="run-backward", render_quality="low")
    for env in (fwd, back):
        env.reset(seed=0)
    # dm_control's run: 1 from +10 m/s, linear to 0 at 0; run-backward mirrors it
    assert [_reward_at_speed(back, v) for v in (-12.0, -10.0, -5.0, 0.0, 5.0, 12.0)] == pytest.approx(
        [1.0, 1.0, 0.5, 0.0, 0.0, 0.0]
    )
    assert [_reward_at_speed(fwd, v) for v in (-12.0, 5.0, 12.0)] == pytest.approx([0.0, 0.5, 1.0])
    assert back.task_name == "run-backward" and back.env_name == "Cheetah"


def test_dmc_hopper_hop_backward_rewards_negative_velocity():
    env = HopperDMControlWrapper(task="hop-backward", render_quality="low")
    env.reset(seed=0)
    # standing at the reference pose (torso 0.8 m over the foot), so the reward is the speed term
    assert [_reward_at_speed(env, v) for v in (-3.0, -1.0, -0.75, -0.5, 0.0, 2.0)] == pytest.approx(
        [1.0, 1.0, 0.75, 0.5, 0.0, 0.0]
    )
    hop = HopperDMControlWrapper(task="hop", render_quality="low")
    hop.reset(seed=0)
    assert _reward_at_speed(hop, 2.0) == pytest.approx(1.0) and _reward_at_speed(hop, -2.0) == 0.0


def test_dmc_backward_tasks_keep_spaces_factors_and_seeded_starts():
    for cls, task, base in (
        (CheetahDMControlWrapper, "run-backward", "run"),
        (HopperDMControlWrapper, "hop-backward", "hop"),
    ):
        a, b = cls(task=task, render_quality="low"), cls(task=base, render_quality="low")
        assert a.observation_space == b.observation_space and a.action_space == b.action_space
        assert a.variation_space.names() == b.variation_space.names()
        (oa, ia), (ob, ib) = a.reset(seed=7), b.reset(seed=7)
        np.testing.assert_array_equal(oa, ob)
        assert set(ia) == set(ib)


def test_dmc_unknown_task_names_the_variants():
    with pytest.raises(UnknownNameError, match="run-backward"):
        CheetahDMControlWrapper(task="run_backward")
    with pytest.raises(UnknownNameError, match="hop-backward"):
        HopperDMControlWrapper(task="hop-backwards")

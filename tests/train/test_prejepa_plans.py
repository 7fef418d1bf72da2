"""A PreJEPA trained through the trainer plans in a World with ``wm:RUN``, proprio included."""

from __future__ import annotations

import numpy as np

import stable_worldmodel as swm
from stable_worldmodel import keys
from stable_worldmodel.planning.learned import PlanSettings, world_model_policy
from stable_worldmodel.train import train

NET = dict(image_size=16, embed_dim=8, cnn_width=8, cnn_grid=2, depth=1, heads=2, dim_head=4, mlp_dim=16,
           history_size=2, frameskip=1, warmup_steps=0, batch_size=4)


def test_a_proprio_model_plans_with_the_normalizer_it_was_trained_with(toy, _stablewm_home):
    train("prejepa", toy, steps=2, progress=False, name="pj", val_every=0, proprio_dim=2, **NET)
    policy, protocol = world_model_policy("pj", PlanSettings(horizon=2, samples=8, iterations=2), device="cpu")
    assert set(protocol["normalizers"]) == {keys.ACTION, keys.PROPRIO}
    assert keys.PROPRIO in policy.process  # proprio and goal_proprio are normalized as in training
    proprio = np.float32([[[0.3, 0.7]]])
    expected = (proprio.reshape(-1, 2) - protocol["normalizers"][keys.PROPRIO]["mean"]) / protocol["normalizers"][keys.PROPRIO]["std"]
    assert np.allclose(policy.process[keys.PROPRIO].transform(proprio.reshape(-1, 2)), expected, atol=1e-5)
    with swm.World("swm/Toy-v0", 2, (16, 16), max_episode_steps=3, verbose=0) as world:
        world.set_policy(policy)
        out = world.evaluate(episodes=2, seed=0)
    assert out["episode_count"] == 2

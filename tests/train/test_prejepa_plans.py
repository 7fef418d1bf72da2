"""A PreJEPA trained through the trainer plans in a World with ``wm:RUN``, proprio included."""

from __future__ import annotations

import numpy as np

import stable_worldmodel as swm
from stable_worldmodel import keys
from stable_worldmodel.planning.learned import PlanSettings, world_model_policy
from stable_worldmodel.train import train

NET = dict(
    image_size=16,
    embed_dim=8,
    cnn_width=8,
    cnn_grid=2,
    depth=1,
    heads=2,
    dim_head=4,
    mlp_dim=16,
    history_size=2,
    frameskip=1,
    warmup_steps=0,
    batch_size=4,
)


def test_a_proprio_model_plans_with_the_normalizer_it_was_trained_with(toy, _stablewm_home):
    train("prejepa", toy, steps=2, progress=False, name="pj", val_every=0, proprio_dim=2, **NET)
    policy, protocol = world_model_policy("pj", PlanSettings(horizon=2, samples=8, iterations=2), device="cpu")
    assert set(protocol["normalizers"]) == {keys.ACTION, keys.PROPRIO}
    assert keys.PROPRIO in policy.process  # proprio and goal_proprio are normalized as in training
    proprio = np.float32([[[0.3, 0.7]]])
    expected = (proprio.reshape(-1, 2) - protocol["normalizers"][keys.PROPRIO]["mean"]) / protocol["normalizers"][
        keys.PROPRIO
    ]["std"]
    assert np.allclose(policy.process[keys.PROPRIO].transform(proprio.reshape(-1, 2)), expected, atol=1e-5)
    with swm.World("swm/Toy-v0", 2, (16, 16), max_episode_steps=3, verbose=0) as world:
        world.set_policy(policy)
        out = world.evaluate(episodes=2, seed=0)
    assert out["episode_count"] == 2


def test_subgoal_graph_on_patch_features_and_not_with_proprio(toy, _stablewm_home, graph_plan):
    """``subgoals="graph"`` with a PreJEPA: nodes are flattened patch features, the waypoint goes
    where its cost reads the goal's (``pixels_goal_emb``); a proprio PreJEPA is refused (its goal
    proprio would still be the final goal's)."""
    import pytest
    import torch

    from stable_worldmodel.errors import ConfigError

    train("prejepa", toy, steps=2, progress=False, name="pj", val_every=0, **NET)
    policy, protocol, seen = graph_plan("pj")
    assert protocol["plan"]["graph"]["nodes"] > 0
    feats = seen[0]["pixels_emb"]  # (B, T, P, Dv), and the waypoint (B, 1, P, Dv): one of the graph's nodes
    waypoint = seen[0]["pixels_goal_emb"]
    # the World keeps 2 frames, the policy gives the model its history_len (1)
    assert feats.shape[:2] == (2, 1) and waypoint.shape == (2, 1, *feats.shape[2:])
    nodes = policy.info_hook.graph.embeddings
    goal = policy.solver.model.encode_pixels(seen[0][keys.GOAL][:, -1])  # (B, P, Dv)
    # a node of the graph, or the goal itself once within the lookahead
    for w, g in zip(waypoint[:, 0], goal, strict=False):
        assert torch.isclose(nodes, w.flatten(), atol=1e-5).all(1).any() or torch.allclose(w, g, atol=1e-5)
    train("prejepa", toy, steps=2, progress=False, name="pjp", val_every=0, proprio_dim=2, **NET)
    with pytest.raises(ConfigError, match="PreJEPA without proprio.*'pjp'"):
        world_model_policy("pjp", PlanSettings(subgoals="graph"), device="cpu")

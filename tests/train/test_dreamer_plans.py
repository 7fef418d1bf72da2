"""A Dreamer trained through the trainer plans towards subgoal-graph waypoints (``wm:RUN`` with
``subgoals="graph"`` / ``"auto"``): nodes are its image encoder's frame embeddings, which its
cost compares the embeddings it predicts with."""

from __future__ import annotations

import torch

from stable_worldmodel import keys
from stable_worldmodel.planning.learned import PlanSettings, resolve_subgoals
from stable_worldmodel.train import train

NET = dict(
    image_size=16,
    cnn_width=8,
    embed_dim=8,
    deter_dim=16,
    stoch_dim=4,
    hidden=16,
    history_size=2,
    frameskip=1,
    warmup_steps=0,
    batch_size=4,
)


def test_dreamer_waypoints_are_frame_embeddings(toy, _stablewm_home, graph_plan):
    train("dreamer", toy, steps=2, progress=False, name="dr", val_every=0, **NET)
    assert resolve_subgoals("dr", PlanSettings()).subgoals == "auto"  # dreamer is a graph model now
    policy, protocol, seen = graph_plan("dr")
    model = policy.solver.model
    assert protocol["plan"]["graph"]["nodes"] > 0
    info = seen[0]
    assert "emb" not in info  # the hook leaves the context to the model (it filters it with the actions)
    waypoint = info["goal_emb"]  # (B, 1, F)
    assert waypoint.shape == (2, 1, model.rssm.embed_dim)
    nodes = policy.info_hook.graph.embeddings
    with torch.no_grad():
        goal = model.encode_goal(info[keys.GOAL][:, -1])  # (B, E)
    # a node of the graph, or the goal itself once within the lookahead
    for w, g in zip(waypoint[:, 0], goal, strict=False):
        assert torch.isclose(nodes, w, atol=1e-5).all(1).any() or torch.allclose(w, g, atol=1e-5)

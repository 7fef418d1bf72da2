"""The generalization report end to end on TwoRoom: the expert, a tiny learned world model (planned
with) and a tiny goal-conditioned policy (feed-forward)."""

from __future__ import annotations

import json

ENV = "swm/TwoRoom-v2"
TINY = dict(
    image_size=16,
    embed_dim=16,
    cnn_width=8,
    depth=1,
    heads=2,
    dim_head=8,
    mlp_dim=32,
    projector_hidden=32,
    sigreg_num_proj=32,
    batch_size=8,
    frameskip=1,
)


def test_fov_sweep_on_tworoom_with_the_expert_and_a_tiny_learned_model(swm, _stablewm_home, tmp_path):
    from stable_worldmodel import World
    from stable_worldmodel.envs import expert_policy
    from stable_worldmodel.train import train

    with World(ENV, 2, (16, 16), max_episode_steps=12, verbose=0, vectorization_mode="sync") as world:
        world.set_policy(expert_policy(ENV))
        world.record_dataset("tr", episodes=4, seed=0)
    train("lewm", "tr", "tiny", steps=2, name="tr-lewm", seed=0, device="cpu", progress=False, **TINY)
    train(
        "gcbc",
        "tr",
        "tiny",
        steps=2,
        name="tr-gcbc",
        seed=0,
        device="cpu",
        progress=False,
        image_size=16,
        embed_dim=8,
        cnn_width=8,
        depth=3,
        heads=2,
        dim_head=4,
        mlp_dim=16,
        batch_size=8,
        frameskip=1,
    )

    out = tmp_path / "sweep.json"
    result = swm(
        "eval",
        ENV,
        "--policy",
        "expert,wm:tr-lewm,gc:tr-gcbc",
        "--fov-sweep",
        "agent,wall",
        "-n",
        "2",
        "--max-steps",
        "6",
        "--image-size",
        "16",
        "--device",
        "cpu",
        "--samples",
        "8",
        "--iterations",
        "1",
        "--horizon",
        "2",
        "--json",
        str(out),
    )
    assert result.exit_code == 0, result.output
    report = json.loads(out.read_text())
    assert report["settings"] == ["in distribution", "agent", "wall", "all factors"]
    for policy in ("expert", "wm:tr-lewm", "gc:tr-gcbc"):
        rows = report["results"][policy]
        assert [r["variation"] for r in rows] == [[], ["agent"], ["wall"], ["all"]]
        assert all(len(r["episode_successes"]) == 2 for r in rows)
    assert report["protocol"]["plan"]["samples"] == 8
    assert out.with_suffix(".png").is_file()

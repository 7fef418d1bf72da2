"""Planning with a trained Dreamer (``wm:RUN``) on swm/Toy-v0: its cost (the predicted frame
embedding's distance to the goal frame's) must lead an agent to the goal better than chance.

Dreamer used to plan at the random policy's level on TwoRoom (its mean-reduced reconstruction let
the KL terms win, so the latent ignored the agent; its cost compared RSSM states with a lone goal
frame). Its latent starts encoding the dot after ~400 steps here, hence 1000 (~25 s)."""

from __future__ import annotations

import pytest
from _toy_home import HIDDEN_GOAL, IMAGE, TOY, toy_home

from stable_worldmodel import World
from stable_worldmodel.planning.learned import PlanSettings, world_model_policy
from stable_worldmodel.policy import RandomPolicy

EVAL_SEED = 10_000
NET = dict(
    image_size=IMAGE,
    cnn_width=8,
    embed_dim=16,
    deter_dim=32,
    stoch_dim=8,
    hidden=32,
    history_size=1,
    num_preds=2,
    frameskip=1,
    batch_size=32,
    warmup_steps=10,
)


@pytest.fixture(scope="module")
def home(tmp_path_factory):
    yield from toy_home(tmp_path_factory, "stablewm_dreamer", [("dreamer", "dr", dict(steps=1000, **NET))])


def test_planning_with_a_trained_dreamer_beats_random(home):
    def success_rate(policy) -> float:
        with World(
            TOY, 4, (IMAGE, IMAGE), max_episode_steps=30, verbose=0, seed=EVAL_SEED, vectorization_mode="sync"
        ) as world:
            world.set_policy(policy)
            return world.evaluate(episodes=32, seed=EVAL_SEED, options=HIDDEN_GOAL)["success_rate"]

    settings = PlanSettings(solver="cem", horizon=2, receding_horizon=1, samples=64, iterations=4, subgoals="none")
    policy, _ = world_model_policy("dr", settings, device="cpu", cache_dir=str(home))
    planned, random = success_rate(policy), success_rate(RandomPolicy(seed=0))
    # checked by hand, training seeds 0 / 1 / 2: planner 50 / 59 / 62%, random 6%; 700 steps: 28%, 400: 6%
    assert planned >= max(2 * random, random + 20), f"planner {planned:.1f}% vs random {random:.1f}%"

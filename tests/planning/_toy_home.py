"""A cache of tiny checkpoints trained on swm/Toy-v0 for the planning tests (see :func:`toy_home`)."""

from __future__ import annotations

from collections.abc import Iterator

import numpy as np
import pytest
import torch

from stable_worldmodel import World, keys

TOY = "swm/Toy-v0"
IMAGE = 16
#: the goal disk painted in the background color: the pixels show only the agent. With the disk
#: visible, a model trained for seconds spends its embedding on the (static) goal position and
#: plans no better than random; the goal *image* still shows the agent at the goal.
HIDDEN_GOAL = {keys.VARIATION_VALUES: {"goal.color": np.array([245, 245, 245], np.uint8)}}


def toy_home(tmp_path_factory, prefix: str, runs: list[tuple[str, str, dict]]) -> Iterator:
    """For a module fixture: yields a cache with dataset ``toy`` (160 expert episodes at 16x16, goal
    disk hidden) and checkpoints ``runs`` (``(model, name, train kwargs)``, trained on the CPU with
    one torch thread: reproducible floats, and fast on busy CPUs)."""
    from stable_worldmodel.envs import expert_policy
    from stable_worldmodel.train import train

    root = tmp_path_factory.mktemp(prefix)
    threads = torch.get_num_threads()
    torch.set_num_threads(1)
    try:
        with pytest.MonkeyPatch.context() as mp:
            mp.setenv("STABLEWM_HOME", str(root))
            with World(TOY, 4, (IMAGE, IMAGE), max_episode_steps=20, verbose=0, vectorization_mode="sync") as world:
                world.set_policy(expert_policy(TOY))
                world.record_dataset("toy", episodes=160, seed=0, options=HIDDEN_GOAL, cache_dir=root)
            for model, name, kwargs in runs:
                train(
                    model,
                    "toy",
                    "tiny",
                    name=name,
                    device="cpu",
                    seed=0,
                    progress=False,
                    cache_dir=str(root),
                    log_every=100,
                    **kwargs,
                )
        yield root
    finally:
        torch.set_num_threads(threads)

"""The code examples of seed 001 (the World API of release 0.0.3), run as written.

Each example runs in a fresh temporary working directory (``./videos`` and ``./data`` land
there) with ``STABLEWM_HOME`` pointing at a temporary cache.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest


@pytest.fixture(autouse=True)
def _in_tmp_cwd(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)


def test_world_quick_start():
    from stable_worldmodel import World
    from stable_worldmodel.policy import RandomPolicy

    # 1. Initialize the World with 4 parallel environments
    world = World(env_name="swm/PushT-v1", num_envs=4, image_shape=(64, 64), history_size=1)

    # 2. Set a policy (e.g., Random)
    world.set_policy(RandomPolicy())

    # 3. Reset and step
    world.reset()
    for _ in range(100):
        world.step()
        # Access current states/infos
        # world.infos["pixels"] -> (4, 3, 64, 64)
    # released 0.0.3 (and we) batch infos as (envs, history, H, W, C)
    assert world.infos["pixels"].shape == (4, 1, 64, 64, 3)


def test_record_video_example():
    from stable_worldmodel import World
    from stable_worldmodel.policy import RandomPolicy

    world = World(env_name="swm/PushT-v1", num_envs=1, image_shape=(64, 64))
    world.set_policy(RandomPolicy())

    # Record a 500-step video
    world.record_video(video_path="./videos", max_steps=500, viewname="pixels")
    videos = sorted(Path("videos").glob("*.mp4"))
    assert len(videos) == 1 and videos[0].stat().st_size > 1000


def test_record_dataset_then_evaluate_from_dataset():
    from stable_worldmodel import World
    from stable_worldmodel.policy import RandomPolicy

    world = World(
        env_name="swm/PushT-v1",
        num_envs=4,  # Collect 4 episodes in parallel
        image_shape=(64, 64),
    )
    world.set_policy(RandomPolicy())

    # Record 50 episodes to a .h5 dataset
    world.record_dataset(dataset_name="pusht_random", episodes=50, cache_dir="./data")
    # Result: ./data/pusht_random.h5
    assert Path("data/pusht_random.h5").is_file()

    from stable_worldmodel import World
    from stable_worldmodel.data import HDF5Dataset
    from stable_worldmodel.policy import RandomPolicy  # or your trained policy

    # 1. Load a dataset for initial states
    dataset = HDF5Dataset("pusht_random", cache_dir="./data")

    # 2. Setup World
    world = World(env_name="swm/PushT-v1", num_envs=4, image_shape=(64, 64))
    world.set_policy(RandomPolicy())

    # 3. Evaluate starting from dataset states
    results = world.evaluate_from_dataset(
        dataset=dataset,
        episodes_idx=[0, 1, 2, 3],  # Episodes to test on
        start_steps=[0, 0, 0, 0],  # Start from beginning
        goal_offset_steps=50,  # Goal is state at t=50
        eval_budget=100,  # Max steps to reach goal
    )

    print(f"Success Rate: {results['success_rate']}%")
    assert len(dataset.lengths) == 50
    assert 0.0 <= results["success_rate"] <= 100.0


def test_per_env_options_example():
    from stable_worldmodel import World

    world = World(env_name="swm/PushT-v1", num_envs=3, image_shape=(64, 64))

    # Different variations for each environment
    per_env_options = [
        {"variation": ["agent.color"], "variation_values": {"agent.color": [255, 0, 0]}},
        {"variation": ["agent.color"], "variation_values": {"agent.color": [0, 255, 0]}},
        {"variation": ["agent.color"], "variation_values": {"agent.color": [0, 0, 255]}},
    ]

    world.reset(options=per_env_options)
    colors = world.infos["variation.agent.color"][:, -1]
    np.testing.assert_array_equal(colors, [[255, 0, 0], [0, 255, 0], [0, 0, 255]])

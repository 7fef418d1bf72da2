"""Fixtures of the trainer tests: one toy dataset recorded once per session and copied into each
test's cache, synthetic datasets with chosen columns, tiny model sizes (the ``swm`` runner is in ../conftest.py)."""

from __future__ import annotations

import shutil

import numpy as np
import pytest
from _nets import TINY_JEPA

TOY = "swm/Toy-v0"
#: name of the recorded dataset in every test's cache
DATASET = "toy"
#: episodes of the recorded dataset (lengths 3 to 13 rows: the expert reaches the goal quickly)
EPISODES = 10
#: a width-8 CNN world model at 16x16 with one predictor layer (LeWM, PLDM)
NET = dict(TINY_JEPA, history_size=2, warmup_steps=0)
#: what each model of the ``tiny`` preset needs on top of the preset to train in well under a second
TINY = {
    "dummy": dict(image_size=16, frameskip=1, warmup_steps=0),
    "lewm": dict(NET, sigreg_num_proj=16),
    "pldm": dict(NET, idm_hidden=16),
    "dreamer": dict(
        image_size=16,
        cnn_width=8,
        embed_dim=8,
        deter_dim=16,
        stoch_dim=4,
        hidden=16,
        history_size=2,
        frameskip=1,
        warmup_steps=0,
    ),
}


@pytest.fixture(autouse=True)
def _one_thread(one_torch_thread):
    """Every trainer test runs torch on one thread (see ../conftest.py)."""


@pytest.fixture(scope="session")
def _recorded(tmp_path_factory):
    """The toy dataset, recorded once: ``EPISODES`` expert episodes at 16x16."""
    from stable_worldmodel import World
    from stable_worldmodel.envs import expert_policy

    root = tmp_path_factory.mktemp("recorded")
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("STABLEWM_HOME", str(root))
        with World(TOY, 1, (16, 16), max_episode_steps=20, verbose=0) as world:
            world.set_policy(expert_policy(TOY))
            return world.record_dataset(DATASET, episodes=EPISODES, seed=0, cache_dir=root)


@pytest.fixture
def toy(_recorded, _stablewm_home) -> str:
    """The name of the recorded toy dataset, copied into this test's cache."""
    _stablewm_home.mkdir(parents=True, exist_ok=True)
    shutil.copy(_recorded, _stablewm_home / f"{DATASET}.h5")
    return DATASET


@pytest.fixture
def write_dataset(_stablewm_home):
    """``write_dataset(name, columns=("pixels", "action"), lengths=(6, 6, 6))``: a synthetic
    dataset in the cache with only ``columns`` (random 16x16 pixels, 2-d actions)."""
    from stable_worldmodel.data.writer import HDF5Writer

    def write(name: str, columns=("pixels", "action"), lengths=(6, 6, 6)):
        rng = np.random.default_rng(0)
        make = {
            "pixels": lambda n: rng.integers(0, 256, (n, 16, 16, 3), dtype=np.uint8),
            "action": lambda n: rng.normal(size=(n, 2)).astype(np.float32),
            "reward": lambda n: rng.normal(size=n),
        }
        _stablewm_home.mkdir(parents=True, exist_ok=True)
        path = _stablewm_home / f"{name}.h5"
        with HDF5Writer(path) as writer:
            writer.write_episodes([{c: make[c](n) for c in columns} for n in lengths])
        return name

    return write


@pytest.fixture
def fit(toy):
    """``fit(model, name, **kwargs)``: :func:`stable_worldmodel.train.train` on the toy dataset on the
    CPU, tiny sizes (``TINY[model]``, none for an unknown model), batch 8, no progress bar;
    ``kwargs`` override anything."""
    from stable_worldmodel.train import train

    def run(model: str, name: str, **kwargs):
        args = dict(dataset=toy, batch_size=8, device="cpu", name=name, seed=0, progress=False, **TINY.get(model, {}))
        args.update(kwargs)
        return train(model, **args)

    return run


@pytest.fixture
def graph_plan(monkeypatch):
    """``graph_plan(run) -> (policy, protocol, infos)``: ``wm:run`` with ``subgoals="graph"`` (horizon 2,
    lookahead 1) evaluated on 2 Toy episodes of 3 steps (history 2); ``infos`` are the infos each
    solve got (copies taken before the model adds its encodings)."""
    import stable_worldmodel as swm
    from stable_worldmodel.planning.learned import PlanSettings, world_model_policy

    def run(name: str):
        settings = PlanSettings(horizon=2, samples=8, iterations=1, subgoals="graph", lookahead=1)
        policy, protocol = world_model_policy(name, settings, device="cpu")
        seen = []
        solve = policy.solver.solve
        monkeypatch.setattr(
            policy.solver, "solve", lambda info, init_action=None: seen.append(dict(info)) or solve(info, init_action)
        )
        with swm.World("swm/Toy-v0", 2, (16, 16), max_episode_steps=3, verbose=0, history_size=2) as world:
            world.set_policy(policy)
            assert world.evaluate(episodes=2, seed=0)["episode_count"] == 2
        return policy, protocol, seen

    return run


@pytest.fixture
def tiny():
    """The tiny sizes of each model (``TINY``)."""
    return TINY

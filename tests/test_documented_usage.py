"""The documented usage of release 0.0.3 and of upstream 0.1.1, run on tiny sizes.

Each test makes the public calls of one documented example (same module paths, names, keywords and
call order) with small sizes (16x16 images, a few episodes of a few steps) and checks the result the
example shows. Only examples that run on the original release count: each one was first run on the
installed original (0.0.3 or 0.1.1); the calls that do not run there are listed below and not tested.

Sources (read from the stored public repositories):

- 0.0.3: ``README.md`` of the 0.0.3 wheel ("Quick Example"), ``docs/quick_start.md`` (the HDF5 /
  ``record_dataset`` version), ``docs/api/world.md`` (tabs Basic Usage, Recording Video, Recording
  Dataset, Evaluation, Per-Environment Options), ``docs/api/policy.md`` (tabs Random Policy, World
  Model Policy, Feed-Forward Policy), and the ``:::`` reference targets of ``docs/api/{world,dataset,
  policy,solver,spaces,wrapper}.md`` (those four pages hold no code blocks).
  ``docs/basic_usage.md`` is empty.
- 0.1.1: ``README.md`` of the 0.1.1 wheel (Quick Start, Data Formats) and ``docs/quick_start.md``
  (the Lance version, whose default format matches 0.1.1's ``World.collect``).

The 0.1.1 tests run from ``$STABLEWM_HOME/datasets``: 0.1.1's ``load_dataset`` resolves a relative
path there, while ``World.collect`` writes relative to the working directory, so the documented
``collect('data/x.lance')`` then ``load_dataset('data/x.lance')`` round trip only works on the
original from that folder.

Not tested, because the original does not run them here:

- 0.0.3 README Quick Example: ``swm.World('swm/PushT-v1', num_envs=8)`` raises TypeError (``image_shape``
  is required), ``record_dataset(dataset_name=..., episodes=...)`` without ``seed`` raises TypeError
  (``None + int``), and ``PlanConfig(horizon=10)`` raises TypeError (``receding_horizon`` is required).
  The same calls with ``image_shape`` and ``seed`` are covered by the quick-start tests.
- 0.0.3 quick start: ``swm.World(env='swm/PushT-v1', num_envs=4)`` (TypeError: ``env_name`` and
  ``image_shape`` missing; the tests pass the id positionally, with ``image_shape``); ``world.step()``
  before any ``set_policy`` (RuntimeError; the tests attach the RandomPolicy of the next block
  first); the plain ``class MyPolicy`` with only ``get_action`` (``set_policy`` calls its missing
  ``set_env``: AttributeError); ``world.record_video(video_path='./videos/')`` into a folder that does
  not exist (imageio FileNotFoundError; the tests create it first); ``world.evaluate_from_dataset(...)``
  (AttributeError: 0.0.3's ``HDF5Dataset`` has no ``get_chunk_data``); ``CEMSolver(..., device='cuda')``
  needs a GPU (run with ``device='cpu'``).
- 0.0.3 ``docs/api/world.md``: the Recording Dataset tab (``record_dataset`` without ``seed``:
  TypeError), the Evaluation tab (``evaluate_from_dataset``: AttributeError as above) and the
  Per-Environment Options tab (``reset(options=[...])``: AttributeError ``'list' object has no
  attribute 'get'``).
- 0.0.3 ``docs/api/policy.md`` World Model Policy tab: ``stable_worldmodel.solver.random`` does not
  exist in 0.0.3 (ModuleNotFoundError); the later ``stable_worldmodel.planning`` version does not
  exist either.
- 0.1.1 README Quick Start: ``swm.World("swm/PushT-v1", num_envs=8)`` raises ValueError
  (``image_shape`` is required) and ``PlanConfig(horizon=10)`` raises TypeError (``receding_horizon``).
- 0.1.1 README Data Formats: ``swm.data.convert("data/pusht.lance", "data/pusht_video", ...)`` into
  the folder the previous line recorded fails (VideoWriter append: schema mismatch on ``step_idx``).
  Conversion into a fresh folder (the quick start's call) is tested.
- 0.1.1 quick start: ``load_dataset`` of a video folder needs ``decord`` (not installed for the
  original); ``load_dataset('lerobot://lerobot/pusht', ...)`` needs Python 3.12 and the network;
  ``class MyPolicy`` (AttributeError ``set_env``, as in 0.0.3); ``record_video_from_dataset`` into a
  missing folder (FileNotFoundError; created first); ``device='cuda'`` (run on CPU).
- Everything under ``scripts/`` (training, ``swm.pretraining``), downloads (``wget`` checkpoints) and
  the shell blocks (``swm ...`` commands, installation).
"""

from __future__ import annotations

import importlib
from pathlib import Path

import numpy as np
import pytest
import torch

IMG = (16, 16)


@pytest.fixture
def in_tmp_cwd(tmp_path, monkeypatch):
    """0.0.3 examples write ``./videos`` and ``./data`` into the working directory."""
    monkeypatch.chdir(tmp_path)
    return tmp_path


@pytest.fixture
def in_datasets_dir(_stablewm_home, monkeypatch):
    """0.1.1 examples run from ``$STABLEWM_HOME/datasets`` (see the module docstring)."""
    folder = Path(_stablewm_home) / "datasets"
    folder.mkdir(parents=True, exist_ok=True)
    monkeypatch.chdir(folder)
    return folder


class QuadraticCost:
    """The quick start's ``MyWorldModel``: any object with ``get_cost(info, action_candidates)``."""

    def get_cost(self, info, action_candidates):
        return (action_candidates**2).sum(dim=(-1, -2))


def _names(folder) -> list[str]:
    return sorted(p.name for p in Path(folder).iterdir())


def _world(num_envs: int, max_episode_steps: int = 12):
    import stable_worldmodel as swm

    return swm.World("swm/PushT-v1", num_envs=num_envs, image_shape=IMG, max_episode_steps=max_episode_steps)


# --------------------------------------------------------------------------------------------
# Blocks that read the same in the 0.0.3 and the 0.1.1 quick start
# --------------------------------------------------------------------------------------------


def test_quick_start_gym_make():
    """Both quick starts: "Just want the environments?" note."""
    import gymnasium as gym

    import stable_worldmodel  # noqa: F401  (registers all environments)

    env = gym.make("swm/PushT-v1", render_mode="rgb_array")
    obs, info = env.reset(seed=0)
    assert isinstance(obs, dict) and isinstance(info, dict)
    assert env.render().shape == (224, 224, 3)
    env.close()


def _variation_blocks(world) -> None:
    """Controlling Variations at Reset and Setting Specific Values (the same in both quick starts)."""
    world.reset(seed=0, options={"variation": ["agent.color", "block.color"]})
    world.reset(seed=0, options={"variation": ["all"]})
    world.reset(seed=0, options={"variation": ["agent"]})

    world.reset(
        seed=0,
        options={
            "variation": ["agent.color", "background.color"],
            "variation_values": {
                "agent.color": np.array([255, 0, 0], dtype=np.uint8),
                "background.color": np.array([0, 0, 0], dtype=np.uint8),
            },
        },
    )
    for env in world.envs.envs:
        space = env.unwrapped.variation_space
        np.testing.assert_array_equal(space["agent"]["color"].value, [255, 0, 0])
        np.testing.assert_array_equal(space["background"]["color"].value, [0, 0, 0])
    assert world.infos["pixels"].shape == (4, 1, *IMG, 3)


def test_quick_start_world_model_policy():
    """Both quick starts: Policy for World Interactions (WorldModelPolicy + CEMSolver + PlanConfig)."""
    import stable_worldmodel as swm
    from stable_worldmodel.policy import PlanConfig, WorldModelPolicy
    from stable_worldmodel.solver import CEMSolver

    world = swm.World("swm/PushT-v1", num_envs=4, image_shape=IMG)
    config = PlanConfig(horizon=10, receding_horizon=5, action_block=1, warm_start=True)
    world_model = QuadraticCost()
    policy = WorldModelPolicy(solver=CEMSolver(model=world_model, num_samples=300), config=config)
    world.set_policy(policy)

    world.reset(seed=0)
    action = policy.get_action(world.infos)
    assert action.shape == (4, 2)
    assert np.all(np.abs(action) <= 1.0)


def test_quick_start_model_based_planning(in_tmp_cwd):
    """Both quick starts: Model-Based Planning (on CPU; the example says device='cuda')."""
    import stable_worldmodel as swm
    from stable_worldmodel.policy import PlanConfig, WorldModelPolicy
    from stable_worldmodel.solver import CEMSolver

    cost_model = QuadraticCost()
    solver = CEMSolver(model=cost_model, num_samples=300, n_steps=30, device="cpu")
    config = PlanConfig(horizon=10, receding_horizon=5, action_block=1, warm_start=True)
    policy = WorldModelPolicy(solver=solver, config=config)

    world = swm.World("swm/PushT-v1", num_envs=1, image_shape=IMG, max_episode_steps=5)
    world.set_policy(policy)
    results = world.evaluate(episodes=2, seed=0)
    assert {"success_rate", "episode_successes", "seeds"} <= set(results)
    assert len(results["episode_successes"]) == 2


# --------------------------------------------------------------------------------------------
# 0.0.3 docs/quick_start.md
# --------------------------------------------------------------------------------------------


def test_003_quick_start_world_infos():
    """World: reset, step, everything in ``world.infos`` (policy attached first, see docstring)."""
    import stable_worldmodel as swm

    world = swm.World("swm/PushT-v1", num_envs=4, image_shape=IMG)
    world.set_policy(swm.policy.RandomPolicy(seed=42))
    world.reset(seed=0)
    world.step()
    # 0.0.3 keeps a history axis: (num_envs, history, H, W, C)
    assert world.infos["pixels"].shape == (4, 1, *IMG, 3)
    assert np.asarray(world.infos["reward"]).shape[0] == 4
    assert np.asarray(world.infos["terminated"]).shape[0] == 4


def test_003_quick_start_variation_space_to_str():
    """Factors of Variation: ``print(world.single_variation_space.to_str())`` runs."""
    import stable_worldmodel as swm

    world = swm.World("swm/PushT-v1", num_envs=4, image_shape=IMG)
    text = world.single_variation_space.to_str()
    assert isinstance(text, str)
    for name in ("agent", "block", "background", "color"):
        assert name in text


def test_003_quick_start_variation_space_to_str_format():
    """The quick start shows the tree of the original: ``agent:`` / ``    color: Box(0, 255, (3,), uint8)``."""
    import stable_worldmodel as swm

    world = swm.World("swm/PushT-v1", num_envs=4, image_shape=IMG)
    lines = world.single_variation_space.to_str().splitlines()
    assert lines[0] == "agent:"
    assert "    color: Box(0, 255, (3,), uint8)" in lines
    assert "background:" in lines and "block:" in lines


def test_003_quick_start_variation_reset_options():
    """Factors of Variation, after the World block's ``reset(seed=0)`` and ``step()`` (0.0.3 needs them first)."""
    import stable_worldmodel as swm

    world = swm.World("swm/PushT-v1", num_envs=4, image_shape=IMG)
    world.set_policy(swm.policy.RandomPolicy(seed=42))
    world.reset(seed=0)
    world.step()
    _variation_blocks(world)


def test_003_quick_start_random_policy():
    """Policy for World Interactions: the built-in random policy."""
    import stable_worldmodel as swm

    world = swm.World("swm/PushT-v1", num_envs=4, image_shape=IMG)
    policy = swm.policy.RandomPolicy(seed=42)
    world.set_policy(policy)
    world.reset(seed=0)
    world.step()
    assert world.policy is policy


def test_003_quick_start_dataset_and_videos(in_tmp_cwd, _stablewm_home):
    """Dataset: Recording a Dataset, Loading a Dataset, Recording Videos, Recording Videos from Dataset."""
    import stable_worldmodel as swm
    from stable_worldmodel.data import HDF5Dataset
    from stable_worldmodel.utils import record_video_from_dataset

    world = _world(num_envs=2)
    policy = swm.policy.RandomPolicy(seed=42)  # can be your JEPA or RL Policy
    world.set_policy(policy)
    world.record_dataset(dataset_name="pusht_random", episodes=4, seed=0)
    assert (Path(_stablewm_home) / "pusht_random.h5").is_file()

    dataset = HDF5Dataset(name="pusht_random", frameskip=1, num_steps=4, keys_to_load=["pixels", "action", "state"])
    sample = dataset[0]
    assert sample["pixels"].shape == (4, 3, *IMG)
    assert sample["action"].shape == (4, 2)
    assert sample["state"].shape[0] == 4
    assert all(isinstance(v, torch.Tensor) for v in sample.values())
    batch = next(iter(torch.utils.data.DataLoader(dataset, batch_size=2)))  # "compatible with DataLoader"
    assert batch["pixels"].shape == (2, 4, 3, *IMG)

    Path("videos").mkdir()  # 0.0.3 does not create the folder
    world.record_video(video_path="./videos/", max_steps=5, fps=30, seed=0)
    assert _names("videos") == ["env_0.mp4", "env_1.mp4"]

    record_video_from_dataset(
        video_path="./videos/", dataset=dataset, episode_idx=[0, 1, 2], max_steps=5, fps=30, viewname="pixels"
    )
    assert {"episode_0.mp4", "episode_1.mp4", "episode_2.mp4"} <= set(_names("videos"))
    assert all((Path("videos") / f"episode_{i}.mp4").stat().st_size > 0 for i in range(3))

    # "Can also be a list: ['pixels', 'goal']" (the dataset then has to load 'goal' too)
    Path("videos_goal").mkdir()
    full = HDF5Dataset(name="pusht_random", num_steps=4)
    record_video_from_dataset(
        video_path="./videos_goal/",
        dataset=full,
        episode_idx=[0, 1, 2],
        max_steps=5,
        fps=30,
        viewname=["pixels", "goal"],
    )
    assert _names("videos_goal") == ["episode_0.mp4", "episode_1.mp4", "episode_2.mp4"]


def test_003_quick_start_evaluate(in_tmp_cwd):
    """Evaluation: Online Evaluation with ``evaluate()``."""
    import stable_worldmodel as swm

    world = swm.World("swm/PushT-v1", num_envs=4, image_shape=IMG, max_episode_steps=5)
    my_policy = swm.policy.RandomPolicy(seed=42)
    world.set_policy(my_policy)
    results = world.evaluate(episodes=6, seed=0)

    assert f"Success Rate: {results['success_rate']:.1f}%".startswith("Success Rate: ")
    assert {"success_rate", "episode_successes", "episode_count", "seeds"} <= set(results)
    assert results["episode_count"] == 6
    assert len(results["episode_successes"]) == 6
    assert set(np.unique(results["episode_successes"])) <= {0, 1}


# --------------------------------------------------------------------------------------------
# 0.0.3 docs/api/world.md and docs/api/policy.md
# --------------------------------------------------------------------------------------------


def test_003_api_world_basic_usage():
    """world.md, tab Basic Usage (10 steps instead of 100)."""
    from stable_worldmodel import World
    from stable_worldmodel.policy import RandomPolicy

    world = World(env_name="swm/PushT-v1", num_envs=4, image_shape=IMG, history_size=1)
    world.set_policy(RandomPolicy())
    world.reset()
    for _ in range(10):
        world.step()
    assert world.infos["pixels"].shape == (4, 1, *IMG, 3)


def test_003_api_world_recording_video(in_tmp_cwd):
    """world.md, tab Recording Video (5 steps instead of 500; the folder is created first, as 0.0.3 needs)."""
    from stable_worldmodel import World
    from stable_worldmodel.policy import RandomPolicy

    world = World(env_name="swm/PushT-v1", num_envs=1, image_shape=IMG)
    world.set_policy(RandomPolicy())
    Path("videos").mkdir()
    world.record_video(video_path="./videos", max_steps=5, viewname="pixels")
    assert _names("videos") == ["env_0.mp4"]
    assert (Path("videos") / "env_0.mp4").stat().st_size > 0


def test_003_api_policy_random_policy():
    """policy.md, tab Random Policy."""
    from stable_worldmodel.policy import RandomPolicy

    policy = RandomPolicy(seed=42)
    assert policy.seed == 42
    world = _world(num_envs=2)
    world.set_policy(policy)
    world.reset(seed=0)
    world.step()


class TinyActor(torch.nn.Module):
    """Stands in for a trained GCBC checkpoint: a module with ``get_action``."""

    def __init__(self):
        super().__init__()
        self.head = torch.nn.Linear(1, 2)

    def get_action(self, info):
        return torch.zeros(info["pixels"].shape[0], 2)


class IdentityScaler:
    """``action_scaler`` of the example: anything with ``transform`` / ``inverse_transform``."""

    def transform(self, x):
        return x

    def inverse_transform(self, x):
        return x


@pytest.mark.filterwarnings("ignore:.*pickled checkpoint:UserWarning")
def test_003_api_policy_feed_forward(_stablewm_home):
    """policy.md, tab Feed-Forward Policy (the checkpoint is a tiny module saved into the cache)."""
    from stable_worldmodel.policy import AutoActionableModel, FeedForwardPolicy

    Path(_stablewm_home).mkdir(parents=True, exist_ok=True)
    torch.save(TinyActor(), Path(_stablewm_home) / "tiny_gcbc_object.ckpt")

    def image_transform(x):
        return x.float() / 255.0

    action_scaler = IdentityScaler()
    model = AutoActionableModel("tiny_gcbc")
    policy = FeedForwardPolicy(
        model=model,
        process={"action": action_scaler},  # Optional preprocessors
        transform={"pixels": image_transform},  # Optional transforms
    )
    assert hasattr(model, "get_action") and not model.training

    world = _world(num_envs=2)
    world.set_policy(policy)
    world.reset(seed=0)
    world.step()
    assert world.infos["pixels"].shape == (2, 1, *IMG, 3)


# mkdocstrings targets (``::: path``) of the 0.0.3 API pages; every one resolves on 0.0.3
_METHODS = ("column_names", "load_chunk", "load_episode", "get_col_data", "get_row_data")
API_TARGETS = {
    "world.md": ["stable_worldmodel.World"]
    + [
        f"stable_worldmodel.world.World.{m}"
        for m in (
            "record_dataset record_video evaluate_from_dataset evaluate reset step close set_policy num_envs "
            "observation_space action_space variation_space single_variation_space single_action_space "
            "single_observation_space"
        ).split()
    ],
    "dataset.md": [
        *(f"stable_worldmodel.data.dataset.Dataset{m}" for m in ("", *(f".{n}" for n in _METHODS))),
        *(f"stable_worldmodel.data.HDF5Dataset{m}" for m in ("", *(f".{n}" for n in _METHODS))),
        *(f"stable_worldmodel.data.FolderDataset{m}" for m in ("", *(f".{n}" for n in _METHODS))),
        "stable_worldmodel.data.ImageDataset",
        "stable_worldmodel.data.VideoDataset",
        *(
            f"stable_worldmodel.data.MergeDataset{m}"
            for m in ("", ".column_names", ".lengths", ".load_chunk", ".get_col_data", ".get_row_data")
        ),
        *(
            f"stable_worldmodel.data.ConcatDataset{m}"
            for m in ("", ".column_names", ".load_chunk", ".get_col_data", ".get_row_data")
        ),
        "stable_worldmodel.data.utils.get_cache_dir",
    ],
    "policy.md": [
        f"stable_worldmodel.policy.{n}"
        for n in (
            "PlanConfig BasePolicy BasePolicy.get_action BasePolicy.set_env BasePolicy._prepare_info RandomPolicy "
            "RandomPolicy.get_action ExpertPolicy ExpertPolicy.get_action "
            "FeedForwardPolicy FeedForwardPolicy.get_action "
            "WorldModelPolicy WorldModelPolicy.get_action AutoActionableModel AutoCostModel"
        ).split()
    ],
    "solver.md": [
        f"stable_worldmodel.solver.{c}{m}"
        for c in ("Solver", "CEMSolver", "MPPISolver", "GradientSolver", "PGDSolver")
        for m in ("", ".configure", ".solve")
    ],
    "spaces.md": [
        *(
            f"stable_worldmodel.spaces.{c}{m}"
            for c in ("Discrete", "MultiDiscrete", "Box")
            for m in ("", ".sample", ".contains", ".reset")
        ),
        "stable_worldmodel.spaces.RGBBox",
        *(f"stable_worldmodel.spaces.Dict{m}" for m in ("", ".sample", ".contains", ".reset", ".update", ".names")),
    ],
    "wrapper.md": [
        f"stable_worldmodel.wrapper.{c}"
        for c in (
            "MegaWrapper EnsureInfoKeysWrapper EnsureImageShape EnsureGoalInfoWrapper EverythingToInfoWrapper "
            "AddPixelsWrapper ResizeGoalWrapper StackedWrapper VariationWrapper"
        ).split()
    ],
}


def _resolve(path: str):
    parts = path.split(".")
    for i in range(len(parts), 0, -1):
        try:
            obj = importlib.import_module(".".join(parts[:i]))
        except ImportError:
            continue
        for part in parts[i:]:
            obj = getattr(obj, part)
        return obj
    raise ImportError(path)


@pytest.mark.parametrize("page", sorted(API_TARGETS))
def test_003_api_reference_targets_resolve(page):
    """docs/api/<page>: every ``:::`` target the 0.0.3 page renders exists."""
    missing = []
    for path in API_TARGETS[page]:
        try:
            _resolve(path)
        except (ImportError, AttributeError):
            missing.append(path)
    assert missing == []


# --------------------------------------------------------------------------------------------
# 0.1.1 README.md
# --------------------------------------------------------------------------------------------


def test_011_readme_quick_start_collect_and_load(in_datasets_dir):
    """README Quick Start, steps 1 and 2 (step 3's ``PlanConfig(horizon=10)`` fails on 0.1.1)."""
    import stable_worldmodel as swm

    # 1. Collect a dataset
    world = swm.World("swm/PushT-v1", num_envs=2, image_shape=IMG, max_episode_steps=20)
    world.set_policy(swm.policy.RandomPolicy(seed=0))  # your_expert_policy
    world.collect("data/pusht_demo.lance", episodes=2, seed=0)

    # 2. Load it and train your world model (format is autodetected)
    dataset = swm.data.load_dataset("data/pusht_demo.lance", num_steps=16)
    sample = dataset[0]
    assert sample["pixels"].shape == (16, 3, *IMG)
    assert sample["action"].shape == (16, 2)
    assert len(dataset.lengths) == 2


def test_011_readme_data_formats_collect_and_load(in_datasets_dir):
    """README Data Formats: the two collects and the load (its ``convert`` line fails on 0.1.1)."""
    import stable_worldmodel as swm

    world = swm.World("swm/PushT-v1", num_envs=2, image_shape=IMG, max_episode_steps=20)
    world.set_policy(swm.policy.RandomPolicy(seed=0))
    world.collect("data/pusht_demo.lance", episodes=2, seed=0)  # the Quick Start before it

    world.collect("data/pusht.lance", episodes=2)  # default: lance
    world.collect("data/pusht_video", episodes=2, format="video")  # mp4 episodes
    ds = swm.data.load_dataset("data/pusht.lance", num_steps=16)  # autodetect

    assert len(ds.lengths) == 2
    assert ds[0]["pixels"].shape == (16, 3, *IMG)
    video_dir = Path("data/pusht_video")
    assert video_dir.is_dir() and any(p.suffix == ".mp4" for p in video_dir.rglob("*"))


# --------------------------------------------------------------------------------------------
# 0.1.1 docs/quick_start.md
# --------------------------------------------------------------------------------------------


def test_011_quick_start_world_infos():
    """World: ``set_policy``, ``reset``; values carry a time axis of 1 after the env axis."""
    import stable_worldmodel as swm

    world = swm.World("swm/PushT-v1", num_envs=4, image_shape=IMG)
    policy = swm.policy.RandomPolicy(seed=42)
    world.set_policy(policy)
    world.reset(seed=0)
    assert world.infos["pixels"].shape == (4, 1, *IMG, 3)  # (num_envs, 1, H, W, C)
    assert world.infos["state"].shape == (4, 1, 7)  # (num_envs, 1, state_dim)


def test_011_quick_start_variation_space_to_str_format():
    """Factors of Variation: ``world.envs.single_variation_space.to_str()`` prints the tree shown."""
    import stable_worldmodel as swm

    world = swm.World("swm/PushT-v1", num_envs=4, image_shape=IMG)
    lines = world.envs.single_variation_space.to_str().splitlines()
    assert lines[0] == "agent:"
    assert "    color: Box(0, 255, (3,), uint8)" in lines


def test_011_quick_start_variation_reset_options():
    """Factors of Variation, after the World block's ``set_policy`` and ``reset(seed=0)``."""
    import stable_worldmodel as swm

    world = swm.World("swm/PushT-v1", num_envs=4, image_shape=IMG)
    world.set_policy(swm.policy.RandomPolicy(seed=42))
    world.reset(seed=0)
    _variation_blocks(world)


def _collect_quick_start(world) -> None:
    """Recording a Dataset, as the 0.1.1 quick start writes it (4 + 2 episodes, then 4 as video)."""
    world.collect("data/pusht_random.lance", episodes=4, seed=0)
    world.collect("data/pusht_random.lance", episodes=2, seed=1)  # +2 episodes (append is the default)
    world.collect("data/pusht_random_video", episodes=4, seed=0, format="video")


def test_011_quick_start_collect_and_load(in_datasets_dir):
    """Dataset: Recording a Dataset (append, video format) and Loading a Dataset."""
    import stable_worldmodel as swm

    world = swm.World("swm/PushT-v1", num_envs=2, image_shape=IMG, max_episode_steps=12)
    policy = swm.policy.RandomPolicy(seed=42)  # can be your JEPA or RL policy
    world.set_policy(policy)
    _collect_quick_start(world)
    assert Path("data/pusht_random_video").is_dir()

    dataset = swm.data.load_dataset(
        "data/pusht_random.lance",  # autodetected as lance
        frameskip=1,
        num_steps=4,
        keys_to_load=["pixels", "action", "state"],
    )
    assert len(dataset.lengths) == 6
    sample = dataset[0]
    assert set(sample) == {"pixels", "action", "state"}
    assert sample["pixels"].shape == (4, 3, *IMG)  # (4, 3, H, W)
    assert sample["action"].shape == (4, 2)  # (4, action_dim)
    batch = next(iter(torch.utils.data.DataLoader(dataset, batch_size=2)))
    assert batch["pixels"].shape == (2, 4, 3, *IMG)


def test_011_quick_start_convert(in_datasets_dir):
    """Dataset: Converting Between Formats (into a fresh folder)."""
    import stable_worldmodel as swm

    world = swm.World("swm/PushT-v1", num_envs=2, image_shape=IMG, max_episode_steps=12)
    world.set_policy(swm.policy.RandomPolicy(seed=42))
    world.collect("data/pusht_random.lance", episodes=2, seed=0)

    swm.data.convert(
        "data/pusht_random.lance",  # source
        "data/pusht_random_video2",  # destination
        dest_format="video",
        fps=30,
    )
    out = Path("data/pusht_random_video2")
    assert out.is_dir() and any(p.suffix == ".mp4" for p in out.rglob("*"))


def test_011_quick_start_videos(in_datasets_dir):
    """Dataset: Recording Videos (``evaluate(video=...)``) and Recording Videos from Dataset."""
    import stable_worldmodel as swm
    from stable_worldmodel.utils import record_video_from_dataset

    world = swm.World("swm/PushT-v1", num_envs=2, image_shape=IMG, max_episode_steps=5)
    world.set_policy(swm.policy.RandomPolicy(seed=42))
    world.collect("data/pusht_random.lance", episodes=3, seed=0)

    world.evaluate(episodes=2, seed=0, video="./videos/")
    assert _names("videos") == ["episode_0.mp4", "episode_1.mp4"]

    dataset = swm.data.load_dataset("data/pusht_random.lance", num_steps=4)
    Path("videos2").mkdir()  # 0.1.1 does not create the folder
    record_video_from_dataset(
        video_path="./videos2/",
        dataset=dataset,
        episode_idx=[0, 1, 2],  # Episodes to export
        max_steps=500,
        fps=30,
        viewname="pixels",  # Can also be a list: ['pixels', 'goal']
    )
    assert _names("videos2") == ["episode_0.mp4", "episode_1.mp4", "episode_2.mp4"]


def test_011_quick_start_evaluate_from_dataset(in_datasets_dir):
    """Evaluation: Dataset-driven Evaluation (start 0..3, goal 5 steps ahead, budget 10)."""
    import stable_worldmodel as swm

    world = swm.World("swm/PushT-v1", num_envs=4, image_shape=IMG, max_episode_steps=12)
    world.set_policy(swm.policy.RandomPolicy(seed=42))
    world.collect("data/pusht_random.lance", episodes=4, seed=0)
    dataset = swm.data.load_dataset(
        "data/pusht_random.lance", frameskip=1, num_steps=4, keys_to_load=["pixels", "action", "state"]
    )

    results = world.evaluate(
        dataset=dataset,
        episodes_idx=[0, 1, 2, 3],  # Which episodes to sample from
        start_steps=[0, 1, 2, 3],  # Starting timestep within each episode
        goal_offset=5,  # Goal = state at start_step + 5
        eval_budget=10,  # Max env steps per episode
    )
    assert {"success_rate", "episode_successes"} <= set(results)
    assert len(results["episode_successes"]) == 4
    assert 0.0 <= results["success_rate"] <= 100.0


def test_011_quick_start_evaluate_episodic():
    """Evaluation: Episodic Evaluation; the dict holds success_rate, episode_successes and seeds."""
    import stable_worldmodel as swm

    world = swm.World("swm/PushT-v1", num_envs=4, image_shape=IMG, max_episode_steps=5)
    my_policy = swm.policy.RandomPolicy(seed=0)
    world.set_policy(my_policy)
    results = world.evaluate(episodes=6, seed=0)

    assert f"Success Rate: {results['success_rate']:.1f}%".startswith("Success Rate: ")
    assert {"success_rate", "episode_successes", "seeds"} <= set(results)
    assert np.asarray(results["episode_successes"]).shape == (6,)
    assert np.asarray(results["seeds"]).shape == (6,)

"""Release 0.0.3's SimpleNavigation (swm/SimpleNavigation-v0, extra ``minigrid``): 0.0.3's spaces,
infos, maze, moves and frames; seeds, reset options, dataset resets, the expert, typed errors, and
the 0.0.3 module paths (``envs.simple_nav``, ``envs.ogbench_manip``)."""

from __future__ import annotations

import hashlib
import subprocess
import sys

import gymnasium as gym
import numpy as np
import pytest

import stable_worldmodel as swm
from stable_worldmodel import keys
from stable_worldmodel._optional import is_available
from stable_worldmodel.envs import get_entry
from stable_worldmodel.envs.simple_nav.expert import SimpleNavigationExpert, expert_action
from stable_worldmodel.envs.simple_nav.maze import ellers_maze, maze_walls
from stable_worldmodel.errors import ConfigError, SpaceError

needs_minigrid = pytest.mark.skipif(not is_available("minigrid"), reason="extra 'minigrid' not installed")
ENV_ID = "swm/SimpleNavigation-v0"
FACTORS = [
    "agent.position",
    "agent.direction",
    "goal.position",
    "goal.agent.direction",
    "maze.p_horizontal",
    "maze.p_vertical",
]
LEFT, RIGHT, FORWARD = 0, 1, 2

# -- 0.0.3, observed (stable-worldmodel 0.0.3 from PyPI, minigrid 3.2.0) -------------------------------
# ellers_maze(9, 9, seed=1, p_horizontal=0.5, p_vertical=0.5)
MAZE_9_SEED_1 = [
    (2, 1), (4, 1), (2, 2), (4, 2), (6, 2), (7, 2), (2, 3), (6, 3), (2, 4),
    (4, 4), (6, 4), (4, 5), (2, 6), (4, 6), (5, 6), (6, 6), (2, 7), (6, 7),
]  # fmt: skip
# a fresh env's reset(seed=2) (its maze: seed 2, p = 0.5), then 12 actions of default_rng(2).integers(3)
EPISODE_SEED_2 = {
    "start": ([5, 7], 2),
    "goal": ([5, 1], 2),
    "states": [
        [5, 7, 2, 5, 1], [4, 7, 2, 5, 1], [4, 7, 1, 5, 1], [4, 7, 0, 5, 1], [4, 7, 3, 5, 1], [4, 7, 0, 5, 1],
        [5, 7, 0, 5, 1], [5, 7, 1, 5, 1], [5, 7, 0, 5, 1], [5, 7, 1, 5, 1], [5, 7, 2, 5, 1], [4, 7, 2, 5, 1],
        [3, 7, 2, 5, 1],
    ],
    "rewards": [-7.0, -7.0, -7.0, -7.0, -7.0, -6.0, -6.0, -6.0, -6.0, -6.0, -7.0, -8.0],
    # sha256[:16] of the 288 x 288 frames: first, goal image, last
    "frames": ("ca215b0105dc5845", "d1d9aa6b2fe78c90", "ffe1a79fdbe9da4a"),
}  # fmt: skip


def _sha(frame: np.ndarray) -> str:
    return hashlib.sha256(np.ascontiguousarray(frame).tobytes()).hexdigest()[:16]


def _corridor(size: int = 9) -> np.ndarray:
    """A maze whose only open cells are row y = 1 (x = 1 .. size - 2) and column x = 1."""
    walls = np.ones((size, size), np.uint8)
    walls[1, 1:-1] = 0
    walls[1:-1, 1] = 0
    return walls


def _fixed(agent, direction, goal, goal_direction=0) -> dict:
    return {
        "variation": [],
        "variation_values": {
            "agent.position": agent,
            "agent.direction": direction,
            "goal.position": goal,
            "goal.agent.direction": goal_direction,
        },
    }


@pytest.fixture
def env():
    pytest.importorskip("minigrid")
    e = gym.make(ENV_ID).unwrapped
    yield e
    e.close()


# -- the maze (no minigrid needed) ---------------------------------------------------------------------
def test_nav_maze_is_0_0_3_ellers_maze():
    assert ellers_maze(9, 9, seed=1, p_horizontal=0.5, p_vertical=0.5) == MAZE_9_SEED_1
    walls = maze_walls(9, 9, seed=1)
    assert walls[0].all() and walls[-1].all() and walls[:, 0].all() and walls[:, -1].all()
    assert not walls[1::2, 1::2].any()  # every room open


@pytest.mark.parametrize("p", [(0.0, 0.0), (0.5, 0.5), (1.0, 1.0), (0.2, 0.9)])
def test_nav_mazes_are_trees(p):
    for seed in range(5):
        walls = maze_walls(11, 9, seed, *p)
        open_cells = {(int(x), int(y)) for y, x in zip(*np.nonzero(~walls), strict=True)}
        edges = sum((x + 1, y) in open_cells for x, y in open_cells) + sum(
            (x, y + 1) in open_cells for x, y in open_cells
        )
        start = next(iter(open_cells))
        seen, todo = {start}, [start]
        while todo:
            x, y = todo.pop()
            for n in ((x + 1, y), (x - 1, y), (x, y + 1), (x, y - 1)):
                if n in open_cells and n not in seen:
                    seen.add(n)
                    todo.append(n)
        assert seen == open_cells and edges == len(open_cells) - 1  # connected, no cycle


def test_nav_maze_errors():
    with pytest.raises(ConfigError, match="odd"):
        maze_walls(8, 9)
    with pytest.raises(ConfigError, match="p_vertical"):
        maze_walls(9, 9, p_vertical=1.5)


# -- the env -------------------------------------------------------------------------------------------
@needs_minigrid
def test_nav_spaces_factors_and_infos_as_0_0_3(env):
    assert env.observation_space == gym.spaces.Dict(
        {
            "proprio": gym.spaces.MultiDiscrete([7, 7, 4], start=[1, 1, 0]),
            "state": gym.spaces.MultiDiscrete([7, 7, 4, 7, 7], start=[1, 1, 0, 1, 1]),
        }
    )
    assert env.action_space == gym.spaces.Discrete(3)
    assert sorted(env.variation_space.names()) == sorted(FACTORS)
    obs, info = env.reset(seed=0)
    assert obs["state"].dtype == np.int64 and np.array_equal(obs["proprio"], obs["state"][:3])
    shapes = {k: np.shape(v) for k, v in info.items()}
    assert shapes == {
        "pos_agent": (2,),
        "dir_agent": (),
        "pos_goal": (2,),
        "goal_state": (5,),
        "goal_proprio": (3,),
        "goal": (288, 288, 3),
        "maze": (9, 9),
    }
    gx, gy = info["pos_goal"]
    np.testing.assert_array_equal(info["goal_state"][[0, 1, 3, 4]], [gx, gy, gx, gy])
    assert env.render().shape == (288, 288, 3)
    assert get_entry(ENV_ID).tags == ("discrete", "minigrid") and get_entry(ENV_ID).tool_steps == 100


@needs_minigrid
def test_nav_episode_frames_and_rewards_match_0_0_3(env):
    ep = EPISODE_SEED_2
    options = _fixed(*ep["start"], *ep["goal"])
    options["variation_values"].update({"maze.p_horizontal": [0.5], "maze.p_vertical": [0.5]})
    obs, info = env.reset(seed=2, options=options)
    states, rewards = [obs["state"].tolist()], []
    first, goal = _sha(env.render()), _sha(info["goal"])
    rng = np.random.default_rng(2)
    for _ in range(12):
        obs, reward, terminated, truncated, info = env.step(int(rng.integers(3)))
        states.append(obs["state"].tolist())
        rewards.append(reward)
        assert not terminated and not truncated
    assert states == ep["states"] and rewards == ep["rewards"]
    assert (first, goal, _sha(env.render())) == ep["frames"]


@needs_minigrid
def test_nav_seeded_resets_are_reproducible(env):
    a = env.reset(seed=7)
    frame_a = env.render()
    env.reset(seed=8)
    b = env.reset(seed=7)
    np.testing.assert_array_equal(a[0]["state"], b[0]["state"])
    np.testing.assert_array_equal(a[1]["maze"], b[1]["maze"])
    np.testing.assert_array_equal(frame_a, env.render())
    mazes = {env.reset()[1]["maze"].tobytes() for _ in range(4)}  # unseeded resets go on drawing
    assert len(mazes) > 1


@needs_minigrid
def test_nav_moves_walls_and_success(env):
    obs, info = env.reset(seed=0, options={"maze": _corridor(), **_fixed([1, 3], 3, [3, 1])})
    assert info["maze"].tolist() == _corridor().tolist()
    assert env.observation_space.contains(obs) and obs["state"].tolist() == [1, 3, 3, 3, 1]
    plan = [(LEFT, [1, 3, 2]), (FORWARD, [1, 3, 2]), (RIGHT, [1, 3, 3]), (FORWARD, [1, 2, 3]), (FORWARD, [1, 1, 3])]
    for action, expect in plan:  # facing left into the wall: no move; up the column
        obs, reward, terminated, _, _ = env.step(action)
        assert obs["proprio"].tolist() == expect
    assert (reward, terminated) == (-2.0, False)
    env.step(RIGHT)
    env.step(np.int64(FORWARD))
    obs, reward, terminated, truncated, info = env.step(np.array([FORWARD]))
    assert obs["state"].tolist() == [3, 1, 0, 3, 1] and (reward, terminated, truncated) == (-0.0, True, False)
    assert env.eval_state(info["goal_state"], obs["state"]) == (True, 0.0)
    assert env.eval_state(info["goal_state"], [1, 3, 0, 3, 1]) == (False, 4.0)


@needs_minigrid
def test_nav_factors_resample_only_what_is_named(env):
    base = env.reset(seed=3, options={"variation": []})[1]
    assert base["pos_agent"].tolist() == [1, 1] and base["pos_goal"].tolist() == [5, 5]
    _, info = env.reset(seed=3, options={"variation": ["goal.position"]})
    assert info["pos_agent"].tolist() == [1, 1] and info["maze"].tolist() == base["maze"].tolist()
    for seed in range(10):  # all six drawn: start and goal on open cells, apart
        _, info = env.reset(seed=seed)
        (ax, ay), (gx, gy) = info["pos_agent"], info["pos_goal"]
        assert not info["maze"][ay, ax] and not info["maze"][gy, gx] and (ax, ay) != (gx, gy)


@needs_minigrid
def test_nav_render_size_and_goal_image(env):
    env.set_render_size((16, 16))
    _, info = env.reset(seed=1)
    frame = env.render()
    assert frame.shape == (16, 16, 3) and frame.dtype == np.uint8 and info["goal"].shape == (16, 16, 3)
    env.set_render_size((16, 24))
    assert env.render().shape == (16, 24, 3)


@needs_minigrid
def test_nav_reset_from_dataset_rows(env):
    _, info = env.reset(seed=4)
    obs, *_ = env.step(LEFT)
    start_row = {"state": obs["state"], "maze": info["maze"]}
    goal_row = {"state": np.array([*info["pos_goal"], 3, *info["pos_goal"]])}
    options = env.reset_options_from_dataset(start_row, goal_row)
    obs2, info2 = env.reset(seed=99, options=options)  # another seed: the row's maze and state all the same
    np.testing.assert_array_equal(obs2["state"], obs["state"])
    np.testing.assert_array_equal(info2["maze"], info["maze"])
    assert info2["goal_state"].tolist() == [*info["pos_goal"], 3, *info["pos_goal"]]
    with pytest.raises(ConfigError, match="maze"):
        env.reset_options_from_dataset({"state": obs["state"]}, goal_row)


@needs_minigrid
def test_nav_expert_reaches_the_goal():
    world = swm.World(ENV_ID, num_envs=2, image_shape=(16, 16), verbose=0, vectorization_mode="sync")
    world.set_policy(swm.envs.expert_policy(ENV_ID))
    world.reset(seed=0)
    done = np.zeros(2, bool)
    for _ in range(60):
        world.step()
        done |= np.asarray(world.terminateds, bool)
        if done.all():
            break
    world.close()
    assert done.all()


def test_nav_expert_turns_towards_the_path():
    walls = _corridor().astype(bool)
    assert expert_action(walls, (1, 3), 3, (3, 1)) == FORWARD  # facing up the column
    assert expert_action(walls, (1, 3), 0, (3, 1)) == LEFT  # facing right: turn left (up)
    assert expert_action(walls, (1, 3), 2, (3, 1)) == RIGHT
    assert expert_action(walls, (1, 3), 1, (3, 1)) == LEFT  # facing away: a left, then another
    assert expert_action(walls, (3, 1), 0, (3, 1)) == LEFT  # on the goal: stays on it
    with pytest.raises(ConfigError, match="maze"):
        SimpleNavigationExpert().get_action({"pos_agent": np.zeros((1, 1, 2))})


@needs_minigrid
def test_nav_typed_errors(env):
    from stable_worldmodel.envs.simple_nav.env import SimpleNavigationEnv

    with pytest.raises(ConfigError, match="odd int"):
        SimpleNavigationEnv(size=8)
    with pytest.raises(ConfigError, match="render_mode"):
        SimpleNavigationEnv(render_mode="human")
    with pytest.raises(ConfigError, match="tile_size"):
        SimpleNavigationEnv(tile_sise=8)
    env.reset(seed=0)
    with pytest.raises(SpaceError, match="0..2"):
        env.step(3)
    with pytest.raises(ConfigError, match="border"):
        env.reset(options={"maze": np.zeros((9, 9))})
    with pytest.raises(ConfigError, match="open"):
        env.reset(options={"maze": _corridor(9), keys.STATE: [4, 4, 0]})
    with pytest.raises(ConfigError, match="direction"):
        env.reset(options={keys.STATE: [1, 1, 5]})


# -- module paths and the missing extra --------------------------------------------------------------
def test_nav_and_ogbench_manip_module_paths_import_light():
    code = (
        "import sys, stable_worldmodel.envs.simple_nav as nav, stable_worldmodel.envs.ogbench_manip as om; "
        "print(any(m in sys.modules for m in ('minigrid', 'pygame', 'mujoco', 'ogbench')))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert out.stdout.split() == ["False"], out.stderr
    from stable_worldmodel.envs.simple_nav import ExpertPolicy, SimpleNavigationExpert

    assert issubclass(ExpertPolicy, SimpleNavigationExpert) and ExpertPolicy().env_id == ENV_ID


def test_nav_without_minigrid_raises_a_typed_error_naming_the_extra():
    code = (
        "import sys; sys.modules['minigrid'] = None\n"
        "import gymnasium as gym, stable_worldmodel\n"
        "from stable_worldmodel.errors import DependencyNotInstalled\n"
        "try:\n"
        "    gym.make('swm/SimpleNavigation-v0')\n"
        "except DependencyNotInstalled as e:\n"
        "    print('typed:', e)\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert "typed:" in out.stdout and "minigrid" in out.stdout and "stable-worldmodel[minigrid]" in out.stdout, (
        out.stderr
    )

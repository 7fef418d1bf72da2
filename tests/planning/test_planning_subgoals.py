"""SubgoalGraph: waypoints on a latent graph of recorded episodes (search on the replay buffer).

The unit tests use 2-D points as "embeddings": two rooms split by a wall at x in (1, 1.2) with
a door at the top (y > 0.9); the recorded episodes walk inside a room or through the door.
"""

from __future__ import annotations

import numpy as np
import pytest
import torch

from stable_worldmodel.errors import ConfigError, UnknownNameError
from stable_worldmodel.planning.learned import PlanSettings
from stable_worldmodel.planning.subgoals import StallMonitor, SubgoalGraph

STEP = 0.05


def _walk(points: list[tuple[float, float]]) -> np.ndarray:
    """Points every STEP along the polyline through ``points``."""
    out = []
    for (x0, y0), (x1, y1) in zip(points[:-1], points[1:], strict=False):
        n = max(int(np.hypot(x1 - x0, y1 - y0) / STEP), 1)
        t = np.arange(n)[:, None] / n
        out.append(np.array([x0, y0]) * (1 - t) + np.array([x1, y1]) * t)
    out.append(np.array([points[-1]]))
    return np.concatenate(out)


@pytest.fixture(scope="module")
def rooms():
    routes = [
        [(0.1, 0.1), (0.9, 0.1)],  # along the bottom of the left room
        [(0.9, 0.1), (0.9, 0.95)],  # up the left side of the wall
        [(0.9, 0.95), (1.3, 0.95)],  # through the door
        [(1.3, 0.95), (1.3, 0.1)],  # down the right side
        [(1.3, 0.1), (2.0, 0.1)],
    ]
    walks = [_walk(r) for r in routes]
    emb = np.concatenate(walks).astype(np.float32)
    episode = np.concatenate([np.full(len(w), i) for i, w in enumerate(walks)])
    return emb, episode


def test_the_waypoint_behind_a_wall_leads_through_the_door(rooms):
    emb, episode = rooms
    graph = SubgoalGraph(emb, episode, lookahead=4)
    here, goal = torch.tensor([[0.9, 0.1]]), torch.tensor([[1.3, 0.1]])  # 0.4 apart, the wall between
    path = graph.path(int(graph.nearest(here)[0]), int(graph.nearest(goal)[0]))
    assert max(float(emb[n, 1]) for n in path) > 0.9  # the path goes through the door
    assert all(not 1.0 < emb[n, 0] < 1.2 or emb[n, 1] > 0.9 for n in path)  # never through the wall
    waypoint = graph.waypoints(here, goal)[0]
    assert waypoint[0] < 1.0 and 0.1 + 3 * STEP <= waypoint[1] <= 0.1 + 5 * STEP  # 4 steps up the left side
    # near the door the waypoint is through it, on the right side
    assert graph.waypoints(torch.tensor([[0.9, 0.9]]), goal)[0, 0] > 1.0


def test_a_goal_within_the_lookahead_or_unreachable_is_kept(rooms):
    emb, episode = rooms
    graph = SubgoalGraph(emb, episode, lookahead=4)
    here = torch.tensor([[0.5, 0.1], [0.5, 0.1]])
    goal = torch.tensor([[0.6, 0.1], [5.0, 5.0]])  # 2 steps away; far from every node, reached via the last one
    out = graph.waypoints(here, goal)
    torch.testing.assert_close(out[0], goal[0])
    # an isolated node (its own episode, far from the others) is unreachable: the goal is kept
    lonely = SubgoalGraph(np.concatenate([emb, [[9.0, 9.0]]]), np.concatenate([episode, [99]]), lookahead=2)
    torch.testing.assert_close(lonely.waypoints(here[:1], torch.tensor([[9.0, 9.0]]))[0], torch.tensor([9.0, 9.0]))


def test_temporal_edges_are_one_way_and_neighbours_two_way():
    # one episode walking right; no neighbour edges (radius = one step, but neighbors=0)
    emb = _walk([(0.0, 0.0), (1.0, 0.0)]).astype(np.float32)
    one_way = SubgoalGraph(emb, np.zeros(len(emb)), lookahead=1, neighbors=0)
    assert one_way.path(0, len(emb) - 1) == list(range(len(emb)))
    assert one_way.path(len(emb) - 1, 0) == []
    both = SubgoalGraph(emb, np.zeros(len(emb)), lookahead=1, neighbors=4, radius_quantile=1.0)
    assert both.path(len(emb) - 1, 0)[-1] == 0


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        (dict(lookahead=0), "lookahead >= 1"),
        (dict(lookahead=2.5), "lookahead >= 1"),
        (dict(radius_quantile=0.0), "radius_quantile in"),
        (dict(neighbors=-1), "neighbors >= 0"),
    ],
)
def test_bad_graph_arguments(rooms, kwargs, match):
    emb, episode = rooms
    with pytest.raises(ConfigError, match=match):
        SubgoalGraph(emb, episode, **kwargs)


def test_bad_graph_inputs():
    with pytest.raises(ConfigError, match=r"embeddings \(N, D\) with N >= 2"):
        SubgoalGraph(np.zeros((3, 2)), np.zeros(2))
    with pytest.raises(ConfigError, match=r"embeddings \(N, D\) with N >= 2"):
        SubgoalGraph(np.zeros(3), np.zeros(3))


def test_plan_settings_check_subgoals():
    with pytest.raises(UnknownNameError, match="graph"):
        PlanSettings(subgoals="grahp")
    with pytest.raises(ConfigError, match="lookahead to be a positive int"):
        PlanSettings(subgoals="graph", lookahead=0)
    plan = PlanSettings(horizon=7, subgoals="graph").as_dict()
    assert plan["subgoals"] == "graph" and plan["lookahead"] == 3  # half the horizon
    assert PlanSettings(horizon=1, subgoals="graph").waypoint_blocks == 1
    assert PlanSettings(horizon=7, subgoals="graph", lookahead=5).as_dict()["lookahead"] == 5
    assert PlanSettings().subgoals == "auto" and PlanSettings().as_dict()["subgoals"] == "auto"
    for plain in (None, "none"):
        assert (
            PlanSettings(subgoals=plain).as_dict()["subgoals"] == "none"
            and "lookahead" not in PlanSettings(subgoals=plain).as_dict()
        )
    assert PlanSettings(patience=7).as_dict()["patience"] == 7
    with pytest.raises(ConfigError, match="patience to be a positive int"):
        PlanSettings(patience=0)


def _at(*distances: float) -> tuple[torch.Tensor, torch.Tensor]:
    """``(current, goal)`` of envs at these distances from the goal (1-D embeddings, goal at 0)."""
    return torch.tensor(distances, dtype=torch.float32)[:, None], torch.zeros(len(distances), 1)


def test_stall_monitor_flags_an_env_that_stops_getting_closer():
    mon = StallMonitor(patience=10, steps_per_call=5, tolerance=1.0)
    assert mon.update(*_at(20.0, 20.0)).tolist() == [False, False]  # the first replan only measures
    assert mon.update(*_at(15.0, 20.0)).tolist() == [False, False]  # env 1: 5 steps without progress
    assert mon.update(*_at(10.0, 19.5)).tolist() == [False, True]  # 10 steps: 0.5 < tolerance is no progress
    assert mon.update(*_at(10.0, 5.0)).tolist() == [False, True]  # once stalled, it stays stalled
    assert mon.update(*_at(9.6, 5.0)).tolist() == [True, True]  # env 0: 0.4 closer in 10 steps


def test_stall_monitor_creeping_progress_adds_up():
    mon = StallMonitor(patience=2, steps_per_call=1, tolerance=1.0)
    flags = [mon.update(*_at(d))[0].item() for d in (10.0, 9.4, 8.8, 8.2, 7.6, 7.0)]
    assert flags == [False] * 6  # 0.6 per step: progress of >= 1 every second step


def test_stall_monitor_starts_over_on_a_new_goal_or_a_restart():
    mon = StallMonitor(patience=1, steps_per_call=1)
    mon.update(*_at(3.0, 3.0))
    assert mon.update(*_at(3.0, 3.0)).tolist() == [True, True]
    current, goal = _at(3.0, 3.0)
    goal[0] = 1.0  # env 0: a new episode with another goal
    assert mon.update(current, goal, restarted=torch.tensor([False, True])).tolist() == [False, False]
    mon.reset()
    assert mon.update(*_at(3.0, 3.0)).tolist() == [False, False]


def test_stall_monitor_checks_its_arguments():
    with pytest.raises(ConfigError, match="patience to be a positive int, got 0"):
        StallMonitor(patience=0)
    with pytest.raises(ConfigError, match="steps_per_call"):
        StallMonitor(patience=3, steps_per_call=True)
    with pytest.raises(ConfigError, match="tolerance >= 0"):
        StallMonitor(patience=3, tolerance=-1.0)

"""WorldModelPolicy inside a World: a hand-written cost on Toy, ground-truth dynamics on TwoRoom."""

from __future__ import annotations

import numpy as np
import torch

from stable_worldmodel import World
from stable_worldmodel.keys import ACTION, GOAL_STATE, STATE
from stable_worldmodel.policy import PlanConfig, WorldModelPolicy
from stable_worldmodel.solver import CEMSolver, MPPISolver

TOY_SPEED = 0.05  # the default agent speed of swm/Toy-v0


class ToyCost:
    """Point model of swm/Toy-v0: final position ``pos + speed * sum(actions)``; cost = distance to goal."""

    def __init__(self):
        self.calls = 0

    def get_cost(self, info, candidates):  # candidates (B, S, H, block * 2)
        self.calls += 1
        b, s = candidates.shape[:2]
        pos, goal = info[STATE][:, :, -1, :2], info[GOAL_STATE][:, :, -1, :2]
        moves = candidates.reshape(b, s, -1, 2).clamp(-1, 1)
        final = (pos + TOY_SPEED * moves.sum(dim=2)).clamp(0, 1)
        return (final - goal).norm(dim=-1)


def toy_world(num_envs=3, max_episode_steps=60):
    return World(
        "swm/Toy-v0",
        num_envs=num_envs,
        image_shape=(16, 16),
        max_episode_steps=max_episode_steps,
        verbose=0,
        vectorization_mode="sync",
    )


def test_receding_horizon_inside_a_world():
    cost = ToyCost()
    config = PlanConfig(horizon=3, receding_horizon=2, action_block=2)
    policy = WorldModelPolicy(CEMSolver(cost, num_samples=32, n_steps=4, topk=4), config)
    with toy_world() as world:
        world.set_policy(policy)
        world.reset(seed=0)
        start = np.linalg.norm(world.infos[STATE][:, -1, :2] - world.infos[GOAL_STATE][:, -1, :2], axis=1)
        for step in range(8):
            world.step()
            assert world.infos[ACTION].shape[0] == 3
            assert np.array_equal(world.infos[ACTION][:, -1], policy._queue[:, (step % 4)])
        assert cost.calls == 2 * 4  # two plans (steps 0 and 4) of 4 CEM iterations
        assert policy.last_plan["actions"].shape == (3, 3, 4)
        end = np.linalg.norm(world.infos[STATE][:, -1, :2] - world.infos[GOAL_STATE][:, -1, :2], axis=1)
        assert (end < start - 0.2).all() or world.terminateds.any()


def test_toy_goals_are_reached_by_planning():
    config = PlanConfig(horizon=4, receding_horizon=1, action_block=2)
    policy = WorldModelPolicy(MPPISolver(ToyCost(), num_samples=32, n_steps=5, topk=8), config)
    with toy_world(num_envs=4) as world:
        world.set_policy(policy)
        result = world.evaluate(episodes=4, seed=1)
    assert result["success_rate"] >= 75


class TwoRoomDynamics(torch.nn.Module):
    """Ground truth of swm/TwoRoom-v2 at its default factors, in torch.

    Steps the agent (radius 2, speed 2) with the border and the wall (passable only in a
    door gap) and scores each plan by the path length to the goal through the nearest door.
    """

    def __init__(self, speed=2.0, radius=2.0, low=4.0, high=60.0):
        super().__init__()
        self.speed, self.radius, self.low, self.high = speed, radius, low, high

    def get_cost(self, info, candidates):
        b, s = candidates.shape[:2]
        state, goal = info[STATE][:, :, -1], info[GOAL_STATE][:, :, -1, :2]
        wall_x, half = state[..., 2], state[..., 3] + self.radius
        doors = state[..., 4:].reshape(b, s, -1, 2)  # (centre y, half height), 0 when absent
        door_lo, door_hi = doors[..., 0] - doors[..., 1] + self.radius, doors[..., 0] + doors[..., 1] - self.radius
        pos = state[..., :2]
        total = torch.zeros(b, s)
        moves = candidates.reshape(b, s, -1, 2).clamp(-1, 1)
        for t in range(moves.shape[2]):
            new = (pos + self.speed * moves[:, :, t]).clamp(self.low, self.high)
            in_door = ((new[..., 1:] > door_lo) & (new[..., 1:] < door_hi) & (doors[..., 1] > 0)).any(-1)
            left = pos[..., 0] < wall_x
            x = torch.where(left, torch.minimum(new[..., 0], wall_x - half), torch.maximum(new[..., 0], wall_x + half))
            pos = torch.stack([torch.where(in_door, new[..., 0], x), new[..., 1]], dim=-1)
            total = total + self.path_length(pos, goal, wall_x, doors)
        return self.path_length(pos, goal, wall_x, doors) + 0.1 * total / moves.shape[2]

    @staticmethod
    def path_length(pos, goal, wall_x, doors):
        same_side = (pos[..., 0] < wall_x) == (goal[..., 0] < wall_x)
        centres = torch.where(doors[..., 1] > 0, doors[..., 0], torch.full_like(doors[..., 0], 1e6))
        door_y = centres.gather(-1, (centres - pos[..., 1:]).abs().argmin(-1, keepdim=True))[..., 0]
        door = torch.stack([wall_x, door_y], dim=-1)
        detour = (pos - door).norm(dim=-1) + (door - goal).norm(dim=-1)
        return torch.where(same_side, (pos - goal).norm(dim=-1), detour)


def test_two_room_goal_reached_with_ground_truth_dynamics():
    config = PlanConfig(horizon=5, receding_horizon=1, action_block=2)
    solver = CEMSolver(TwoRoomDynamics(), num_samples=64, n_steps=6, topk=8)
    with World(
        "swm/TwoRoom-v2", num_envs=4, image_shape=(16, 16), max_episode_steps=80, verbose=0, vectorization_mode="sync"
    ) as world:
        world.set_policy(WorldModelPolicy(solver, config))
        result = world.evaluate(episodes=4, seed=3)
    assert result["success_rate"] >= 75

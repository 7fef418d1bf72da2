"""Subgoals from the training data: plan towards a waypoint the data shows is on the way.

A world model's latent distance, like the Euclidean one, does not know about walls: when the
goal lies behind one, every short plan that moves towards it gets stuck, and the way round
first leads away from it. :class:`SubgoalGraph` (search on the replay buffer, Eysenbach et
al. 2019, here in the model's latent space) builds a graph whose nodes are frames of the
training episodes (every ``stride`` env steps, 1 by default) encoded by the model, with

- **temporal edges**: from each node to the next one of its episode (one stride);
  these follow paths the data actually took, so they never cross a wall;
- **neighbour edges** (both ways): between nodes whose embeddings are within ``radius`` of
  each other, ``radius`` being the ``radius_quantile`` of the temporal edges' latent lengths
  (nodes that close are at most about one stride apart).

Path lengths count hops, so about strides: weighting the edges by latent length instead lets
paths run through regions the encoder compresses, and the waypoints then lie far further
than ``lookahead`` strides (measured on TwoRoom: behind the wall).

:meth:`SubgoalGraph.waypoints` takes the current and goal embeddings of each env, finds the
shortest path between their nearest nodes (a breadth-first search from the goal over
reversed edges, cached per goal) and returns the embedding of the node ``lookahead`` strides along it, or the
goal itself when the goal is within ``lookahead`` strides (or no path exists). The planner
then minimises the latent distance to that waypoint instead of the goal.
:class:`~stable_worldmodel.planning.world_model_policy.WorldModelPolicy` calls it at each
replan when given ``subgoals=`` (``swm eval --policy wm:RUN --subgoals graph``).

Shapes: N nodes, D embedding size, B envs.
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np
import torch

from ..errors import ConfigError

logger = logging.getLogger(__name__)

__all__ = ["StallMonitor", "SubgoalGraph", "build_subgoal_graph"]


def _pairwise_sq(a: torch.Tensor, b: torch.Tensor) -> torch.Tensor:
    return (a.pow(2).sum(-1, keepdim=True) + b.pow(2).sum(-1)[None] - 2.0 * a @ b.T).clamp_min(0.0)


class SubgoalGraph:
    """The latent graph of training frames (module docstring).

    Args:
        embeddings: ``(N, D)`` node embeddings.
        episode: ``(N,)`` episode of each node; consecutive nodes of one episode (in order)
            are joined by temporal edges.
        lookahead: strides along the path to the waypoint (>= 1).
        radius_quantile: quantile of the temporal edge lengths used as the neighbour radius.
        neighbors: at most this many neighbour edges per node.
    """

    def __init__(
        self,
        embeddings: torch.Tensor | np.ndarray,
        episode: Sequence[int] | np.ndarray,
        lookahead: int = 3,
        radius_quantile: float = 0.5,
        neighbors: int = 8,
    ):
        emb = torch.as_tensor(embeddings, dtype=torch.float32).detach().cpu()
        ep = np.asarray(episode).reshape(-1)
        if emb.ndim != 2 or len(emb) != len(ep) or len(emb) < 2:
            raise ConfigError(
                "SubgoalGraph requires embeddings (N, D) with N >= 2 and one episode id per node, "
                f"got {tuple(emb.shape)} and {ep.shape}"
            )
        if not (isinstance(lookahead, (int, np.integer)) and not isinstance(lookahead, bool) and lookahead >= 1):
            raise ConfigError(f"SubgoalGraph requires lookahead >= 1 (an int), got {lookahead!r}")
        if not 0.0 < radius_quantile <= 1.0:
            raise ConfigError(f"SubgoalGraph requires radius_quantile in (0, 1], got {radius_quantile!r}")
        if not (isinstance(neighbors, (int, np.integer)) and neighbors >= 0):
            raise ConfigError(f"SubgoalGraph requires neighbors >= 0 (an int), got {neighbors!r}")
        self.embeddings, self.episode, self.lookahead = emb, ep, int(lookahead)
        n = len(emb)
        src_t = np.nonzero(ep[1:] == ep[:-1])[0]  # temporal edges src -> src + 1
        step = (emb[src_t + 1] - emb[src_t]).norm(dim=-1).numpy()
        self.radius = float(np.quantile(step, radius_quantile)) if len(src_t) else 0.0
        src, dst = [src_t], [src_t + 1]
        if neighbors and self.radius > 0:
            k = min(int(neighbors) + 1, n)
            for lo in range(0, n, 2048):  # (2048, N) distances at a time
                dist, idx = torch.topk(_pairwise_sq(emb[lo : lo + 2048], emb), k, dim=1, largest=False)
                dist, idx = dist.sqrt().numpy(), idx.numpy()
                rows = np.broadcast_to(np.arange(lo, lo + len(idx))[:, None], idx.shape)
                keep = (dist <= self.radius * (1 + 1e-3)) & (idx != rows)  # float error of the expansion
                src += [rows[keep], idx[keep]]  # both ways
                dst += [idx[keep], rows[keep]]
        pairs = np.unique(np.stack([np.concatenate(dst), np.concatenate(src)], 1), axis=0)  # sorted by dst
        # reversed adjacency (CSR): the nodes with an edge *into* each node, for a search from the goal
        self._into_ptr = np.searchsorted(pairs[:, 0], np.arange(n + 1))
        self._into = pairs[:, 1]
        self.num_edges = len(pairs)
        self._cache: dict[int, tuple[np.ndarray, np.ndarray]] = {}

    def __repr__(self) -> str:
        return (
            f"SubgoalGraph(nodes={len(self.embeddings)}, edges={self.num_edges}, lookahead={self.lookahead}, "
            f"radius={self.radius:.4g})"
        )

    def nearest(self, emb: torch.Tensor) -> np.ndarray:
        """Index of the node nearest to each of ``emb: (B, D)``: ``(B,)``."""
        return _pairwise_sq(emb.detach().float().cpu(), self.embeddings).argmin(dim=1).numpy()

    def _to_goal(self, goal_node: int) -> tuple[np.ndarray, np.ndarray]:
        """Hops to ``goal_node`` (inf: no path) and the next node towards it, for every node: a
        breadth-first search from the goal over reversed edges, one vectorized level at a time (cached)."""
        if goal_node not in self._cache:
            if len(self._cache) > 256:
                self._cache.clear()
            n = len(self._into_ptr) - 1
            dist, nxt = np.full(n, np.inf), np.full(n, -1, np.int64)
            dist[goal_node], frontier, level = 0.0, np.array([goal_node]), 0
            while len(frontier):
                level += 1
                counts = self._into_ptr[frontier + 1] - self._into_ptr[frontier]
                parent = np.repeat(frontier, counts)
                cand = self._into[
                    np.repeat(self._into_ptr[frontier] - np.cumsum(counts) + counts, counts) + np.arange(counts.sum())
                ]
                new = np.isinf(dist[cand])
                cand, first = np.unique(cand[new], return_index=True)
                dist[cand], nxt[cand] = level, parent[new][first]
                frontier = cand
            self._cache[goal_node] = (dist, nxt)
        return self._cache[goal_node]

    def path(self, start_node: int, goal_node: int) -> list[int]:
        """Nodes of the shortest path from ``start_node`` to ``goal_node`` (``[]`` when none)."""
        dist, nxt = self._to_goal(int(goal_node))
        if not np.isfinite(dist[start_node]):
            return []
        out, node = [int(start_node)], int(start_node)
        while node != goal_node:
            node = int(nxt[node])
            out.append(node)
        return out

    def waypoints(self, current: torch.Tensor, goal: torch.Tensor) -> torch.Tensor:
        """``current, goal: (B, D)`` -> the embeddings to plan towards ``(B, D)`` (module docstring)."""
        out = goal.clone()
        starts, goals = self.nearest(current), self.nearest(goal)
        for i, (s, g) in enumerate(zip(starts, goals, strict=False)):
            path = self.path(int(s), int(g))  # [] when unreachable
            if len(path) > self.lookahead + 1:  # farther than the lookahead: the node that far along
                out[i] = self.embeddings[path[self.lookahead]].to(out)
        return out


class StallMonitor:
    """Which envs stopped getting closer to their goal (``subgoals="auto"``).

    Each :meth:`update` (one replan, ``steps_per_call`` env steps after the last) measures every
    env's latent distance to its goal. An env whose distance has not come ``tolerance`` below the
    distance of its last progress (at first: its starting distance) for ``patience`` env steps is
    *stalled* from then on, until its goal changes or it restarts (a new episode), when it starts
    over.

    Args:
        patience: env steps without progress before an env counts as stalled (>= 1).
        steps_per_call: env steps between two updates (the plan's executed steps).
        tolerance: the least improvement that counts as progress (a latent length).
    """

    def __init__(self, patience: int, steps_per_call: int = 1, tolerance: float = 0.0):
        for name, value in (("patience", patience), ("steps_per_call", steps_per_call)):
            if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 1:
                raise ConfigError(f"StallMonitor requires {name} to be a positive int, got {value!r}")
        if not tolerance >= 0:
            raise ConfigError(f"StallMonitor requires tolerance >= 0, got {tolerance!r}")
        self.patience, self.steps_per_call, self.tolerance = int(patience), int(steps_per_call), float(tolerance)
        self.reset()

    def reset(self) -> None:
        """Forget every env's progress."""
        self._goal: torch.Tensor | None = None  # (B, D) the goals being tracked
        self._best = self._idle = self._stalled = None  # (B,) distance at the last progress, steps since, stalled

    def update(self, current: torch.Tensor, goal: torch.Tensor, restarted: Any = None) -> torch.Tensor:
        """``current, goal: (B, D)``, ``restarted: (B,)`` bool or None -> ``(B,)`` bool: stalled envs."""
        dist = (goal - current).norm(dim=-1).float().cpu()
        goal = goal.detach().float().cpu()
        if self._goal is None or self._goal.shape != goal.shape:
            self._goal, self._best = goal.clone(), dist.clone()
            self._idle, self._stalled = (
                torch.zeros(len(dist), dtype=torch.long),
                torch.zeros(len(dist), dtype=torch.bool),
            )
            return self._stalled.clone()
        new = (goal - self._goal).abs().amax(dim=-1) > 1e-5
        if restarted is not None:
            new |= torch.as_tensor(restarted, dtype=torch.bool).reshape(-1).cpu()
        self._goal[new], self._best[new], self._stalled[new] = goal[new], dist[new], False
        progress = dist < self._best - self.tolerance  # creeping counts once it adds up to the tolerance
        self._best = torch.where(progress, dist, self._best)
        self._idle = torch.where(progress | new, 0, self._idle + self.steps_per_call)
        self._stalled |= self._idle >= self.patience
        return self._stalled.clone()


def build_subgoal_graph(
    encode: Callable[[torch.Tensor], torch.Tensor],
    dataset: Any,
    episodes: Sequence[int],
    transform: Callable[[torch.Tensor], torch.Tensor],
    *,
    lookahead_steps: int,
    stride: int = 1,
    max_nodes: int = 20_000,
    batch_size: int = 256,
    device: Any = "cpu",
    **graph_kwargs: Any,
) -> SubgoalGraph:
    """A :class:`SubgoalGraph` of ``dataset``'s ``episodes``, one node every ``stride`` env steps,
    waypoints ``lookahead_steps`` env steps along the path.

    ``encode`` maps preprocessed images ``(N, C, h, w)`` to embeddings ``(N, D)``;
    ``transform`` preprocesses the dataset's ``pixels`` ``(N, C, H, W)`` uint8 as at planning
    time. When the episodes hold more than ``max_nodes`` frames, the stride grows to fit. Dense
    nodes (stride 1) keep the neighbour radius small, so neighbour edges do not jump walls.
    """
    from .. import keys

    if not len(episodes):
        raise ConfigError("build_subgoal_graph requires at least one episode, got none")
    lengths = np.asarray(dataset.lengths)[np.asarray(episodes)]
    stride = max(int(stride), int(np.ceil(lengths.sum() / max_nodes)), 1)
    frames, ep_ids = [], []
    for ep in episodes:
        pixels = dataset.load_episode(int(ep))[keys.PIXELS]
        take = pixels[::stride]
        frames.append(take)
        ep_ids.append(np.full(len(take), int(ep)))
    embs = []
    with torch.inference_mode():
        pending = torch.cat(frames)
        for lo in range(0, len(pending), batch_size):
            batch = transform(pending[lo : lo + batch_size]).to(device)
            embs.append(encode(batch).float().cpu())
    lookahead = max(1, int(np.ceil(int(lookahead_steps) / stride)))
    graph = SubgoalGraph(torch.cat(embs), np.concatenate(ep_ids), lookahead=lookahead, **graph_kwargs)
    graph.stride = stride
    logger.info("subgoal graph of %d episodes (stride %d): %r", len(episodes), stride, graph)
    return graph

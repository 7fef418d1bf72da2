"""A ready-to-run :class:`~stable_worldmodel.policy.WorldModelPolicy` from a trained checkpoint.

``world_model_policy("tr-lewm", solver="cem")`` loads ``checkpoints/tr-lewm`` (weights,
config and our ``protocol.json``), moves the model to the device, and wires what the run
recorded: the action normalizer (the solver plans in normalized action-block units), the
image preprocessing (``pixels`` and ``goal``), and ``action_block = frameskip``.
Upstream checkpoints (no ``protocol.json``) plan with ``frameskip`` and ``image_*`` given
as arguments.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field, replace
from typing import Any

from ..errors import ConfigError
from ..wm.config import GOAL_COSTS

logger = logging.getLogger(__name__)

__all__ = ["PlanSettings", "world_model_policy"]

SUBGOALS = ("auto", "graph", "none")
PLAN_COSTS = ("auto", *GOAL_COSTS)
#: the least ``patience`` (env steps) of ``subgoals="auto"``: a plan needs a few steps to show progress
MIN_PATIENCE = 10


@dataclass(frozen=True)
class PlanSettings:
    """How to plan: solver name, horizon (blocks), receding horizon (blocks executed before
    replanning: 1 by default, ``None`` for the whole plan), samples, iterations, seed,
    and ``cost``: ``"min"`` scores a candidate by its predicted embedding closest to the goal's
    (the goal may be reached before the horizon ends), ``"final"`` by the last one (upstream's
    ``criterion``), ``"auto"`` (the default): ``"min"`` for the models that score goal distance,
    and the model's own cost for the others (TD-MPC2: reward and value), which take no other.

    ``subgoals="graph"`` plans towards waypoints of a latent graph of the training episodes
    (:mod:`~stable_worldmodel.planning.subgoals`), ``lookahead`` blocks ahead along its shortest
    path to the goal (default: half the horizon, see :attr:`waypoint_blocks`); ``"none"`` (or
    ``None``) plans on the goal alone (plain MPC, what papers report). ``"auto"`` (the default)
    plans on the goal alone and switches an episode to the graph's waypoints once it stalls: its
    latent distance to the goal has not improved by a typical step for ``patience`` env steps
    (default: half a horizon, ``horizon`` x the action block // 2, at least :data:`MIN_PATIENCE`;
    on upstream's TwoRoom with LeWM tiny: 12 steps 96%, 25 steps 92%, always waypoints 98%).
    It needs what the graph needs (LeWM, PLDM, Dreamer or a PreJEPA without proprio, trained by
    ``swm train`` on a dataset still on disk) and is ``"none"`` elsewhere; the protocol that
    :func:`world_model_policy` returns records which.

    ``compile=True`` scores candidates through ``torch.compile`` of the model's ``get_cost``
    (:meth:`~stable_worldmodel.solver.base.BaseSolver.compile_cost`): the first plan compiles (tens of
    seconds on a CPU), every later one runs faster, with the same costs up to float rounding."""

    solver: str = "cem"
    horizon: int = 5
    receding_horizon: int | None = 1
    samples: int = 300
    iterations: int = 30
    topk: int | None = None
    seed: int = 0
    cost: str = "auto"
    subgoals: str | None = "auto"
    lookahead: int | None = None
    patience: int | None = None
    compile: bool = False
    extra: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        from ..solver import list_solvers

        if self.solver not in list_solvers():
            from ..errors import unknown_name

            raise unknown_name("planning solver", self.solver, list_solvers())
        if self.cost not in PLAN_COSTS:
            from ..errors import unknown_name

            raise unknown_name("goal cost", self.cost, PLAN_COSTS)
        for name in ("horizon", "samples", "iterations"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int) or value < 1:
                raise ConfigError(f"PlanSettings requires {name} to be a positive int, got {value!r}")
        rh = self.receding_horizon
        if rh is not None and (isinstance(rh, bool) or not isinstance(rh, int) or not 1 <= rh <= self.horizon):
            raise ConfigError(f"PlanSettings requires 1 <= receding_horizon <= horizon={self.horizon}, got {rh!r}")
        if self.subgoals is not None and self.subgoals not in SUBGOALS:
            from ..errors import unknown_name

            raise unknown_name("subgoal method", self.subgoals, SUBGOALS)
        for name in ("lookahead", "patience"):
            value = getattr(self, name)
            if value is not None and (isinstance(value, bool) or not isinstance(value, int) or value < 1):
                raise ConfigError(f"PlanSettings requires {name} to be a positive int, got {value!r}")
        if not isinstance(self.compile, bool):
            raise ConfigError(f"PlanSettings requires compile to be True or False, got {self.compile!r}")

    @property
    def waypoint_blocks(self) -> int:
        """``lookahead``, by default half the horizon (at least 1 block): far waypoints lie where the
        latent distance no longer guides the planner (measured on TwoRoom: 2 of 5 blocks plans
        round the wall, 5 of 5 stalls)."""
        return self.lookahead or max(1, self.horizon // 2)

    def as_dict(self) -> dict[str, Any]:
        return {
            "solver": self.solver,
            "horizon": self.horizon,
            "receding_horizon": self.receding_horizon or self.horizon,
            "samples": self.samples,
            "iterations": self.iterations,
            "topk": self.topk,
            "seed": self.seed,
            "cost": self.cost,
            "subgoals": self.subgoals or "none",
            **({"lookahead": self.waypoint_blocks} if self.subgoals not in (None, "none") else {}),
            **({"patience": self.patience} if self.subgoals == "auto" and self.patience else {}),
            **({"compile": True} if self.compile else {}),
            **self.extra,
        }


def _make_solver(model: Any, settings: PlanSettings, device: Any) -> Any:
    """The solver of ``settings``: its class's :class:`~stable_worldmodel.solver.base.PlanKnobs` say
    which constructor arguments the plan's samples, iterations and elites go to."""
    from ..solver import get_solver_class

    cls = get_solver_class(settings.solver)
    kwargs = cls.knobs.kwargs(settings.samples, settings.iterations, settings.topk)
    solver = cls(model, device=device, seed=settings.seed, **kwargs)
    return solver.compile_cost() if settings.compile else solver


def world_model_policy(
    run: str,
    settings: PlanSettings | None = None,
    *,
    device: str = "auto",
    cache_dir: str | None = None,
    frameskip: int | None = None,
) -> tuple[Any, dict[str, Any]]:
    """``(policy, protocol)`` for checkpoint ``run`` (see the module docstring). ``frameskip``
    (the action block) defaults to the run's; another than the one it recorded is a
    :class:`~stable_worldmodel.errors.RunMismatchError`.

    The World must give the model ``pixels`` and ``goal`` infos with ``history_size`` 1.
    """
    import torch

    from ..policy import PlanConfig, WorldModelPolicy
    from .goal_policy import load_run

    settings = settings or PlanSettings()
    model, protocol, dev, process, transform = load_run(
        run, "get_cost", "a world model with get_cost (lewm, pldm, dummy)", "gc", device, cache_dir
    )
    for p in model.parameters():  # GD differentiates w.r.t. the actions only
        p.requires_grad_(False)
    if not hasattr(model, "goal_cost") and settings.cost != "auto":
        raise ConfigError(
            f"PlanSettings(cost={settings.cost!r}) requires a model with goal_cost, got {type(model).__name__} "
            f"(it plans on its own cost); use cost='auto'"
        )
    if hasattr(model, "goal_cost"):
        model.goal_cost = "min" if settings.cost == "auto" else settings.cost
    if frameskip is not None:  # another block than the run's: its model takes actions of another size
        from .run_fit import RunFacts, check_run_fits

        check_run_fits(RunFacts.from_protocol(run, protocol), "world_model_policy", frameskip=frameskip)
    block = int(frameskip or protocol.get("frameskip", 1))
    config = PlanConfig(
        horizon=settings.horizon,
        receding_horizon=settings.receding_horizon or settings.horizon,
        history_len=1,
        action_block=block,
        warm_start=True,
    )
    solver = _make_solver(model, settings, dev)
    policy = WorldModelPolicy(solver, config, process=process, transform=transform)
    settings = resolve_subgoals(run, settings, cache_dir, protocol=protocol, block=block)
    plan = settings.as_dict()
    if settings.subgoals in ("graph", "auto"):
        graph = _subgoal_graph(run, model, protocol, transform, block, settings.waypoint_blocks, dev, cache_dir)
        patience = settings.patience if settings.subgoals == "auto" else None
        policy.info_hook = _WaypointHook(
            model, graph, patience, (settings.receding_horizon or settings.horizon) * block
        )
        plan["graph"] = {
            "nodes": len(graph.embeddings),
            "edges": graph.num_edges,
            "stride": graph.stride,
            "episodes": "train split of " + str(protocol.get("dataset")),
        }
    protocol = {**protocol, "plan": plan, "device": str(dev), "action_block": block}
    if dev.type == "cuda":
        torch.backends.cuda.matmul.allow_tf32 = True
    return policy, protocol


def resolve_subgoals(
    run: str,
    settings: PlanSettings,
    cache_dir: str | None = None,
    *,
    protocol: dict | None = None,
    block: int | None = None,
) -> PlanSettings:
    """``settings`` with ``subgoals="auto"`` kept where a subgoal graph can be built for checkpoint
    ``run`` (trained by ``swm train`` as a LeWM, PLDM, Dreamer or PreJEPA without proprio, its training
    dataset on disk, its ``patience`` filled in for action blocks of ``block`` env steps, by
    default the run's frameskip) and made ``"none"`` elsewhere; other values are returned as they are."""
    if settings.subgoals != "auto":
        return settings
    if protocol is None:
        from ..wm.run import Run

        protocol = Run.open(run, cache_dir).protocol.to_dict()
    why = _graph_unavailable(protocol, cache_dir)
    if why:
        logger.info("Run %r plans on the goal alone (subgoals='auto' -> 'none'): %s", run, why)
        return replace(settings, subgoals="none")
    logger.info(
        "Run %r plans on the goal, and towards waypoints of its training data where it stalls "
        "(subgoals='auto'; 'none' plans on the goal alone)",
        run,
    )
    block = int(block or protocol.get("frameskip", 1))
    return replace(settings, patience=settings.patience or max(MIN_PATIENCE, settings.horizon * block // 2))


def _graph_unavailable(protocol: dict, cache_dir: str | None) -> str | None:
    """Why a subgoal graph cannot be built for a run with ``protocol`` (None: it can)."""
    from ..wm import get_config_class, list_models

    model = protocol.get("model")
    if model not in list_models():
        return f"model {model!r} is not a registered model trained by swm train"
    why = get_config_class(model).subgoal_graph_unavailable(protocol.get("config") or {})
    if why:
        return why
    if not protocol.get("dataset") or protocol.get("train_episodes") is None:
        return "its protocol names no training dataset"
    path = protocol.get("dataset_path")
    if path and _exists(path):
        return None
    from ..data.utils import resolve_dataset_path

    if not resolve_dataset_path(protocol["dataset"], cache_dir).exists():
        return f"its training dataset {protocol['dataset']!r} is not on disk"
    return None


def _subgoal_graph(
    run: str, model: Any, protocol: dict, transform: dict, block: int, lookahead: int, dev: Any, cache_dir: str | None
) -> Any:
    """The :class:`~.subgoals.SubgoalGraph` of ``run``'s training episodes (a node per frame),
    waypoints ``lookahead`` action blocks of ``block`` env steps ahead."""
    from .. import keys
    from ..data import HDF5Dataset
    from .subgoals import build_subgoal_graph

    _WaypointHook.check(model, run)
    name, episodes = protocol.get("dataset"), protocol.get("train_episodes")
    if not name or episodes is None:
        raise ConfigError(
            f"subgoals='graph' requires a run trained by swm train (its protocol names the dataset and "
            f"train split), got run {run!r} without them"
        )
    path = protocol.get("dataset_path")
    try:
        dataset = (
            HDF5Dataset(path=path, keys_to_load=[keys.PIXELS])
            if path and _exists(path)
            else HDF5Dataset(name, keys_to_load=[keys.PIXELS], cache_dir=cache_dir)
        )
    except FileNotFoundError as exc:
        raise ConfigError(f"subgoals='graph' requires run {run!r}'s training dataset {name!r}: {exc}") from exc
    return build_subgoal_graph(
        lambda x: model.encode_pixels(x).flatten(1),
        dataset,
        episodes,
        transform[keys.PIXELS],
        device=dev,
        lookahead_steps=max(1, int(lookahead)) * block,
    )


def _exists(path: str) -> bool:
    from pathlib import Path

    return Path(path).exists()


class _WaypointHook:
    """``WorldModelPolicy.info_hook``: encode the frames and the goal once, and put the graph's
    waypoint where the model's cost reads the encoded goal: ``goal_emb`` (LeWM, PLDM, Dreamer:
    ``(B, 1, D)``) or ``pixels_goal_emb`` (PreJEPA without proprio: patch features ``(B, 1, P, Dv)``).
    Graph nodes are the flattened ``encode_pixels`` embeddings. Dreamer filters its context
    itself (with the actions between frames), so its context key is None.

    ``patience`` (env steps; None: always aim at the waypoint) is ``subgoals="auto"``: an env aims
    at its goal until a :class:`~.subgoals.StallMonitor` (``steps_per_call`` env steps per replan,
    a graph radius as the least progress) says it stalled, then at the graph's waypoints."""

    def __init__(self, model: Any, graph: Any, patience: int | None = None, steps_per_call: int = 1):
        from .subgoals import StallMonitor

        self.model, self.graph = model, graph
        self.context_key, self.goal_key = self.keys(model)
        self.monitor = None if patience is None else StallMonitor(patience, steps_per_call, graph.radius)

    @staticmethod
    def keys(model: Any) -> tuple[str | None, str]:
        """The info keys the model caches its context (None: not set by the hook) and goal embeddings under."""
        from ..wm.base import SupportsSubgoalGraph

        if not isinstance(model, SupportsSubgoalGraph):
            raise ConfigError(
                "subgoals='graph' requires a model with subgoal_keys() (LeWM, PLDM, Dreamer, PreJEPA), "
                f"got {type(model).__name__}"
            )
        return model.subgoal_keys()

    @classmethod
    def check(cls, model: Any, run: str) -> None:
        try:
            cls.keys(model)
        except ConfigError as exc:
            raise ConfigError(f"{exc} (run {run!r})") from None

    def reset(self) -> None:
        """Forget the progress of every env (``WorldModelPolicy.reset_plan`` calls it)."""
        if self.monitor is not None:
            self.monitor.reset()

    def __call__(self, info: dict) -> dict:
        import torch

        from .. import keys

        dev = next(self.model.parameters()).device
        with torch.inference_mode():
            pixels = info[keys.PIXELS].to(dev)  # (B, T, C, h, w)
            emb = self.model.encode_pixels(pixels if self.context_key else pixels[:, -1:])  # (B, T, ...)
            goal = self.model.encode_pixels(info[keys.GOAL].to(dev))[:, -1]  # (B, ...)
            current, flat_goal = emb[:, -1].flatten(1), goal.flatten(1)
            if self.monitor is None:
                waypoint = self.graph.waypoints(current, flat_goal).reshape(goal.shape)
            else:  # the graph is searched only once some env has stalled
                step = info.get(keys.STEP_IDX)
                restarted = None if step is None else torch.as_tensor(step).reshape(len(goal), -1)[:, -1] == 0
                on = self.monitor.update(current, flat_goal, restarted)
                waypoint = goal
                if bool(on.any()):
                    found = self.graph.waypoints(current, flat_goal).reshape(goal.shape)
                    waypoint = torch.where(on.to(dev).reshape(-1, *([1] * (goal.ndim - 1))), found, goal)
        if self.context_key:
            info[self.context_key] = emb
        info[self.goal_key] = waypoint[:, None]
        return info


def attach_prediction_panel(
    policy: Any, run: str, decoder: str | None = None, *, device: str = "auto", cache_dir: str | None = None
) -> str | None:
    """Make ``policy`` (a ``wm:run`` :class:`~stable_worldmodel.policy.WorldModelPolicy`) decode
    what it predicts with frame decoder run ``decoder`` (default: ``<run>-frame`` when it
    exists; ``swm train frame --from RUN`` makes it; else the model's own image decoder when it
    has one, as Dreamer), so ``World.record_video`` shows it. Returns the decoder run used
    (``run`` for the model's own decoder), or None when there is none to use."""
    from .._device import resolve_device
    from ..wm.frame import FrameModel, PredictionPanel
    from ..wm.run import Run
    from ..wm.utils import checkpoint_root

    name = decoder or f"{run}-frame"
    if decoder is None and not (checkpoint_root(cache_dir) / name).is_dir():
        model = policy.solver.model
        from ..wm.base import DecodesFrames

        if not (isinstance(model, DecodesFrames) and model.decodes_frames):
            return None
        protocol = Run.open(run, cache_dir).protocol.to_dict()
        policy.prediction_panel = PredictionPanel(
            model, None, protocol.get("image_mean", (0.5,) * 3), protocol.get("image_std", (0.5,) * 3)
        )
        return run
    opened = Run.open(name, cache_dir)
    frame, protocol = opened.load_model(), opened.protocol.to_dict()
    if not isinstance(frame, FrameModel):
        raise ConfigError(
            f"A prediction panel requires a frame decoder run (swm train frame --from {run}), "
            f"got {type(frame).__name__} in {name!r}"
        )
    source = protocol.get("config", {}).get("source")
    if source not in (None, run):
        logger.warning(
            "Frame decoder %r was trained on the latents of %r, not %r: its frames may not mean much", name, source, run
        )
    frame = frame.to(resolve_device(device, who="Planning")).eval()
    policy.prediction_panel = PredictionPanel(
        policy.solver.model, frame, protocol.get("image_mean", (0.5,) * 3), protocol.get("image_std", (0.5,) * 3)
    )
    return name

"""The losses of :class:`~stable_worldmodel.wm.gcrl.GCRL`, one function per algorithm (upstream
0.1.1's ``scripts/train/gcbc.py``, ``gcivl.py`` and ``gciql.py``, written for one training loop).

``batch`` (from :class:`~stable_worldmodel.train.data.TrainData` or any caller)::

    pixels            (B, T, C, h, w)  preprocessed frames; the policy sees the first H = history_size
    action            (B, T, A)        normalized action blocks (NaN, at episode ends, counts as 0)
    goal_pixels       (B, 1, C, h, w)  a hindsight goal per sample (value / critic goal)
    actor_goal_pixels (B, 1, C, h, w)  optional: the goal of the actor term (default: goal_pixels)
    <key>, goal_<key>                  the inputs of each extra encoder (e.g. proprio)

- **gcbc**: ``action_loss = MSE(mean action of frames < H, action[:, :H])`` (T >= H).
- **gcivl** (T >= H + 1): the reward is -1 until the frame equals the goal (then 0 and the
  episode ends there); ``value_loss = expectile(V(s_t, g), r_t + discount * mask_t * V'(s_{t+1}, g))``
  with ``V'`` the EMA teacher; the actor is advantage weighted, ``actor_loss = mean(min(exp(
  awr_alpha * A), awr_max_weight) * NLL(a_t | policy))`` with ``A = V(s_{t+1}, g) - V(s_t, g)``.
- **gciql** (T >= H + 1): ``value_loss = expectile(V(s, g), Q'(s, a, g))``, ``critic_loss =
  MSE(Q(s, a, g), r + discount * mask * V'(s', g))``, and the actor as above with
  ``A = Q'(s, a, g) - V(s, g)`` (IQL's advantage).

Upstream trains the value (and critic) first and the actor afterwards, in two runs, the encoder
frozen in the second; here they are one sum with detached advantages (the actor never shapes the
value heads). ``model.actor_encoder_grad`` says whether the actor's loss also trains the shared
encoder: False is upstream's frozen second run (fine with a pretrained encoder); our presets set
True, as a from-scratch encoder trained by the value loss alone gives the actor too little to act
on (OGBench gives the actor an encoder of its own for the same reason). A goal "equals" a frame
when the preprocessed images (and extra inputs) are identical, as upstream compares them.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import torch
import torch.nn.functional as F

from ... import keys
from ...errors import ConfigError, SpaceError, UnknownNameError
from .module import ExpectileLoss, TeacherStudentWrapper

if TYPE_CHECKING:  # pragma: no cover
    from .gcrl import GCRL

__all__ = ["ACTOR_GOAL_PIXELS", "ALGORITHMS", "GOAL_PIXELS", "LOSSES", "gcbc_loss", "gciql_loss", "gcivl_loss"]

ALGORITHMS = ("gcbc", "gcivl", "gciql")
GOAL_PIXELS = keys.goal_key(keys.PIXELS)
ACTOR_GOAL_PIXELS = f"actor_{GOAL_PIXELS}"


def _get(batch: dict, key: str, model: GCRL) -> torch.Tensor:
    if key not in batch:
        raise UnknownNameError(
            f"{type(model).__name__}.loss ({model.algorithm}) requires batch[{key!r}], got keys {sorted(batch)}"
        )
    return batch[key]


def _frames(model: GCRL, batch: dict, extra: int) -> int:
    """H (the policy's frames), after checking the batch holds ``H + extra`` frames."""
    pixels = _get(batch, keys.PIXELS, model)
    if pixels.ndim != 5:
        raise SpaceError(
            f"{type(model).__name__}.loss requires pixels of shape (B, T, C, h, w), got {tuple(pixels.shape)}"
        )
    h = model.history_size
    if pixels.shape[1] < h + extra:
        raise ConfigError(
            f"{type(model).__name__}.loss ({model.algorithm}) "
            f"requires history_size + {extra} = {h + extra} frames per sample, "
            f"got {pixels.shape[1]}"
        )
    return h


def _encode(model: GCRL, batch: dict, goal_key: str) -> dict:
    """Observation embeddings ``embed (B, T, P, d)`` and goal embeddings ``goal_embed (B, 1, P, d)``."""
    for key in (keys.ACTION, goal_key):
        _get(batch, key, model)
    info = model.encode(dict(batch), pixels_key=keys.PIXELS, target="embed")
    return model.encode(info, pixels_key=goal_key, prefix=keys.goal_key(""), target="goal_embed")


def _action(batch: dict, h: int) -> torch.Tensor:
    return torch.nan_to_num(batch[keys.ACTION][:, :h].float(), 0.0)


def _not_at_goal(model: GCRL, batch: dict, h: int) -> torch.Tensor:
    """``(B, H, 1)``: 1 where frame t differs from the goal (reward -1, the episode goes on), 0 where equal."""
    equal = (batch[keys.PIXELS][:, :h] == batch[GOAL_PIXELS]).flatten(2).all(dim=-1)
    for key in model.extra_encoders:
        goal_key = keys.goal_key(key)
        if key in batch and goal_key in batch:
            equal &= (batch[key][:, :h] == batch[goal_key]).flatten(2).all(dim=-1)
    return (~equal).float().unsqueeze(-1)


def _student(head: Any) -> Callable[..., torch.Tensor]:
    return head.forward_student if isinstance(head, TeacherStudentWrapper) else head


def _teacher(head: Any) -> Callable[..., torch.Tensor]:
    if isinstance(head, TeacherStudentWrapper):
        return head.forward_teacher

    def run(*args: Any) -> torch.Tensor:
        with torch.no_grad():
            return head(*args)

    return run


def _update_targets(model: GCRL) -> None:
    if model.training:
        for head in (model.value_predictor, model.critic_predictor):
            if isinstance(head, TeacherStudentWrapper):
                head.update_teacher()


def _actor(model: GCRL, batch: dict, info: dict, h: int, advantage: Callable[[torch.Tensor], torch.Tensor]) -> dict:
    """The advantage-weighted Gaussian NLL of the data actions. The actor's goal is
    ``actor_goal_pixels`` when the batch has it; ``advantage(goal)`` gets its detached tokens
    ``(B, P, d)`` and returns ``(B, H, 1)``. The actor trains the encoder only when
    ``model.actor_encoder_grad``."""
    grad = model.actor_encoder_grad
    goal = info["goal_embed"]
    if ACTOR_GOAL_PIXELS in batch:
        with torch.set_grad_enabled(grad and torch.is_grad_enabled()):
            prefix = f"actor_{keys.goal_key('')}"
            goal = model.encode(dict(batch), pixels_key=ACTOR_GOAL_PIXELS, prefix=prefix, target="actor_goal_embed")[
                "actor_goal_embed"
            ]
    emb = info["embed"][:, :h]
    if not grad:
        emb, goal = emb.detach(), goal.detach()
    with torch.no_grad():
        adv = advantage(goal.detach().flatten(1, 2))
        weight = torch.exp(model.awr_alpha * adv).clamp(max=model.awr_max_weight)
    means, _ = model.predict_actions(emb, goal)
    log_std = model._clamped_log_stds()
    nll = log_std + 0.5 * (_action(batch, h) - means).square() / torch.exp(2 * log_std)
    return {"actor_loss": (weight * nll).mean(), "adv_mean": adv.mean(), "awr_weight_mean": weight.mean()}


def gcbc_loss(model: GCRL, batch: dict) -> dict:
    """Behaviour cloning of the data action blocks given the frames and the goal."""
    h = _frames(model, batch, 0)
    info = _encode(model, batch, GOAL_PIXELS)
    means, _ = model.predict_actions(info["embed"][:, :h], info["goal_embed"])
    action_loss = F.mse_loss(means, _action(batch, h))
    return {"loss": action_loss, "action_loss": action_loss, "emb": info["pixels_embed"]}


def _td_inputs(model: GCRL, batch: dict):
    """What both value-based losses start from: ``(h, info, obs, next obs, goal)`` embeddings, targets updated."""
    h = _frames(model, batch, 1)
    _update_targets(model)
    info = _encode(model, batch, GOAL_PIXELS)
    emb, goal = info["embed"], info["goal_embed"].flatten(1, 2)
    return h, info, emb[:, :h].flatten(1, 2), emb[:, 1 : h + 1].flatten(1, 2), goal


def gcivl_loss(model: GCRL, batch: dict) -> dict:
    """Implicit V-learning (expectile TD on V alone) plus the advantage-weighted actor."""
    h, info, obs, nxt, goal = _td_inputs(model, batch)
    value = _student(model.value_predictor)(obs, goal)
    with torch.no_grad():
        mask = _not_at_goal(model, batch, h)
        target = -mask + model.discount * mask * _teacher(model.value_predictor)(nxt, goal)
    value_loss = ExpectileLoss(model.expectile)(value, target)

    def advantage(g: torch.Tensor) -> torch.Tensor:
        head = _student(model.value_predictor)
        return head(nxt.detach(), g) - head(obs.detach(), g)

    actor = _actor(model, batch, info, h, advantage)
    loss = value_loss + actor["actor_loss"]
    return {
        "loss": loss,
        "value_loss": value_loss,
        **actor,
        "v_mean": value.detach().mean(),
        "emb": info["pixels_embed"],
    }


def gciql_loss(model: GCRL, batch: dict) -> dict:
    """Implicit Q-learning (expectile V towards the target critic, TD critic) plus the advantage-weighted actor."""
    h, info, obs, nxt, goal = _td_inputs(model, batch)
    action = _action(batch, h)
    value = _student(model.value_predictor)(obs, goal)
    with torch.no_grad():
        q_target_net = _teacher(model.critic_predictor)(obs, action, goal)
        mask = _not_at_goal(model, batch, h)
        td_target = -mask + model.discount * mask * _teacher(model.value_predictor)(nxt, goal)
    value_loss = ExpectileLoss(model.expectile)(value, q_target_net)
    critic_loss = F.mse_loss(_student(model.critic_predictor)(obs, action, goal), td_target)

    def advantage(g: torch.Tensor) -> torch.Tensor:
        o = obs.detach()
        return _teacher(model.critic_predictor)(o, action, g) - _student(model.value_predictor)(o, g)

    actor = _actor(model, batch, info, h, advantage)
    loss = value_loss + critic_loss + actor["actor_loss"]
    return {
        "loss": loss,
        "value_loss": value_loss,
        "critic_loss": critic_loss,
        **actor,
        "v_mean": value.detach().mean(),
        "emb": info["pixels_embed"],
    }


LOSSES: dict[str, Callable[[Any, dict], dict]] = {"gcbc": gcbc_loss, "gcivl": gcivl_loss, "gciql": gciql_loss}

"""A ready-to-act policy from a trained goal-conditioned checkpoint (``swm eval --policy gc:RUN``).

``goal_conditioned_policy("tr-gcbc")`` loads ``checkpoints/tr-gcbc`` as ``wm:RUN`` does
(:func:`~stable_worldmodel.wm.utils.load_checkpoint`: weights, ``config.json``, our
``protocol.json``) and wires what the run recorded into a
:class:`~stable_worldmodel.policy.FeedForwardPolicy`: the image preprocessing of ``pixels``
and ``goal``, and the action normalizer (``inverse_transform`` of the model's actions). The
model must act through ``get_action(info) -> (B, A)`` (``GCRL``, 0.0.3's ``GCBC``). A model
trained on action blocks (``frameskip`` k > 1) acts with the first action of its block and
sees the next frame before acting again. Upstream checkpoints (no ``protocol.json``) act on
224x224 images with ImageNet statistics and no action normalizer.
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np
import torch
from torch import nn

from .. import keys
from ..errors import ConfigError
from ..policy import FeedForwardPolicy

__all__ = ["GoalConditionedPolicy", "goal_conditioned_policy"]


class _FirstAction(nn.Module):
    """``model`` acting with the first ``action_dim`` numbers of its ``(B, k * A)`` action blocks."""

    def __init__(self, model: nn.Module, action_dim: int):
        super().__init__()
        self.model, self.action_dim = model, int(action_dim)

    def get_action(self, info: dict) -> torch.Tensor:
        return self.model.get_action(info)[:, : self.action_dim]


class GoalConditionedPolicy(FeedForwardPolicy):
    """:class:`~stable_worldmodel.policy.FeedForwardPolicy` whose actions are clipped to the
    env's Box bounds and cast to its dtype (a regression head can ask for more than the env takes)."""

    def __init__(self, model: Any, process: dict | None = None, transform: dict | None = None, **kwargs: Any):
        super().__init__(model, process=process, transform=transform, **kwargs)
        self.type = "goal_conditioned"

    def get_action(self, info_dict: dict, **kwargs: Any) -> np.ndarray:
        action = super().get_action(info_dict, **kwargs)
        space = self._require_env().action_space
        if isinstance(space, gym.spaces.Box) and action.shape == space.shape:
            action = np.clip(action, space.low, space.high).astype(space.dtype, copy=False)
        return action


def load_run(
    run: str, method: str, expects: str, other_prefix: str, device: str = "auto", cache_dir: str | None = None
):
    """``(model in eval mode on its device, protocol, device, process, transform)`` of checkpoint ``run``.

    ``model`` must have ``method`` (``get_cost`` for ``wm:``, ``get_action`` for ``gc:``), else a
    ConfigError pointing at ``other_prefix``. ``process`` holds the run's action normalizer,
    ``transform`` its image preprocessing of ``pixels`` and ``goal``, as recorded in
    ``protocol.json`` (upstream checkpoints: 224x224 images with ImageNet statistics).
    """
    from .._device import resolve_device
    from ..wm.preprocess import ImageTransform, Normalizer
    from ..wm.run import Run

    dev = resolve_device(device, who="Planning")
    opened = Run.open(run, cache_dir)
    run = opened.name
    model, protocol = opened.load_model(), opened.protocol.to_dict()
    if not callable(getattr(model, method, None)) and opened.protocol.model == "frame":
        from ..wm.frame.config import decoder_usage

        raise ConfigError(
            f"{'gc' if other_prefix == 'wm' else 'wm'}:{run} requires {expects}, got a frame decoder (it shows what "
            f"another run predicts; it neither plans nor acts); use it as: {decoder_usage(run)}"
        )
    if not callable(getattr(model, method, None)):
        raise ConfigError(
            f"{'gc' if other_prefix == 'wm' else 'wm'}:{run} requires {expects}, got a {type(model).__name__}; "
            f"use --policy {other_prefix}:{run} instead"
        )
    model = model.to(dev).eval()
    process = {}
    for key, norm in protocol.get("normalizers", {}).items():  # action, and proprio for models trained on it
        process[key] = Normalizer.from_dict(norm)
    typed = opened.protocol  # an upstream checkpoint (no protocol.json): 224 px, ImageNet statistics
    images = ImageTransform(typed.image_mean, typed.image_std, typed.image_size)
    return model, protocol, dev, process, {keys.PIXELS: images, keys.GOAL: images}


def goal_conditioned_policy(
    run: str, *, device: str = "auto", cache_dir: str | None = None
) -> tuple[GoalConditionedPolicy, dict[str, Any]]:
    """``(policy, protocol)`` for checkpoint ``run``; give the World ``protocol["history_size"]`` frames."""
    model, protocol, dev, process, transform = load_run(
        run, "get_action", "a goal-conditioned policy checkpoint (gcbc, gcivl, gciql)", "wm", device, cache_dir
    )
    block, action_dim = int(protocol.get("frameskip", 1)), protocol.get("action_dim")
    if block > 1 and action_dim:
        model = _FirstAction(model, int(action_dim))
    policy = GoalConditionedPolicy(model, process=process, transform=transform)
    history = int(protocol.get("history_size", getattr(model, "history_size", 1)))
    return policy, {**protocol, "device": str(dev), "history_size": history, "action_block": block}

"""``encode`` of the goal-conditioned policies, shared by ``GCRL`` (0.1.1) and ``GCBC`` (0.0.3).

A subclass gives its image encoder (:meth:`GoalImageEncoding._image_encoder`), an
``extra_encoders`` module dict and ``interpolate_pos_encoding``.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import torch
from torch import nn

from ... import keys
from ...errors import CheckpointError, ConfigError, SpaceError, UnknownNameError

__all__ = ["GoalImageEncoding", "require"]


def require(info: Mapping[str, Any], key: str, who: str) -> Any:
    """``info[key]``, or an :class:`~stable_worldmodel.errors.UnknownNameError` naming what is there."""
    if key not in info:
        raise UnknownNameError(f"{who} requires info[{key!r}], got keys {sorted(info)}")
    return info[key]


class GoalImageEncoding:
    """Frames (and extra inputs) to tokens ``(B, T, P, d)``."""

    extra_encoders: nn.ModuleDict
    interpolate_pos_encoding: bool
    #: 0.0.3's GCBC stops the gradient at the encoder output (a frozen backbone)
    detach_embeddings = False
    #: the state-dict prefix of this class's action head, and the other family's: its prefix and
    #: what it is (two classes answer to "gcbc": see :meth:`load_state_dict`)
    head_prefix = ""
    other_family: tuple[str, str] = ("", "")

    def load_state_dict(self, state_dict: Mapping[str, Any], strict: bool = True, assign: bool = False):
        """``nn.Module.load_state_dict``, with a :class:`~stable_worldmodel.errors.CheckpointError`
        naming the right class when ``state_dict`` holds the other goal-conditioned family's
        weights (0.0.3's ``GCBC`` and 0.1.1's ``GCRL``, which ``make("gcbc")`` builds), instead of
        torch's list of missing and unexpected keys."""
        prefix, what = self.other_family
        names = list(state_dict)
        if (
            prefix
            and any(k.startswith(prefix) for k in names)
            and not any(k.startswith(self.head_prefix) for k in names)
        ):
            raise CheckpointError(
                f"{type(self).__name__}.load_state_dict requires {type(self).__name__} weights "
                f"({self.head_prefix}*), got the weights of {what}"
            )
        return super().load_state_dict(state_dict, strict=strict, assign=assign)

    def _image_encoder(self) -> nn.Module:  # pragma: no cover - abstract
        raise NotImplementedError("_image_encoder() -> the module that embeds (N, C, h, w) images")

    def encode(
        self,
        info: dict,
        pixels_key: str = keys.PIXELS,
        emb_keys: Any = None,
        prefix: str | None = None,
        target: str = "embed",
        is_video: bool = False,
    ) -> dict:
        """Add ``info[target]: (B, T, P, d')``: the embeddings of ``info[pixels_key] (B, T, C, h, w)``
        (also as ``pixels_<target>``), each extra encoder's ``<key>_<target> (B, T, e)`` of
        ``info[<prefix><key>]`` tiled over the P tokens and concatenated (``d' = d + sum e``).
        ``emb_keys`` (default, or when empty: every extra encoder) picks the extra encoders.
        Returns the same dict."""
        who = f"{type(self).__name__}.encode"
        if target in info:
            raise ConfigError(f"{who} would overwrite info[{target!r}]; give a dict without it or another target")
        emb_keys = list(emb_keys or self.extra_encoders.keys())
        prefix = prefix or ""
        pixels = require(info, pixels_key, who)
        if pixels.ndim != 5:
            raise SpaceError(f"{who} requires info[{pixels_key!r}] of shape (B, T, C, h, w), got {tuple(pixels.shape)}")
        embed = (self._encode_video if is_video else self._encode_image)(pixels.float())
        info[f"pixels_{target}"] = embed
        parts = [embed]
        for key in emb_keys:
            if key not in self.extra_encoders:
                raise UnknownNameError(f"{who} has no extra encoder {key!r}; it has {sorted(self.extra_encoders)}")
            extra = self.extra_encoders[key](require(info, f"{prefix}{key}", who).float())  # (B, T, e)
            info[f"{key}_{target}"] = extra
            parts.append(extra.unsqueeze(2).expand(-1, -1, embed.shape[2], -1))
        info[target] = torch.cat(parts, dim=3) if len(parts) > 1 else embed
        return info

    def _encoder_kwargs(self) -> dict[str, Any]:
        return {"interpolate_pos_encoding": True} if self.interpolate_pos_encoding else {}

    def _encode_image(self, pixels: torch.Tensor) -> torch.Tensor:
        """``(B, T, C, h, w) -> (B, T, P, d)``: a ``last_hidden_state`` without its first (CLS)
        token, or ``.logits`` as one token."""
        b, t = pixels.shape[:2]
        out = self._image_encoder()(pixels.reshape(b * t, *pixels.shape[2:]), **self._encoder_kwargs())
        hidden = getattr(out, "last_hidden_state", None)
        tokens = hidden[:, 1:] if hidden is not None else out.logits.unsqueeze(1)
        tokens = tokens.reshape(b, t, *tokens.shape[1:])
        return tokens.detach() if self.detach_embeddings else tokens

    def _encode_video(self, pixels: torch.Tensor) -> torch.Tensor:
        """A video encoder over ``(B, T, C, h, w)``: output ``t`` sees frames ``<= t``,
        the last one repeated to length T."""
        t = pixels.shape[1]
        outs = []
        for k in range(t):
            frames = torch.cat([pixels[:, : k + 1], pixels[:, k : k + 1].expand(-1, t - k - 1, -1, -1, -1)], dim=1)
            outs.append(self._image_encoder()(frames, **self._encoder_kwargs()).last_hidden_state)
        return torch.stack(outs, dim=1)

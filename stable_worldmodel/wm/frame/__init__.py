"""``wm.frame``: a pixel decoder trained on the frozen latents of another run, to look at what a
world model predicts (``swm train frame --from RUN``; ``swm eval --video`` shows its frames).

Classes resolve lazily, so importing this package imports no torch.
"""

from __future__ import annotations

from ..._lazy import lazy_getattr

__all__ = ["FrameConfig", "FrameDecoder", "FrameModel", "PredictionPanel"]
_WHERE = {"FrameConfig": ".config", "FrameDecoder": ".module", "FrameModel": ".module", "PredictionPanel": ".module"}

__getattr__ = lazy_getattr(__name__, _WHERE)

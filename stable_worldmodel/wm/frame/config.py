"""The frame decoder's light config (no torch import): it takes its image protocol from the
source run it decodes (``source``, a checkpoint of ``$STABLEWM_HOME/checkpoints``)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, ClassVar

from ...errors import ConfigError
from ..base import WorldModelConfig

__all__ = ["FrameConfig"]


def decoder_usage(run: str, source: str | None = None) -> str:
    """How a frame decoder run is used (it decodes another run's latents; it neither plans nor acts)."""
    if source is None:
        source = run[: -len("-frame")] if run.endswith("-frame") else "SOURCE"
    return f"swm eval ENV --policy wm:{source} --video DIR --decoder {run}"


@dataclass
class FrameConfig(WorldModelConfig):
    """``source`` (the run whose frozen encoder's latents are decoded; required) and ``width``
    (channels of the decoder's last upsampling stage; earlier stages double it, up to 8x).

    The image size, normalization and embedding width come from the source run's
    ``protocol.json``; the decoder is trained on single frames (``history_size`` 1), so the
    source model's other settings play no part. Presets: ``tiny`` (width 16, 1000 steps: a
    CPU in a minute or two), ``small`` (width 32, 5000 steps) and ``paper`` (width 64, 20000 steps).
    """

    model_name: ClassVar[str] = "frame"
    target: ClassVar[str] = "stable_worldmodel.wm.frame.FrameModel"
    presets: ClassVar[dict[str, dict[str, Any]]] = {
        "tiny": {"width": 16, "steps": 1000},
        "small": {"width": 32, "steps": 5000, "batch_size": 128},
        "paper": {"width": 64, "steps": 20000, "batch_size": 128, "lr": 3e-4},
    }

    FIELD_HELP: ClassVar[dict[str, str]] = {
        "source": "The run whose latents the decoder learns to turn into frames (required: --from RUN).",
        "width": "Channels of the decoder's last upsampling stage (earlier stages double it, up to 8x).",
        "embed_dim": "The source run's embedding width (read from its protocol.json; not set by hand).",
        "image_size": "Side of the frames, in pixels (read from the source run's protocol.json).",
        "image_mean": "Per-channel mean of the pixels (read from the source run's protocol.json).",
        "image_std": "Per-channel scale of the pixels (read from the source run's protocol.json).",
    }

    source: str = ""
    width: int = 16
    #: the source run's embedding width (set from its protocol, not by the user)
    embed_dim: int = 0
    history_size: int = 1
    num_preds: int = 1
    frameskip: int = 1

    def __post_init__(self) -> None:
        from ..run import Run

        if not isinstance(self.source, str) or not self.source:
            raise ConfigError(
                "FrameConfig requires source, the run whose latents it decodes (swm train frame --from RUN)"
            )
        if isinstance(self.width, bool) or not isinstance(self.width, int) or self.width < 1:
            raise ConfigError(f"FrameConfig requires width to be a positive int, got {self.width!r}")
        run = Run.open(self.source)
        weights, protocol = run.weights, run.protocol.raw
        source_cfg = protocol.get("config") or {}
        if "embed_dim" not in source_cfg or "image_size" not in protocol:
            raise ConfigError(
                "FrameConfig requires a source run trained here (a protocol.json with its config), "
                f"got {weights.parent}"
            )
        self.image_size = int(protocol["image_size"])
        self.image_mean = tuple(protocol.get("image_mean", self.image_mean))
        self.image_std = tuple(protocol.get("image_std", self.image_std))
        self.embed_dim = int(source_cfg["embed_dim"])
        self._source_weights = weights
        self._source_protocol = protocol
        super().__post_init__()

    @property
    def default_run(self) -> str:
        """The run name when none is given: ``<source>-frame`` (what ``swm eval --video`` looks for)."""
        return f"{self.source}-frame"

    @property
    def source_dataset(self) -> str | None:
        """The dataset the source run was trained on (the default of ``swm train frame``)."""
        return self._source_protocol.get("dataset")

    def target_tree(self, action_dim: int) -> dict[str, Any]:
        from ..trust import resolve_targets
        from ..utils import CONFIG_NAME, TARGET_ALIASES, _read_json

        source_path = self._source_weights.parent / CONFIG_NAME
        source_tree = _read_json(source_path, "the source run's model config")
        resolve_targets(source_tree, source=source_path, aliases=TARGET_ALIASES)  # refused before anything is built
        return {
            "_target_": self.target,
            "world_model": source_tree,
            "decoder": {
                "_target_": "stable_worldmodel.wm.frame.FrameDecoder",
                "embed_dim": self.embed_dim,
                "image_size": self.image_size,
                "channels": len(self.image_mean),
                "width": self.width,
            },
        }

    def prepare_model(self, model: Any) -> None:
        """Load the source run's weights into ``model.world_model`` (called by the trainer)."""
        from ..utils import _read_weights

        # checked as every load is: the sha256 the run recorded, no pickle, no NaN/inf
        model.world_model.load_state_dict(_read_weights(self._source_weights, self._source_protocol))

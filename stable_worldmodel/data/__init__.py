"""Datasets: recording, loading and managing them.

Importing this package is cheap: h5py and torch are imported only when a dataset
class or a function that needs them is first used (PEP 562 lazy attributes).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from .._lazy import lazy_getattr
from .utils import get_cache_dir

_ATTRS: dict[str, str] = {
    # name -> submodule that defines it
    "Dataset": "dataset",
    "HDF5Dataset": "hdf5",
    "HDF5Writer": "writer",
    "FolderDataset": "folder",
    "ImageDataset": "folder",
    "write_folder_dataset": "folder",
    "VideoDataset": "video_dataset",
    "write_video_dataset": "video_dataset",
    "MergeDataset": "compose",
    "ConcatDataset": "compose",
    "GoalDataset": "compose",
    "SpaceInfo": "info",
    "VariationInfo": "info",
    "WorldInfo": "info",
    "dataset_info": "info",
    "list_datasets": "info",
    "delete_dataset": "info",
    "list_models": "info",
    "delete_model": "info",
    "world_info": "info",
    "list_worlds": "info",
    "is_image": "info",
    "repair": "_superblock",
    "record_video_from_dataset": "video",
    "load_dataset": "utils",
    "ReplayBuffer": "buffer",
    "LeRobotAdapter": "lerobot",
    "LanceDataset": "lance",
    "LanceWriter": "lance",
    "LanceVideoDataset": "lance_video",
    "LanceVideoWriter": "lance_video",
    "classic_filter": "buffer",
    "resolve_dataset": "utils",
    "column_normalizer": "utils",
    "convert": "utils",
    "FolderWriter": "folder",
    "VideoWriter": "video_dataset",
    "FORMATS": "format",
    "Format": "format",
    "register_format": "format",
    "get_format": "format",
    "detect_format": "format",
    "list_formats": "format",
    "IdentityScaler": "normalization",
    "ZScoreScaler": "normalization",
    "PercentileScaler": "normalization",
    "get_scaler": "normalization",
}

__all__ = ["get_cache_dir", *_ATTRS]


__getattr__ = lazy_getattr(__name__, {name: f".{module}" for name, module in _ATTRS.items()})


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))


if TYPE_CHECKING:  # pragma: no cover
    from ._superblock import repair  # noqa: F401
    from .buffer import ReplayBuffer, classic_filter  # noqa: F401
    from .compose import ConcatDataset, GoalDataset, MergeDataset  # noqa: F401
    from .dataset import Dataset  # noqa: F401
    from .folder import FolderDataset, FolderWriter, ImageDataset, write_folder_dataset  # noqa: F401
    from .format import FORMATS, Format, detect_format, get_format, list_formats, register_format  # noqa: F401
    from .hdf5 import HDF5Dataset  # noqa: F401
    from .info import (  # noqa: F401
        SpaceInfo,
        VariationInfo,
        WorldInfo,
        dataset_info,
        delete_dataset,
        delete_model,
        is_image,
        list_datasets,
        list_models,
        list_worlds,
        world_info,
    )
    from .lance import LanceDataset, LanceWriter  # noqa: F401
    from .lance_video import LanceVideoDataset, LanceVideoWriter  # noqa: F401
    from .lerobot import LeRobotAdapter  # noqa: F401
    from .normalization import IdentityScaler, PercentileScaler, ZScoreScaler, get_scaler  # noqa: F401
    from .utils import column_normalizer, load_dataset, resolve_dataset  # noqa: F401
    from .video import record_video_from_dataset  # noqa: F401
    from .video_dataset import VideoDataset, VideoWriter, write_video_dataset  # noqa: F401
    from .writer import HDF5Writer  # noqa: F401

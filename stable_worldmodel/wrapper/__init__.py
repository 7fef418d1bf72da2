"""Wrappers that turn any Gymnasium env into a World-ready one (seed name: ``wrappers``)."""

from .checks import EnsureGoalInfoWrapper, EnsureImageShape, EnsureInfoKeysWrapper
from .goal import ResizeGoalWrapper
from .info import EverythingToInfoWrapper, InfoKeyCollisionError, UnsupportedActionSpaceError
from .keys import MapKeysWrapper
from .mega import MegaWrapper
from .pixels import AddPixelsWrapper, SupportsMultiview
from .stack import StackedWrapper
from .variation import VariationWrapper
from .visual import (
    BlurWrapper,
    ChromaKeyWrapper,
    ColorJitterWrapper,
    CutoutWrapper,
    GrayscaleWrapper,
    MovingPatchWrapper,
    NoiseWrapper,
    OcclusionWrapper,
    RandomConvWrapper,
    RandomShiftWrapper,
    ResolutionWrapper,
    constant,
    cosine,
    exponential,
    linear,
    sinusoidal,
)

__all__ = [
    "AddPixelsWrapper",
    "BlurWrapper",
    "ChromaKeyWrapper",
    "ColorJitterWrapper",
    "CutoutWrapper",
    "EnsureGoalInfoWrapper",
    "EnsureImageShape",
    "EnsureInfoKeysWrapper",
    "EverythingToInfoWrapper",
    "GrayscaleWrapper",
    "InfoKeyCollisionError",
    "MapKeysWrapper",
    "MegaWrapper",
    "MovingPatchWrapper",
    "NoiseWrapper",
    "OcclusionWrapper",
    "RandomConvWrapper",
    "RandomShiftWrapper",
    "ResizeGoalWrapper",
    "ResolutionWrapper",
    "StackedWrapper",
    "SupportsMultiview",
    "UnsupportedActionSpaceError",
    "VariationWrapper",
    "constant",
    "cosine",
    "exponential",
    "linear",
    "sinusoidal",
]

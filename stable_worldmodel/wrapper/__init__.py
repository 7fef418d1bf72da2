"""Wrappers that turn any Gymnasium env into a World-ready one (seed name: ``wrappers``)."""

from .checks import EnsureGoalInfoWrapper, EnsureImageShape, EnsureInfoKeysWrapper
from .goal import ResizeGoalWrapper
from .info import EverythingToInfoWrapper, InfoKeyCollisionError, UnsupportedActionSpaceError
from .mega import MegaWrapper
from .pixels import AddPixelsWrapper, SupportsMultiview
from .stack import StackedWrapper
from .variation import VariationWrapper

__all__ = [
    "AddPixelsWrapper",
    "EnsureGoalInfoWrapper",
    "EnsureImageShape",
    "EnsureInfoKeysWrapper",
    "EverythingToInfoWrapper",
    "InfoKeyCollisionError",
    "MegaWrapper",
    "ResizeGoalWrapper",
    "StackedWrapper",
    "SupportsMultiview",
    "UnsupportedActionSpaceError",
    "VariationWrapper",
]

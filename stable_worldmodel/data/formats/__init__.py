"""The built-in dataset formats, registered on import (each module is light: readers and
writers are imported when a format opens one). Detection order: this import order."""

from . import hdf5, video, folder, meta  # noqa: F401  (order matters: video folders are folders too)

"""The built-in dataset formats, registered on import (each module is light: readers and
writers are imported when a format opens one). Detection order: this import order."""

# Detection tries the formats in this order, and video folders are folders too: not sorted.
# isort: off
from . import hdf5  # noqa: F401 (imported to register the format)
from . import video  # noqa: F401 (imported to register the format)
from . import folder  # noqa: F401 (imported to register the format)
from . import meta  # noqa: F401 (imported to register the format)
from . import lance_video  # noqa: F401 (imported to register the format)
from . import lance  # noqa: F401 (imported to register the format)
from . import lerobot  # noqa: F401 (imported to register the format)

# isort: on

"""Command-line interface for stable-worldmodel (``swm``, ``stable-worldmodel``, ``python -m stable_worldmodel.cli``).

Commands:

- ``swm list {model|dataset|world}``: cached models / datasets, registered worlds.
- ``swm show {model|dataset|world} [NAMES...] [--all]``: panels with files, parameters and protocol of
  checkpoints, columns, counts and shapes of datasets, spaces and factors of worlds.
- ``swm delete {model|dataset} NAMES... [--yes]``: remove cached resources (asks first).
- ``swm collect ENV``: record an HDF5 dataset; ``swm eval ENV``: success rate with a 95% interval
  (``--policy wm:RUN`` plans with a trained world model).
- ``swm train MODEL --dataset NAME``: train a world model (checkpoint in ``$STABLEWM_HOME/checkpoints``).
- ``swm envs`` / ``swm fovs ENV``: environments and their factors of variation.
- ``swm demo``: collect, train a tiny LeWM, evaluate random / expert / LeWM+CEM, videos and a plot.
- ``swm --version``.

Bad input exits non-zero with one ``Error: ...`` line (``SWM_DEBUG=1`` shows the traceback).
"""

from __future__ import annotations

from .display import display_dataset_info, display_world_info
from .resources import delete, list_cmd, show
from .root import app, common, main

__all__ = ["app", "common", "delete", "display_dataset_info", "display_world_info", "list_cmd", "main", "show"]

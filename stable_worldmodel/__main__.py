"""``python -m stable_worldmodel ...`` is the ``swm`` command."""

from .cli import main

raise SystemExit(main())

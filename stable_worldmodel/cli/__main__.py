"""``python -m stable_worldmodel.cli``."""

from __future__ import annotations

from . import main

raise SystemExit(main())

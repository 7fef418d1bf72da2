"""Command-line interface (``swm``). The full command set arrives with the CLI issue."""

from __future__ import annotations

import sys


def main(argv: list[str] | None = None) -> int:
    from . import __version__

    args = sys.argv[1:] if argv is None else argv
    if args in (["--version"], ["-V"]):
        sys.stdout.write(f"stable-worldmodel {__version__}\n")
        return 0
    sys.stdout.write(f"stable-worldmodel {__version__}: commands are not implemented yet (try --version)\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

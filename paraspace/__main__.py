"""``python -m paraspace``: the command-line interface (``paraspace --help``), the same as the
installed ``paraspace`` command."""

from __future__ import annotations

from paraspace.app.cli import main

if __name__ == "__main__":
    raise SystemExit(main())

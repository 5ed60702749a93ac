"""Progress of long command-line work, as one updating line on stderr.

:func:`progress_line` returns a ``progress(fraction, message)`` callback (the core's
``kinematics.progress`` convention) that redraws ``\\r[####......]  42 %  message`` on stderr, at
most every 0.1 s, and a ``close()`` that ends the line. It draws only when stderr is a terminal:
piped or redirected stderr, and therefore CI logs, stay clean, and stdout (where ``--json``
writes) is never touched.
"""

from __future__ import annotations

import sys
import time
from collections.abc import Callable
from typing import TextIO

__all__ = ["progress_line"]

WIDTH = 24


def progress_line(label: str, stream: TextIO | None = None, *,
                  force: bool = False) -> tuple[Callable[[float, str], None] | None, Callable[[], None]]:
    """``(progress, close)`` for a task named ``label``; ``progress`` is ``None`` (nothing drawn)
    unless ``stream`` (default stderr) is a terminal or ``force`` is set."""
    out = sys.stderr if stream is None else stream
    isatty = getattr(out, "isatty", None)
    if not force and not (callable(isatty) and isatty()):
        return None, lambda: None
    state = {"last": 0.0, "drawn": False}

    def progress(fraction: float, message: str = "") -> None:
        now = time.monotonic()
        if now - state["last"] < 0.1 and fraction < 1.0:
            return
        state["last"] = now
        f = min(1.0, max(0.0, float(fraction)))
        bar = "#" * int(round(f * WIDTH))
        text = f"\r{label} [{bar:<{WIDTH}}] {100 * f:3.0f} %  {message[:60]:<60}"
        out.write(text)
        out.flush()
        state["drawn"] = True

    def close() -> None:
        if state["drawn"]:
            out.write("\r" + " " * (len(label) + WIDTH + 72) + "\r")
            out.flush()

    return progress, close

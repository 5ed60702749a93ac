"""Progress of long command-line work: one tqdm bar on stderr, for every command.

:func:`progress_line` returns a ``progress(fraction, message)`` callback (the core's
``kinematics.progress`` convention) that moves a tqdm bar ``label [#####.....]  42 %, message`` on
stderr (redrawn at most every 0.1 s), and a ``close()`` that draws the last state and clears it.
It draws only when stderr is a terminal, or when asked to (``force``, e.g. ``paraspace optimize --progress``): piped or
redirected stderr, and therefore CI logs, stay clean, and stdout (where ``--json`` writes) is never
touched.
"""

from __future__ import annotations

import contextlib
import sys
from collections.abc import Callable, Iterator
from typing import TextIO

from tqdm import tqdm

__all__ = ["progress_line", "progress_scope"]

WIDTH = 24
#: per mille: the bar counts 0..1000 so that fractions of a percent still move it
_STEPS = 1000
#: Most characters of the message beside the bar.
MESSAGE_CHARS = 60


def _short(message: str, most: int = MESSAGE_CHARS) -> str:
    """``message`` as drawn beside the bar: whole when it fits in ``most`` characters, else cut at the
    last space that leaves room for ``...`` (mid-word only when there is none), so a cut never reads
    as a different word ("432 blocks test")."""
    if len(message) <= most:
        return message
    head = message[:most - 3]
    cut = head.rfind(" ")
    return (head[:cut] if cut > 0 else head).rstrip(" ,;:(") + "..."


def progress_line(label: str, stream: TextIO | None = None, *,
                  force: bool = False) -> tuple[Callable[[float, str], None] | None, Callable[[], None]]:
    """``(progress, close)`` for a task named ``label``; ``progress`` is ``None`` (nothing drawn)
    unless ``stream`` (default stderr) is a terminal or ``force`` is set."""
    out = sys.stderr if stream is None else stream
    isatty = getattr(out, "isatty", None)
    if not force and not (callable(isatty) and isatty()):
        return None, lambda: None
    bars: list[tqdm] = []  # created at the first report, so that the first report is drawn

    def progress(fraction: float, message: str = "") -> None:
        n = round(min(1.0, max(0.0, float(fraction))) * _STEPS)
        if not bars:
            bars.append(tqdm(total=_STEPS, initial=n, desc=label, postfix=_short(message), file=out, leave=False,
                             mininterval=0.1, ascii=" #",
                             bar_format="{desc} [{bar:" + str(WIDTH) + "}] {percentage:3.0f} %{postfix}"))
            return
        bars[0].set_postfix_str(_short(message), refresh=False)
        bars[0].update(n - bars[0].n)

    def close() -> None:
        if bars:
            bars[0].refresh()  # the last state, even when it came within 0.1 s of the one drawn before
            bars[0].close()

    return progress, close


@contextlib.contextmanager
def progress_scope(label: str, stream: TextIO | None = None, *,
                   force: bool = False) -> Iterator[Callable[[float, str], None] | None]:
    """``with progress_scope(label) as progress:``: :func:`progress_line`'s callback, its bar cleared
    when the block ends, normally or by an exception."""
    progress, close = progress_line(label, stream, force=force)
    try:
        yield progress
    finally:
        close()

"""Numbers as the explorer and the command line print them.

:func:`fixed` writes a fixed number of decimals and never a negative zero: a value that rounds to
zero prints as ``0.000``, not ``-0.000`` (a carriage at ``eta = -1e-15`` is at zero, and a minus
sign there only makes a reader look twice).
"""

from __future__ import annotations

__all__ = ["fixed"]


def fixed(value: float, decimals: int = 2, width: int = 0) -> str:
    """``value`` with ``decimals`` decimals (right-aligned in ``width``), without ``-0``."""
    text = f"{float(value):.{decimals}f}"
    if text.startswith("-") and float(text) == 0.0:
        text = text[1:]
    return text.rjust(width)

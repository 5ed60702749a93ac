"""Numbers as the explorer and the command line print them.

:func:`significant` writes ``digits`` significant digits, in plain notation with thousands
separators between 0.001 and one million (``29,400``, ``0.402``) and in scientific notation
outside (``5.120e+06``), so one panel never mixes ``13579.3`` with ``2.94e+04``. Trailing zeros are
kept (``0.4020``, ``5.120e+06``): a value and its bracket written to the same digits read alike
(``5.120e+06`` beside ``4.905e+06``, never ``5.12e+06``).

:func:`fixed` writes a fixed number of decimals and never a negative zero: a value that rounds to
zero prints as ``0.000``, not ``-0.000`` (a carriage at ``eta = -1e-15`` is at zero, and a minus
sign there only makes a reader look twice).

:func:`format_number` writes the shortest text that parses back to exactly the value (links and
files: what is shared is what is computed).
"""

from __future__ import annotations

__all__ = ["fixed", "format_number", "significant"]


def format_number(value: float) -> str:
    """Shortest text that parses back to exactly ``value`` (``60.0 -> "60"``, ``0.1 -> "0.1"``)."""
    v = float(value)
    if v == 0.0:
        return "0"  # also for -0.0
    text = repr(v)
    if text.endswith(".0"):
        text = text[:-2]
    return text


def fixed(value: float, decimals: int = 2, width: int = 0) -> str:
    """``value`` with ``decimals`` decimals (right-aligned in ``width``), without ``-0``."""
    text = f"{float(value):.{decimals}f}"
    if text.startswith("-") and float(text) == 0.0:
        text = text[1:]
    return text.rjust(width)


def significant(value: float, digits: int = 4) -> str:
    """``value`` to ``digits`` significant digits (see the module docstring)."""
    import math

    v = float(value)
    if v == 0.0 or not math.isfinite(v):
        return "0" if v == 0.0 else str(v)
    r = float(f"{v:.{digits}g}")  # rounded first: 999,999.7 reads 1.000e+06, not 1,000,000
    if not 1e-3 <= abs(r) < 1e6:
        return f"{v:#.{digits}g}"
    decimals = max(0, digits - 1 - math.floor(math.log10(abs(r))))
    return f"{r:,.{decimals}f}"

"""Sliders whose number box accepts values beyond the track keep what was typed.

A slider's track spans its usual range (Table I's for a design parameter), while its number box
accepts the whole valid range (a = 120, a cone of 80 degrees). The browser's box (Mantine's
NumberInput, viser 1.1.1) clamps its value to the track's ends when it loses focus, and sends that end
as a new value: a typed value that had been applied, or refused, became the track's end at the next
click elsewhere, which is a value nobody typed. :func:`hold_typed_values` widens the track as soon as
a value beyond it arrives, so the box has nothing to clamp once the wider track is in the page; the
page's typing gate (:data:`paraspace.app.explorer.pagehook.TYPING_GATE`) keeps the box's blur from
clamping before then.
"""

from __future__ import annotations

from typing import Any

__all__ = ["hold_typed_values"]


def hold_typed_values(handle: Any) -> Any:
    """Widen ``handle``'s track whenever it takes a value beyond it (module docstring), and return
    ``handle``. Call it when the slider is made, so that it runs before the controllers' callbacks:
    a = 120, applied, stays 120 when the box loses focus (it became 100), and a refused d_s = 150
    (d_s <= r = 100) stays refused (it was applied as 100)."""
    def widen(_event: Any = None) -> None:
        v = float(handle.value)
        if not handle.min <= v <= handle.max:
            handle.min, handle.max = min(handle.min, v), max(handle.max, v)
    handle.on_update(widen)
    return handle

"""Progress reporting and cooperative cancellation for long computations.

Every long function of the core takes ``progress`` (a callable ``(fraction, message) -> None``,
fraction in [0, 1]) and ``cancel`` (anything with ``is_set() -> bool``, e.g. a
:class:`threading.Event`, or a zero-argument callable returning bool). It checks ``cancel`` between
chunks of work and raises :class:`Cancelled` when asked to stop.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, Protocol


class Cancelled(Exception):
    """The computation was cancelled by its caller."""


class _HasIsSet(Protocol):
    def is_set(self) -> bool: ...


ProgressFn = Callable[[float, str], None]
CancelToken = _HasIsSet | Callable[[], bool] | None


def is_cancelled(cancel: CancelToken) -> bool:
    """Whether a cancel token asks to stop."""
    if cancel is None:
        return False
    if hasattr(cancel, "is_set"):
        return bool(cancel.is_set())
    return bool(cancel())


def check(cancel: CancelToken) -> None:
    """Raise :class:`Cancelled` if the token is set."""
    if is_cancelled(cancel):
        raise Cancelled()


class Reporter:
    """Maps the progress of a sub-task onto ``[start, stop]`` of a parent's progress."""

    def __init__(self, progress: ProgressFn | None, start: float = 0.0, stop: float = 1.0) -> None:
        self.progress, self.start, self.stop = progress, start, stop

    def __call__(self, fraction: float, message: str = "") -> None:
        if self.progress is not None:
            f = min(1.0, max(0.0, float(fraction)))
            self.progress(self.start + (self.stop - self.start) * f, message)

    def sub(self, start: float, stop: float) -> Reporter:
        span = self.stop - self.start
        return Reporter(self.progress, self.start + span * start, self.start + span * stop)


def noop_progress(fraction: float, message: str = "") -> Any:  # pragma: no cover - trivial
    return None

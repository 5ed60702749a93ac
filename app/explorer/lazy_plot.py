"""A plotly plot that is created when it first has a figure.

Any ``gui.add_plotly`` makes the browser load and evaluate plotly.js (about 1.7 MB on the websocket
and 0.6-2 s of blocked main thread, measured by ``benchmarks/explorer_latency.py``): done at page
load, that lands right when the first workspace shell arrives and delays it. A :class:`LazyPlot`
holds the plot's place in its panel with a one-line markdown placeholder (same container, same
``order``) and adds the real plot at its first figure. It answers the attributes the controllers
and tests use on a plot handle: ``figure``, ``aspect``, ``visible``.

**The page's plot gate** (:class:`PlotGate`, one per page: :func:`hold_plots`). The first figures
come from jobs that end right after the first shell is *sent*, while the browser is still parsing and
drawing it; a plot created then made the browser evaluate plotly.js first and draw the shell after
it (page load -> first shell drawn 4.2 s, plotly.js evaluated at 3.6 s, against 2.9 s without plots;
software WebGL, 2026-12-05). On a page whose gate is held, the plots' first figures wait (each plot
keeps its latest figure) until the gate opens: the gate's ``opener`` runs once, on a thread of its
own, at the first figure that waits (the explorer's waits until the browser has drawn the first
shell, :func:`paraspace.app.explorer.jsbridge.wait_drawn`, bounded in time), and then every waiting
plot is created with its latest figure. A page without a held gate creates its plots at once.

Every plot has an **Open large** button below it: the same figure in a modal window as wide as
the browser allows (:data:`LARGE_ASPECT`; the page widens viser's modals, see
:mod:`app.explorer.pagehook`), with zoom and hover, for reading a plot that the side panel shows
small.
"""

from __future__ import annotations

import logging
import threading
import weakref
from collections.abc import Callable, Mapping
from typing import Any

import viser

log = logging.getLogger(__name__)

#: Height / width of a plot in the "Open large" window (a wide window: a lower plot than in the panel).
LARGE_ASPECT = 0.62


class PlotGate:
    """Holds the creation of one page's plots until it opens (module docstring, *The page's plot
    gate*). ``opener`` runs once, on a daemon thread, when the first creation waits; the gate opens
    when it returns (or raises)."""

    def __init__(self, opener: Callable[[], object]) -> None:
        self._opener = opener
        self._lock = threading.Lock()
        self._open = False
        self._closed = False
        self._started = False
        self._waiting: list[Callable[[], None]] = []
        self.opened = threading.Event()

    def wait_or_run(self, create: Callable[[], None]) -> bool:
        """``create`` later (when the gate opens; ``True``) or not at all here (the gate is open:
        ``False``, the caller creates at once). On a closed gate (the page left) nothing is ever
        created (``True``)."""
        with self._lock:
            if self._closed:
                return True
            if self._open:
                return False
            self._waiting.append(create)
            start = not self._started
            self._started = True
        if start:
            threading.Thread(target=self._run, name="plot-gate", daemon=True).start()
        return True

    def _run(self) -> None:
        try:
            self._opener()
        except Exception:  # noqa: BLE001 - the plots are created anyway
            log.exception("the plot gate's opener failed")
        self.open()

    def open(self) -> None:
        """Open the gate: create every waiting plot (each with its latest figure), and every later one
        at once."""
        with self._lock:
            self._open = True
            waiting, self._waiting = ([] if self._closed else self._waiting), []
        for create in waiting:
            try:
                create()
            except Exception:  # noqa: BLE001 - a page that left meanwhile; the other plots still go
                log.exception("creating a plot after the gate opened failed")
        self.opened.set()


    def close(self) -> None:
        """The page left: no plot of it is created any more (nothing is sent to a closed
        connection); an opener still waiting ends on its own time-out."""
        with self._lock:
            self._closed = True
            self._waiting = []


#: The held gate of each page's GUI (:func:`hold_plots`); a GUI without one creates its plots at once.
#: Both sides weak: the gate's opener refers to the page's client, hence to its GUI, and the plots
#: built on the GUI and the caller keep the gate.
_GATES: weakref.WeakKeyDictionary[Any, weakref.ref[PlotGate]] = weakref.WeakKeyDictionary()


def hold_plots(gui: viser.GuiApi, opener: Callable[[], object]) -> PlotGate:
    """Hold the creation of the plots built on ``gui`` from now on until ``opener`` has run (module
    docstring); returns the gate, which the caller keeps (``open()`` opens it early)."""
    gate = PlotGate(opener)
    _GATES[gui] = weakref.ref(gate)
    return gate


def _gate_of(gui: Any) -> PlotGate | None:
    ref = _GATES.get(gui)
    return None if ref is None else ref()


class LazyPlot:
    """A placeholder for ``gui.add_plotly`` inside ``container`` (module docstring); construct it
    inside ``with container:``, like any element of the panel."""

    def __init__(self, gui: viser.GuiApi, container: Any, text: str = "", *, config: Mapping[str, Any] | None = None,
                 aspect: float = 1.0, visible: bool = True) -> None:
        self._gui = gui
        self._container = container
        self._config = dict(config or {})
        self._aspect = float(aspect)
        self._visible = bool(visible)
        self._figure: Any = None
        self._handle: Any | None = None
        self._lock = threading.Lock()
        self._gate = _gate_of(gui)
        self._waits = False  # a creation is waiting for the gate
        # built inside ``with container:`` (as every element of a panel): the placeholder goes there
        self._placeholder = gui.add_markdown(f"*{text}*" if text else "", visible=self._visible and bool(text))
        self._order = self._placeholder.order
        self.title = ""  # the "Open large" window's title (the figure's own title when empty)
        self.large = gui.add_button("Open large", icon=viser.Icon.ARROWS_MAXIMIZE, disabled=True,
                                    visible=self._visible,
                                    hint="the same plot in a wide window, with zoom and hover read-outs")
        self.large.on_click(lambda _e: self.open_large())

    @property
    def created(self) -> bool:
        """Whether the plotly element exists in the browser yet."""
        return self._handle is not None

    @property
    def figure(self) -> Any:
        """The last figure given (``None`` before the first)."""
        return self._figure

    @figure.setter
    def figure(self, fig: Any) -> None:
        with self._lock:
            self._figure = fig
            if self._handle is not None:
                self._handle.figure = fig
                return
            if self._waits:  # the gate's creation will take this figure
                return
            if self._gate is None or not self._gate.wait_or_run(self._create):
                self._create_locked()
                return
            self._waits = True

    def _create(self) -> None:
        """The plot with the latest figure (the gate opened)."""
        with self._lock:
            self._waits = False
            if self._handle is None and self._figure is not None:
                self._create_locked()

    def _create_locked(self) -> None:
        with self._container:
            self._handle = self._gui.add_plotly(self._figure, config=self._config, aspect=self._aspect,
                                                order=self._order, visible=self._visible)
        self._placeholder.remove()
        self.large.disabled = False

    def open_large(self) -> Any | None:
        """Show the current figure in a wide modal window (with a Close button); returns the modal
        (``None`` before the first figure)."""
        fig = self._figure
        if fig is None:
            return None
        title = self.title
        if not title:
            try:
                title = str(fig.layout.title.text or "").split("<br>")[0]
            except AttributeError:
                title = ""
        modal = self._gui.add_modal(title or "plot")
        with modal:
            self._gui.add_plotly(fig, config=self._config, aspect=min(self._aspect, LARGE_ASPECT))
            self._gui.add_button("Close", icon=viser.Icon.X).on_click(lambda _e: modal.close())
        return modal

    @property
    def aspect(self) -> float:
        return self._aspect

    @aspect.setter
    def aspect(self, value: float) -> None:
        with self._lock:
            self._aspect = float(value)
            if self._handle is not None:
                self._handle.aspect = self._aspect

    @property
    def visible(self) -> bool:
        return self._visible

    @visible.setter
    def visible(self, value: bool) -> None:
        with self._lock:
            self._visible = bool(value)
            self.large.visible = self._visible
            if self._handle is not None:
                self._handle.visible = self._visible
            elif self._placeholder.content:
                self._placeholder.visible = self._visible

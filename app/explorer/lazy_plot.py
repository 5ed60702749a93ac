"""A plotly plot that is created when it first has a figure.

Any ``gui.add_plotly`` makes the browser load and evaluate plotly.js (about 1.7 MB on the websocket
and 0.6-1.1 s of blocked main thread, measured by ``benchmarks/explorer_latency.py``): done at page
load, that lands right when the first workspace shell arrives and delays it. A :class:`LazyPlot`
holds the plot's place in its panel with a one-line markdown placeholder (same container, same
``order``) and adds the real plot at its first figure, so plotly.js arrives after the first shell.
It answers the attributes the controllers and tests use on a plot handle: ``figure``, ``aspect``,
``visible``.

Every plot has an **Open large** button below it: the same figure in a modal window as wide as
the browser allows (:data:`LARGE_ASPECT`; the page widens viser's modals, see
:mod:`app.explorer.pagehook`), with zoom and hover, for reading a plot that the side panel shows
small.
"""

from __future__ import annotations

import threading
from collections.abc import Mapping
from typing import Any

import viser

#: Height / width of a plot in the "Open large" window (a wide window: a lower plot than in the panel).
LARGE_ASPECT = 0.62


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
            with self._container:
                self._handle = self._gui.add_plotly(fig, config=self._config, aspect=self._aspect, order=self._order,
                                                    visible=self._visible)
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

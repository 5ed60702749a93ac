"""app.explorer.lazy_plot.LazyPlot: no plotly element (hence no plotly.js in the page) before the first figure;
then one, at the placeholder's place in its folder, with the aspect and visibility set before. On a page whose
plots are held (the plot gate), none before the gate opens, then each with its latest figure."""

from __future__ import annotations

import gc
import threading
import weakref

import plotly.graph_objects as go
import viser

from paraspace.app.explorer import lazy_plot
from paraspace.app.explorer.lazy_plot import LazyPlot, hold_plots


def test_created_at_the_first_figure_in_place():
    server = viser.ViserServer(port=0, verbose=False)
    made: list = []
    try:
        gui = server.gui
        real = gui.add_plotly
        gui.add_plotly = lambda *a, **k: made.append(real(*a, **k)) or made[-1]  # type: ignore[method-assign]
        with gui.add_folder("plots") as folder:
            before = gui.add_markdown("above")
            plot = LazyPlot(gui, folder, "the plot appears here", aspect=0.5)
            after = gui.add_button("below")
        assert not plot.created and made == []
        plot.aspect = 0.8
        plot.visible = False
        fig = go.Figure(go.Scatter(x=[1, 2], y=[3, 4]))
        plot.figure = fig
        assert plot.created and len(made) == 1 and plot.figure is fig
        h = made[0]
        assert before.order < h.order < after.order  # where the placeholder was
        assert h.aspect == 0.8 and h.visible is False
        plot.visible = True
        plot.figure = go.Figure(go.Bar(x=[1], y=[2]))
        assert len(made) == 1 and h.visible and h.figure.data[0].type == "bar"
    finally:
        server.stop()


def test_open_large_shows_the_same_figure_in_a_wide_window():
    from paraspace.app.explorer.lazy_plot import LARGE_ASPECT

    server = viser.ViserServer(port=0, verbose=False)
    made: list = []
    try:
        gui = server.gui
        real = gui.add_plotly
        gui.add_plotly = lambda *a, **k: made.append(real(*a, **k)) or made[-1]  # type: ignore[method-assign]
        with gui.add_folder("plots") as folder:
            plot = LazyPlot(gui, folder, "the plot appears here", aspect=1.4)
        assert plot.large.disabled and plot.open_large() is None  # nothing to show yet
        fig = go.Figure(go.Scatter(x=[1, 2], y=[3, 4]), layout=dict(title="Fig. 4 - V vs a<br>second line"))
        plot.figure = fig
        assert not plot.large.disabled
        titles: list[str] = []
        real_modal = gui.add_modal
        gui.add_modal = lambda title, **k: titles.append(title) or real_modal(title, **k)  # type: ignore[method-assign]
        modal = plot.open_large()
        assert modal is not None and len(made) == 2
        large = made[1]
        assert large.figure.to_dict() == fig.to_dict() and large.aspect == LARGE_ASPECT  # lower than the panel's
        assert titles == ["Fig. 4 - V vs a"]  # the figure's first title line
        plot.visible = False
        assert not plot.large.visible
    finally:
        server.stop()


def test_held_plots_wait_for_the_gate_then_show_their_latest_figure():
    server = viser.ViserServer(port=0, verbose=False)
    made: list = []
    release = threading.Event()
    opener_calls: list[str] = []

    def opener() -> None:  # the explorer's waits for the browser to draw its first shell
        opener_calls.append(threading.current_thread().name)
        assert release.wait(30)

    try:
        gui = server.gui
        real = gui.add_plotly
        gui.add_plotly = lambda *a, **k: made.append(real(*a, **k)) or made[-1]  # type: ignore[method-assign]
        gate = hold_plots(gui, opener)
        with gui.add_folder("plots") as folder:
            first = LazyPlot(gui, folder, "first plot", aspect=0.5)
            second = LazyPlot(gui, folder, "second plot")
        fig1, fig2 = go.Figure(go.Scatter(x=[1], y=[1])), go.Figure(go.Bar(x=[1], y=[2]))
        first.figure = fig1
        first.figure = fig2  # a newer figure while it waits
        second.figure = fig1
        assert made == [] and not first.created and not second.created  # no plotly.js yet
        assert first.figure is fig2 and first.large.disabled
        assert gate.opened.wait(0.3) is False  # the opener is still waiting
        assert len(opener_calls) == 1 and opener_calls[0] == "plot-gate"  # once, off the caller's thread
        release.set()
        assert gate.opened.wait(30)
        assert first.created and second.created and len(made) == 2 and len(opener_calls) == 1
        by_type = sorted(h.figure.data[0].type for h in made)
        assert by_type == ["bar", "scatter"]  # each plot with its latest figure, created once
        assert not first.large.disabled and made[[h.figure.data[0].type for h in made].index("bar")].aspect == 0.5
        with gui.add_folder("later") as later_folder:
            later = LazyPlot(gui, later_folder, "a plot built after the gate opened")
        later.figure = fig1
        assert later.created and len(made) == 3  # at once
    finally:
        release.set()
        server.stop()


def test_a_failing_opener_still_opens_the_gate():
    server = viser.ViserServer(port=0, verbose=False)
    try:
        gui = server.gui

        def opener() -> None:
            raise RuntimeError("the browser left")

        gate = hold_plots(gui, opener)
        with gui.add_folder("plots") as folder:
            plot = LazyPlot(gui, folder, "a plot")
        plot.figure = go.Figure(go.Scatter(x=[1], y=[1]))
        assert gate.opened.wait(30) and plot.created
    finally:
        server.stop()


def test_a_held_gate_does_not_keep_its_page_alive():
    """The gate's opener refers to the page (as the explorer's does, through its client): once the page and
    its plots are gone, neither the registry nor the gate keeps them."""

    class Page:
        pass

    page = Page()
    gate = hold_plots(page, lambda p=page: p)  # the opener keeps the page, as the explorer's keeps its client
    assert lazy_plot._gate_of(page) is gate
    page_ref, gate_ref = weakref.ref(page), weakref.ref(gate)
    del page, gate
    gc.collect()
    assert page_ref() is None and gate_ref() is None


def test_a_closed_gate_creates_nothing():
    """The page left (the session closes its gate): a plot waiting for the gate, or given a figure later,
    is never created, so nothing is queued on the closed connection."""
    server = viser.ViserServer(port=0, verbose=False)
    made: list = []
    release = threading.Event()
    try:
        gui = server.gui
        real = gui.add_plotly
        gui.add_plotly = lambda *a, **k: made.append(real(*a, **k)) or made[-1]  # type: ignore[method-assign]
        gate = hold_plots(gui, lambda: release.wait(30))
        with gui.add_folder("plots") as folder:
            waiting = LazyPlot(gui, folder, "a plot given its figure before the page left")
            later = LazyPlot(gui, folder, "a plot given its figure after")
        waiting.figure = go.Figure(go.Scatter(x=[1], y=[1]))
        gate.close()
        release.set()
        assert gate.opened.wait(30)
        later.figure = go.Figure(go.Bar(x=[1], y=[2]))
        assert made == [] and not waiting.created and not later.created
    finally:
        release.set()
        server.stop()

"""app.explorer.lazy_plot.LazyPlot: no plotly element (hence no plotly.js in the page) before the first figure;
then one, at the placeholder's place in its folder, with the aspect and visibility set before."""

from __future__ import annotations

import plotly.graph_objects as go
import viser

from paraspace.app.explorer.lazy_plot import LazyPlot


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

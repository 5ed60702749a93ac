"""The PNG / SVG downloads of the Plots tab's figures, as they are on screen.

Off the data path slider -> state -> job -> engine -> mesh -> scene: each plot's controller
registers the :class:`~app.figures.FigureSpec` it has just drawn (:meth:`PlotExports.set`); a
download button sends that spec as a static file (:func:`app.figures.export`, PNG at
``figures.EXPORT_DPI`` dpi or SVG), rendered once per spec and format.
"""

from __future__ import annotations

from typing import Any

from .. import figures
from .session import SessionContext


class PlotExports:
    """The figure on screen of each plot (``"orientation"``, ``"sweep"``, ``"surface"``) and its files."""

    def __init__(self, ctx: SessionContext) -> None:
        self.ctx = ctx
        self.specs: dict[str, figures.FigureSpec | None] = {}
        self._files: dict[tuple[str, str], tuple[Any, bytes]] = {}  # (plot, format) -> file of the plot on screen

    def set(self, which: str, spec: figures.FigureSpec) -> None:
        """Plot ``which`` now shows ``spec`` (its earlier files are dropped)."""
        with self.ctx.lock:
            self.specs[which] = spec
            for k in [k for k in self._files if k[0] == which]:
                del self._files[k]

    def download(self, which: str, fmt: str) -> None:
        """Send the plot ``which`` as it is on screen, as a static ``fmt`` file (``"png"`` or ``"svg"``)."""
        ctx = self.ctx
        with ctx.lock:
            spec = self.specs.get(which)
            hit = self._files.get((which, fmt))
        if spec is None:
            ctx.notify("Not ready", "this plot has not been computed yet", color="orange")
            return
        if hit is not None and hit[0] is spec:
            data = hit[1]
        else:
            data = figures.export(spec, fmt)
            with ctx.lock:
                self._files[(which, fmt)] = (spec, data)
        ctx.client.send_file_download(f"{spec.filename}.{fmt}", data, save_immediately=True)

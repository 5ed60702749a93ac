"""The explorer's "Legend" folder: what the 3-D view's colours, labels and units mean.

* the shell's colour key, one per colour mode of the View tab, each with its own title: "height
  z" (the viridis map of :func:`kinematics.shell.viridis` over the shell's z range, with tick
  values, redrawn when a new shell arrives), "dexterity 1/kappa" (the same map over the field's
  range, labelled 1/kappa) and "binding limit" (categorical swatches with each limit's share of
  the surface); "computing..." while a mode's colours are not ready, so the key never describes
  colours that are not on screen, and "not computed" with the reason when they could not be;
* the leg colours by state, the platform's colour (pose in or out of the workspace), the axes;
* the units: lengths in the paper's dimensionless units, volumes in units³, angles in degrees.
"""

from __future__ import annotations

import dataclasses
import functools
import io
from typing import Any

import numpy as np
import viser

from paraspace.kinematics.shell import viridis

from ..textsafe import md_text

#: Pixel size of the colour bar image.
BAR_SIZE = (360, 78)

LEGEND_TEXT = (
    "**Legs:** blue = inside their stroke, orange = at a limit, red = out of range (a label names the leg)  \n"
    "**Platform:** green = the pose is in the workspace, red = outside (label above the platform)  \n"
    "**Axes:** x red, y green, z blue, from the base centre; grid cells r/5, sections r  \n"
    "**Total-orientation workspace** (Pose tab, on request): translucent purple  \n"
    "**Pinned designs** (Compare tab): height contours in the pin's colour: pin 1 magenta, 2 brown, "
    "3 olive, 4 cyan  \n"
    "**Units:** lengths in the paper's units (dimensionless, r = 100 by default), volumes in units³, "
    "angles in degrees"
)


@dataclasses.dataclass
class LegendPanel:
    """Handles of one client's Legend folder."""

    colorbar: Any
    caption: Any
    text: Any

    def show_z_range(self, lo: float, hi: float, stale: str = "") -> None:
        """Redraw the colour bar for a shell spanning ``z in [lo, hi]`` (``stale``: the shell is an
        older state's, and why, e.g. "previous design, recomputing")."""
        self.colorbar.label = "shell colour = height z"
        self.colorbar.image = colorbar_image(lo, hi)
        self.caption.content = (f"Shell colour = height z, from {lo:.4g} (bottom) to {hi:.4g} (top), length units"
                                + (f" - *{stale}*" if stale else ""))

    def show_field_range(self, lo: float, hi: float, label: str, caption: str,
                         title: str = "shell colour = dexterity 1/kappa") -> None:
        """Redraw the colour bar for a shell coloured by another field (e.g. 1/kappa)."""
        self.colorbar.label = title
        self.colorbar.image = colorbar_image(lo, hi, label=label)
        self.caption.content = caption

    def show_categories(self, title: str, entries: tuple[tuple[str, tuple[int, int, int]], ...],
                        caption: str) -> None:
        """A categorical key: one swatch per ``(name, colour)`` (e.g. the binding limits)."""
        self.colorbar.label = title
        self.colorbar.image = swatch_image(entries)
        self.caption.content = caption

    def show_computing(self, title: str, what: str) -> None:
        """The key of a colour mode whose colours are being computed: no bar, "computing...", so
        the Legend never describes colours that are not on screen."""
        # the caption first: a reader never sees the new title beside the previous mode's caption
        self.caption.content = f"{what}: computing... (the shell keeps its previous colours until then)"
        self.colorbar.label = title
        self.colorbar.image = _blank_bar()


    def show_not_computed(self, title: str, what: str, why: str) -> None:
        """The key of a colour mode whose colours could not be computed: the height bar stays (the
        shell shows its height colours), and the caption says which mode failed and why."""
        self.caption.content = (f"{what}: **not computed** ({md_text(why)}); the shell shows its height "
                                "colours again. Choose the mode again to retry.")
        self.colorbar.label = f"{title}: not computed, height z shown"


@functools.lru_cache(maxsize=32)
def colorbar_image(lo: float, hi: float, size: tuple[int, int] = BAR_SIZE,
                   label: str = "z (length units)") -> np.ndarray:
    """RGB image (H, W, 3) of the shell's colour map from ``lo`` to ``hi`` with five labelled ticks
    (drawn with matplotlib's object API: safe in worker threads). Cached (read-only arrays): the
    shell on screen keeps its range while it is marked stale, and a returning design its own."""
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.colors import ListedColormap
    from matplotlib.figure import Figure

    w, h = size
    fig = Figure(figsize=(w / 100.0, h / 100.0), dpi=100)
    FigureCanvasAgg(fig)
    ax = fig.add_axes((0.09, 0.52, 0.82, 0.3))  # room for the end ticks' labels
    cmap = ListedColormap(viridis(np.linspace(0.0, 1.0, 256))[:, :3] / 255.0)
    span = hi - lo if hi > lo else 1.0
    ax.imshow(np.linspace(0.0, 1.0, 256)[None, :], aspect="auto", cmap=cmap, extent=(lo, lo + span, 0.0, 1.0))
    ax.set_yticks([])
    ticks = np.linspace(lo, lo + span, 5)
    ax.set_xticks(ticks)
    ax.set_xticklabels([f"{t:.3g}" for t in ticks], fontsize=9)
    ax.set_xlabel(label, fontsize=9, labelpad=1)
    return _pixels(fig)


def _pixels(fig: Any) -> np.ndarray:
    """The drawn figure as a read-only RGB image (H, W, 3) (matplotlib's object API: thread-safe)."""
    fig.canvas.draw()
    buf = io.BytesIO()
    fig.savefig(buf, format="raw", dpi=100)
    rgba = np.frombuffer(buf.getvalue(), np.uint8).reshape(int(fig.bbox.height), int(fig.bbox.width), 4)
    image = np.ascontiguousarray(rgba[:, :, :3])
    image.setflags(write=False)
    return image


@functools.lru_cache(maxsize=1)
def _blank_bar(size: tuple[int, int] = BAR_SIZE) -> np.ndarray:
    image = np.full((size[1], size[0], 3), 255, np.uint8)
    image.setflags(write=False)
    return image


@functools.lru_cache(maxsize=16)
def swatch_image(entries: tuple[tuple[str, tuple[int, int, int]], ...],
                 size: tuple[int, int] = (BAR_SIZE[0], 96)) -> np.ndarray:
    """RGB image (H, W, 3): a labelled swatch per ``(name, colour)``, two columns of three rows."""
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure
    from matplotlib.patches import Rectangle

    w, h = size
    fig = Figure(figsize=(w / 100.0, h / 100.0), dpi=100)
    FigureCanvasAgg(fig)
    ax = fig.add_axes((0.0, 0.0, 1.0, 1.0))
    ax.set_xlim(0, 2)
    ax.set_ylim(0, 3)
    ax.axis("off")
    for k, (name, rgb) in enumerate(entries[:6]):
        col, row = k % 2, 2 - k // 2
        ax.add_patch(Rectangle((col + 0.03, row + 0.2), 0.14, 0.6, facecolor=np.array(rgb) / 255.0,
                               edgecolor="black", linewidth=0.6))
        ax.text(col + 0.21, row + 0.5, name, fontsize=9, va="center", ha="left")
    return _pixels(fig)


def build_legend_folder(gui: viser.GuiApi, order: float | None = None) -> LegendPanel:
    """The Legend folder (open by default: a first-time user needs it), at ``order`` in the panel."""
    with gui.add_folder("Legend", expand_by_default=True, order=order):
        colorbar = gui.add_image(np.full((BAR_SIZE[1], BAR_SIZE[0], 3), 255, np.uint8), format="png",
                                 label="shell colour = height z")
        caption = gui.add_markdown("Shell colour = height z (waiting for the workspace)")
        text = gui.add_markdown(LEGEND_TEXT)
    return LegendPanel(colorbar=colorbar, caption=caption, text=text)

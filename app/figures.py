"""Every plot of paraspace, for the explorer and the command line, from one description.

A figure is first described by a small neutral :class:`FigureSpec` (title, panels, axis titles
with units, data, the current design's marker, a legend, warnings) built from the data by one
function per figure:

* :func:`sweep_spec` -- paper Fig. 4: any measure a sweep row carries (volume, hollowness, TI_1,
  TI_2, ...) against one design parameter, the current design marked;
* :func:`study_spec` -- paper Fig. 5: a measure over a 2-D grid of two parameters (the (a, d_s)
  study), as a 3-D surface and as a heat map whose cells are *centred* on the samples;
* :func:`orientation_spec` -- paper Fig. 3(e)-(g): the feasible (angle, position) samples of the
  three rotations on the three lines, one small panel per (line, rotation) so regions never
  overlap, blend or hide each other; each region's Δ box of eq. (28), a saturated Δ (the region
  spans the whole scan) drawn in a distinct style and reported by :func:`saturation_warning`.

The same spec then becomes an interactive plotly figure (:func:`to_plotly`: the explorer's
``gui.add_plotly``, hover read-outs, offline since viser bundles plotly.js) or a static matplotlib
figure (:func:`to_matplotlib`, :func:`export`: PNG at :data:`EXPORT_DPI` dpi, SVG, PDF), so the
picture on screen and the downloaded file show the same content.

plotly is imported only by :func:`to_plotly`, so the command line never loads it. matplotlib is
used through its object API (no pyplot state), which is safe in worker threads.
"""

from __future__ import annotations

import dataclasses
import html
import io
import math
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:  # pragma: no cover
    import plotly.graph_objects as go
    from matplotlib.figure import Figure

__all__ = [
    "EXPORT_DPI", "EXPORT_FORMATS", "MEASURES", "PARAM_INFO", "Box", "Grid", "Mask", "Marker", "Panel", "Series",
    "FigureSpec", "LegendEntry", "Saturation", "axis_title", "measure_axis", "param_axis", "plottable_measures",
    "sweep_spec", "study_spec", "orientation_spec", "orientation_saturation", "saturation_warning",
    "to_plotly", "to_matplotlib", "export", "export_format",
]

#: Resolution of PNG exports (dots per inch).
EXPORT_DPI = 200
#: File formats :func:`export` writes (by file-name suffix).
EXPORT_FORMATS: tuple[str, ...] = ("png", "svg", "pdf")

#: Lengths are in the paper's units (it gives none), volumes in units³, angles in degrees.
LENGTH = "units"

#: Design parameters: (axis name, unit).
PARAM_INFO: dict[str, tuple[str, str]] = {
    "a": ("a - platform radius", LENGTH),
    "b": ("b - U-joint spacing", LENGTH),
    "d_s": ("d_s - radial stroke", LENGTH),
    "r": ("r - base radius", LENGTH),
    "l_min": ("l_min - minimum leg length", LENGTH),
    "l_s": ("l_s - leg stroke", LENGTH),
    "eta_s": ("η_s - arc stroke", "deg"),
}

#: Measures of a sweep row (``kinematics.sweep.evaluate_design``): (axis name, unit), in menu order.
MEASURES: dict[str, tuple[str, str]] = {
    "volume": ("V - workspace volume", LENGTH + "³"),
    "hollowness": ("hollowness (underside cavity ratio)", "ratio 0-1"),
    "void_ratio": ("void ratio (enclosed voids / filled volume)", "ratio 0-1"),
    "TI_1": ("TI₁ - rotation index, eq. (28a)", "deg·" + LENGTH),
    "TI_2": ("TI₂ - tilt index, eq. (28b)", "deg·" + LENGTH),
    "solidity": ("solidity (V / convex hull volume)", "ratio 0-1"),
    "open_cavity_ratio": ("open cavity ratio", "ratio 0-1"),
    "column_gap_ratio": ("column gap ratio", "ratio 0-1"),
    "largest_component_fraction": ("largest component / V", "ratio 0-1"),
    "box_contact_fraction": ("box contact fraction", "ratio 0-1"),
    "voids": ("enclosed voids", "count"),
    "void_volume": ("void volume", LENGTH + "³"),
    "hull_volume": ("convex hull volume", LENGTH + "³"),
    "hollow_volume": ("underside cavity volume", LENGTH + "³"),
    "sealed_cavity_volume": ("sealed cavity volume", LENGTH + "³"),
    "components": ("connected components", "count"),
    "genus": ("genus of the outer surface", "count"),
    "euler_characteristic": ("Euler characteristic", "count"),
    "voxels": ("reachable voxels", "count"),
    "task_fraction": ("task fraction (share of the task reachable)", "ratio 0-1"),
    "task_margin": ("task margin (growth of the task region)", LENGTH),
}

# Okabe-Ito colours (distinguishable with the common colour-vision deficiencies)
ROTATION_COLORS: dict[str, str] = {"phi_z": "#0072B2", "tau_yprime": "#D55E00", "psi_x": "#009E73"}
ROTATION_NAMES: dict[str, str] = {"phi_z": "φ (about z)", "tau_yprime": "τ (about y')", "psi_x": "ψ (about x)"}
ROTATION_SYMBOLS: dict[str, str] = {"phi_z": "φ", "tau_yprime": "τ", "psi_x": "ψ"}
ROTATION_INDEX: dict[str, str] = {"phi_z": "TI_1", "tau_yprime": "TI_2", "psi_x": "TI_2"}
LINE_TITLES: dict[str, str] = {"z": "(e) z line: x = 0, y' = 0", "y_prime": "(f) y' line: x = 0, z = {z0}",
                               "x": "(g) x line: y' = 0, z = {z0}"}
LINE_SYMBOLS: dict[str, str] = {"z": "z", "y_prime": "y'", "x": "x"}
CURRENT_COLOR = "#CC0000"
BOX_COLOR = "#222222"
SATURATED_COLOR = "#CC0000"
OUTSIDE_COLOR = "#D9D9D9"
SERIES_COLOR = "#0072B2"
#: Largest number of samples per axis of an orientation map sent to the browser.
MAX_PLOTLY_SAMPLES = 250


# --------------------------------------------------------------------------------------------
# the neutral description


@dataclasses.dataclass
class Series:
    """A line with markers: ``y`` against ``x`` (NaN leaves a gap)."""

    name: str
    x: list[float]
    y: list[float]
    color: str = SERIES_COLOR


@dataclasses.dataclass
class Marker:
    """A marked point (the current design, an optimum). ``y`` (``z`` on a surface) may be unknown
    (``None``): then only a line at ``x`` (a vertical line at ``(x, y)`` on a surface) is drawn."""

    name: str
    x: float
    y: float | None = None
    z: float | None = None
    color: str = CURRENT_COLOR
    symbol: str = "diamond"  # "diamond" | "star" | "circle"
    vline: bool = False  # also a vertical line at x across the panel


@dataclasses.dataclass
class Grid:
    """Values on a rectangular grid of samples: ``z[iy][ix]`` at ``(x[ix], y[iy])``."""

    x: list[float]
    y: list[float]
    z: list[list[float]]
    colorscale: str = "viridis"


@dataclasses.dataclass
class Box:
    """An axis-aligned rectangle ``[x0, x1] x [y0, y1]``; ``saturated`` draws it in the saturation style."""

    x0: float
    x1: float
    y0: float
    y1: float
    saturated: bool = False


@dataclasses.dataclass
class Mask:
    """Samples that are in a set: ``inside[iy][ix]`` at ``(x[ix], y[iy])`` drawn in ``color``;
    ``scan`` is the sampled box ``(x0, x1, y0, y1)`` (outside it is shaded as not scanned)."""

    name: str
    x: np.ndarray
    y: np.ndarray
    inside: np.ndarray
    color: str
    scan: tuple[float, float, float, float]


@dataclasses.dataclass
class Panel:
    """One plot area. ``kind``: ``"xy"`` (series), ``"heatmap"`` / ``"surface"`` (``grid``) or
    ``"mask"`` (``mask`` and ``boxes``). Axis titles carry their units."""

    kind: str
    title: str
    x_title: str
    y_title: str
    z_title: str = ""
    series: list[Series] = dataclasses.field(default_factory=list)
    grid: Grid | None = None
    mask: Mask | None = None
    boxes: list[Box] = dataclasses.field(default_factory=list)
    markers: list[Marker] = dataclasses.field(default_factory=list)
    notes: list[str] = dataclasses.field(default_factory=list)  # short texts written in the panel
    x_range: tuple[float, float] | None = None
    y_range: tuple[float, float] | None = None
    hover: str = ""  # plotly hover template (value names and units)
    short_title: str = ""  # the title in a narrow interactive panel ("\n": line break); default ``title``


@dataclasses.dataclass
class LegendEntry:
    """A figure-level legend entry: a filled swatch (``kind="fill"``) or a line style (``"box"``,
    ``"saturated"``)."""

    label: str
    color: str
    kind: str = "fill"


@dataclasses.dataclass
class FigureSpec:
    """A whole figure: title, panels on a ``rows x cols`` grid, legend, warnings, export size."""

    title: str
    panels: list[Panel]
    rows: int = 1
    cols: int = 1
    legend: list[LegendEntry] = dataclasses.field(default_factory=list)
    warnings: list[str] = dataclasses.field(default_factory=list)
    size: tuple[float, float] = (7.0, 4.2)  # inches, static export
    aspect: float = 0.75  # height / width of the plot in the explorer (viser's ``aspect``)
    filename: str = "paraspace_plot"


def axis_title(name: str, unit: str) -> str:
    """``"name [unit]"``: every axis says what it shows and in which unit."""
    return f"{name} [{unit}]" if unit else name


def param_axis(param: str) -> str:
    """Axis title of a design parameter, e.g. ``"a - platform radius [units]"``."""
    name, unit = PARAM_INFO.get(param, (param, LENGTH))
    return axis_title(name, unit)


def measure_axis(measure: str) -> str:
    """Axis title of a measure, e.g. ``"V - workspace volume [units³]"`` (unknown names: ``[-]``)."""
    name, unit = MEASURES.get(measure, (measure, "-"))
    return axis_title(name, unit)


def _is_number(v: Any) -> bool:
    return isinstance(v, (int, float, np.integer, np.floating)) and not isinstance(v, bool)


def plottable_measures(rows: Sequence[dict]) -> list[str]:
    """The numeric measures the sweep ``rows`` carry, known measures first (menu order), then any
    other numeric field except the parameter values and timings."""
    skip = {"value", "value2", "x", "y", "ix", "iy", "compute_seconds", "voxel_size", "connectivity"}
    present: list[str] = []
    for r in rows:
        for k, v in r.items():
            if k not in present and k not in skip and _is_number(v):
                present.append(k)
    known = [m for m in MEASURES if m in present]
    return known + [m for m in present if m not in MEASURES]


def _num(v: Any) -> float:
    return float(v) if _is_number(v) and math.isfinite(float(v)) else math.nan


def _fmt(v: float | None) -> str:
    if v is None or not math.isfinite(v):
        return "?"
    from .numfmt import significant

    return significant(v, 4)


def _voxel_note(voxel: float | None) -> str:
    return f" (voxel h = {voxel:g})" if voxel else ""


# --------------------------------------------------------------------------------------------
# the figures


def sweep_spec(rows: Sequence[dict], param: str, measure: str = "volume", *, current: float | None = None,
               current_value: float | None = None, voxel: float | None = None) -> FigureSpec:
    """Paper Fig. 4: ``measure`` against ``param`` from sweep rows (``{"value": v, measure: m}``).

    ``current`` (the current design's value of ``param``) is marked by a vertical line, and by a
    point at ``current_value`` when that is known. Rows without the measure (failed points) leave a
    gap.
    """
    pts = sorted(((_num(r.get("value")), _num(r.get(measure))) for r in rows), key=lambda p: p[0])
    xs = [p[0] for p in pts]
    ys = [p[1] for p in pts]
    mname, munit = MEASURES.get(measure, (measure, "-"))
    pname, punit = PARAM_INFO.get(param, (param, LENGTH))
    short = mname.split(" - ")[0]
    panel = Panel(kind="xy", title="", x_title=param_axis(param), y_title=measure_axis(measure),
                  series=[Series(short, xs, ys)],
                  hover=f"{param} = %{{x:.4g}} {punit}<br>{short} = %{{y:.4g}} {munit}<extra></extra>")
    if current is not None and math.isfinite(current):
        cv = None if current_value is None or not math.isfinite(current_value) else float(current_value)
        label = f"current design: {param} = {current:g}" + (f", {short} = {_fmt(cv)}" if cv is not None else "")
        panel.markers.append(Marker(label, float(current), cv, vline=True))
    title = f"Fig. 4 - {short} vs {param}{_voxel_note(voxel)}"
    return FigureSpec(title=title, panels=[panel], size=(7.0, 4.4), aspect=0.95,
                      filename=f"paraspace_{measure}_vs_{param}")


def study_spec(values_x: Sequence[float], values_y: Sequence[float], grid: Sequence[Sequence[Any]], *,
               param_x: str = "a", param_y: str = "d_s", measure: str = "volume",
               current: tuple[float, float] | None = None, current_value: float | None = None,
               voxel: float | None = None, panels: Sequence[str] = ("surface", "heatmap")) -> FigureSpec:
    """Paper Fig. 5: ``grid[iy][ix]`` (the measure at ``(values_x[ix], values_y[iy])``) as a 3-D
    surface and a heat map (``panels`` picks which, in order). Heat-map cells are centred on the
    samples. The grid's maximum gets a star; ``current`` (the current design's ``(x, y)``) a red
    marker (on the surface at ``current_value``, or a vertical line when that is unknown).
    """
    xs = [float(v) for v in values_x]
    ys = [float(v) for v in values_y]
    z = [[_num(v) for v in row] for row in grid]
    short = MEASURES.get(measure, (measure, "-"))[0].split(" - ")[0]
    munit = MEASURES.get(measure, (measure, "-"))[1]
    ux, uy = PARAM_INFO.get(param_x, (param_x, LENGTH))[1], PARAM_INFO.get(param_y, (param_y, LENGTH))[1]
    hover = (f"{param_x} = %{{x:.4g}} {ux}<br>{param_y} = %{{y:.4g}} {uy}<br>{short} = %{{z:.4g}} {munit}"
             "<extra></extra>")
    arr = np.asarray(z, float)
    markers: list[Marker] = []
    if arr.size and np.isfinite(arr).any():
        iy, ix = np.unravel_index(int(np.nanargmax(arr)), arr.shape)
        markers.append(Marker(f"max {short} = {_fmt(arr[iy, ix])} at {param_x} = {xs[ix]:g}, {param_y} = {ys[iy]:g}",
                              xs[ix], ys[iy], float(arr[iy, ix]), color="#FFFFFF", symbol="star"))
    if current is not None:
        cv = None if current_value is None or not math.isfinite(current_value) else float(current_value)
        markers.append(Marker(f"current design: {param_x} = {current[0]:g}, {param_y} = {current[1]:g}"
                              + (f", {short} = {_fmt(cv)}" if cv is not None else ""),
                              float(current[0]), float(current[1]), cv, symbol="circle"))
    out: list[Panel] = []
    for kind in panels:
        out.append(Panel(kind=kind, title="3-D surface" if kind == "surface" else "heat map (cells centred on samples)",
                         x_title=param_axis(param_x), y_title=param_axis(param_y), z_title=measure_axis(measure),
                         grid=Grid(xs, ys, z), markers=list(markers), hover=hover))
    title = f"Fig. 5 - {short} over ({param_x}, {param_y}){_voxel_note(voxel)}"
    n = len(out)
    return FigureSpec(title=title, panels=out, rows=n, cols=1, size=(6.6, 5.0 * n), aspect=0.3 + 0.85 * n,
                      filename=f"paraspace_{measure}_{param_x}_{param_y}")


@dataclasses.dataclass
class Saturation:
    """A Δ of eq. (28) that equals the scanned range: the true extent may be larger."""

    line: str
    rotation: str
    coordinate: str  # "angle" or "position"
    delta: float
    scan: tuple[float, float]
    index: str  # the index it feeds, "TI_1" or "TI_2"


def orientation_saturation(result: Any, rel_tol: float = 1e-9) -> list[Saturation]:
    """The saturated Δ's of an :class:`~kinematics.orientation.OrientationResult`: regions whose
    angle Δ equals the angle scan (``region.angle_range``) or whose position Δ equals the line's
    scanned range (``region.position_range``)."""
    out: list[Saturation] = []
    for (line, rot), reg in result.regions.items():
        for coord, delta, scan in (("angle", reg.delta_angle, reg.angle_range),
                                   ("position", reg.delta_position, reg.position_range)):
            span = float(scan[1]) - float(scan[0])
            if span > 0 and delta >= span * (1.0 - rel_tol) - 1e-12:
                out.append(Saturation(line, rot, coord, float(delta), (float(scan[0]), float(scan[1])),
                                      ROTATION_INDEX.get(rot, "TI_2")))
    return out


def saturation_warning(result: Any) -> str:
    """One plain sentence per affected index saying which Δ's span the whole scan (so that index is
    a lower bound: a wider scan could give more), or ``""`` when none does."""
    sats = orientation_saturation(result)
    parts = []
    for index, sub in (("TI₁", "TI_1"), ("TI₂", "TI_2")):
        groups: dict[tuple[str, str, float, tuple[float, float]], list[str]] = {}
        for s in sats:
            if s.index == sub:
                who = s.line if s.coordinate == "angle" else s.rotation
                groups.setdefault((s.rotation if s.coordinate == "angle" else s.line, s.coordinate, s.delta, s.scan),
                                  []).append(who)
        if not groups:
            continue
        what = []
        for (key, coord, delta, scan), whos in groups.items():
            if coord == "angle":
                lines = ", ".join(LINE_SYMBOLS[w] for w in whos)
                what.append(f"Δ{ROTATION_SYMBOLS[key]} = {delta:g}° = the whole scan [{scan[0]:g}°, {scan[1]:g}°] "
                            f"on the {lines} line{'s' if len(whos) > 1 else ''}")
            else:
                rots = ", ".join(ROTATION_SYMBOLS[w] for w in whos)
                what.append(f"Δ{LINE_SYMBOLS[key]} = {delta:.4g} = the whole {LINE_SYMBOLS[key]} line "
                            f"[{scan[0]:.4g}, {scan[1]:.4g}] for {rots}")
        parts.append(f"{index} is a lower bound: {'; '.join(what)}; a wider scan could give more.")
    return " ".join(parts)


def _crop_rows(inside: np.ndarray, pos: np.ndarray, lo: float, hi: float) -> slice:
    keep = np.nonzero((pos >= lo) & (pos <= hi))[0]
    if keep.size == 0:
        return slice(0, 0)
    return slice(int(keep[0]), int(keep[-1]) + 1)


def orientation_spec(result: Any, z0: float | None = None) -> FigureSpec:
    """Paper Fig. 3(e)-(g) from an :class:`~kinematics.orientation.OrientationResult`: one panel per
    (line, rotation) -- rows the z, y' and x lines, columns φ, τ, ψ -- each showing the feasible
    samples in the rotation's colour, the region's Δ box (eq. (28)) dashed, and a saturated Δ box in
    red with a note. Every panel of a row has the same axes, so regions compare side by side without
    overlapping. The grey band is outside the scan."""
    from paraspace.kinematics.orientation import LINES, ROTATIONS

    z0 = result.settings.z0 if z0 is None else z0
    sats = {(s.line, s.rotation, s.coordinate) for s in orientation_saturation(result)}
    panels: list[Panel] = []
    for line in LINES:
        regs = [result.regions.get((line, r)) for r in ROTATIONS]
        present = [g for g in regs if g is not None]
        # common position window of the row: the regions' intervals, padded, within the scan
        ivs = [g.position_interval for g in present if g.position_interval is not None]
        prange = present[0].position_range if present else (0.0, 1.0)
        arange = present[0].angle_range if present else (-90.0, 90.0)
        if ivs:
            lo, hi = min(i[0] for i in ivs), max(i[1] for i in ivs)
            pad = 0.08 * max(hi - lo, 1.0)
            y_lo, y_hi = max(prange[0], lo - pad), min(prange[1], hi + pad)
        else:
            y_lo, y_hi = prange
        y_span = y_hi - y_lo
        if y_lo <= prange[0]:
            y_lo -= 0.05 * y_span
        if y_hi >= prange[1]:
            y_hi += 0.05 * y_span
        a_pad = 0.06 * (arange[1] - arange[0])
        ls = LINE_SYMBOLS[line]
        for rot, reg in zip(ROTATIONS, regs):
            sym = ROTATION_SYMBOLS[rot]
            color = ROTATION_COLORS[rot]
            title = f"{sym} on {ls}"
            short = ""
            notes: list[str] = []
            boxes: list[Box] = []
            mask = None
            if reg is not None:
                pos = np.asarray(reg.positions, float)
                ang = np.asarray(reg.angles, float)
                feas = np.asarray(reg.feasible, bool)
                rows = _crop_rows(feas, pos, y_lo, y_hi)
                mask = Mask(ROTATION_NAMES[rot], ang, pos[rows], feas[rows], color,
                            (float(arange[0]), float(arange[1]), float(prange[0]), float(prange[1])))
                sat_a = (line, rot, "angle") in sats
                sat_p = (line, rot, "position") in sats
                if reg.angle_interval is not None and reg.position_interval is not None:
                    (a0, a1), (p0, p1) = reg.angle_interval, reg.position_interval
                    boxes.append(Box(a0, a1, p0, p1, saturated=sat_a or sat_p))
                    title = (f"{sym} on {ls}: Δ{sym} = {reg.delta_angle:g}°{'*' if sat_a else ''}, "
                             f"Δ{ls} = {reg.delta_position:.4g}{'*' if sat_p else ''}")
                    short = (f"{sym} on {ls}\nΔ{sym} {reg.delta_angle:g}°{'*' if sat_a else ''} · "
                             f"Δ{ls} {reg.delta_position:.4g}{'*' if sat_p else ''}")
                    if sat_a:
                        notes.append(f"Δ{sym} = whole scan")
                    if sat_p:
                        notes.append(f"Δ{ls} = whole line")
                else:
                    title = f"{sym} on {ls}: no feasible sample"
                    short = f"{sym} on {ls}\nno feasible sample"
            panels.append(Panel(
                kind="mask", title=title, short_title=short, x_title=f"{sym} [deg]",
                y_title=f"{ls} [{LENGTH}]" if rot == ROTATIONS[0] else "",
                mask=mask, boxes=boxes, notes=notes,
                x_range=(arange[0] - a_pad, arange[1] + a_pad), y_range=(y_lo, y_hi),
                hover=f"{sym} = %{{x:g}}°<br>{ls} = %{{y:.4g}} {LENGTH}<extra>{sym} feasible</extra>"))
    legend = [LegendEntry(f"{ROTATION_NAMES[r]} feasible", ROTATION_COLORS[r]) for r in ROTATIONS]
    legend.append(LegendEntry("Δ box of eq. (28)", BOX_COLOR, "box"))
    if sats:
        legend.append(LegendEntry("* Δ = whole scan (saturated)", SATURATED_COLOR, "saturated"))
    legend.append(LegendEntry("outside the scan", OUTSIDE_COLOR))
    warn = saturation_warning(result)
    title = (f"Fig. 3(e)-(g) - orientation workspace, z0 = {z0:g}:\n"
             f"TI₁ = {_fmt(result.ti1)}, TI₂ = {_fmt(result.ti2)} [deg·{LENGTH}]")
    return FigureSpec(title=title, panels=panels, rows=3, cols=3, legend=legend, warnings=[warn] if warn else [],
                      size=(10.0, 10.0), aspect=1.75, filename="paraspace_orientation")


# --------------------------------------------------------------------------------------------
# plotly (the explorer)


def _esc(text: str) -> str:
    """plotly renders a subset of HTML in titles: escape (names can come from a request)."""
    return html.escape(str(text), quote=False)


_PLOTLY_SYMBOL = {"diamond": "diamond", "star": "star", "circle": "circle-open"}


def _lines(text: str) -> str:
    """Escaped plotly text; ``"\n"`` becomes a line break."""
    return "<br>".join(_esc(t) for t in str(text).split("\n"))


def _short_axis(title: str) -> str:
    """``"a - platform radius [units]"`` -> ``"a [units]"`` (3-D axes have little room)."""
    name, _, rest = title.partition(" - ")
    unit = "[" + title.rsplit("[", 1)[-1] if "[" in title else ""
    return f"{name} {unit}".strip() if rest else title


def _axis_ref(i: int, axis: str) -> str:
    return axis if i == 0 else f"{axis}{i + 1}"


def to_plotly(spec: FigureSpec) -> go.Figure:
    """The interactive plotly figure of ``spec`` (hover read-outs, zoom; offline)."""
    import plotly.graph_objects as go
    from plotly.subplots import make_subplots

    if not spec.panels:
        fig = go.Figure()
        fig.update_layout(title=dict(text=_esc(spec.title), font=dict(size=13, color="#555555")),
                          xaxis=dict(visible=False), yaxis=dict(visible=False), height=120,
                          margin=dict(l=10, r=10, t=40, b=10), plot_bgcolor="white")
        return fig
    types = [[{"type": "scene" if p.kind == "surface" else "xy"}
              for p in spec.panels[r * spec.cols:(r + 1) * spec.cols]] for r in range(spec.rows)]
    multi = len(spec.panels) > 1
    fig = make_subplots(rows=spec.rows, cols=spec.cols, specs=types,
                        subplot_titles=[_lines(p.short_title or p.title) for p in spec.panels] if multi else None,
                        horizontal_spacing=0.06 if spec.cols > 1 else 0.02,
                        vertical_spacing=0.09 if spec.rows > 1 else 0.02)
    legend_seen: set[str] = set()

    def legend_once(name: str) -> bool:
        if name in legend_seen:
            return False
        legend_seen.add(name)
        return True

    xy_index = 0
    for i, p in enumerate(spec.panels):
        row, col = i // spec.cols + 1, i % spec.cols + 1
        at = dict(row=row, col=col)
        if p.kind == "xy":
            for s in p.series:
                fig.add_trace(go.Scatter(x=s.x, y=s.y, mode="lines+markers", name=_esc(s.name),
                                         line=dict(color=s.color, width=2), marker=dict(size=6),
                                         hovertemplate=p.hover or None, connectgaps=False), **at)
        elif p.kind == "heatmap" and p.grid is not None:
            g = p.grid
            fig.add_trace(go.Heatmap(x=g.x, y=g.y, z=g.z, colorscale=g.colorscale, hovertemplate=p.hover or None,
                                     name="", showscale=True,
                                     colorbar=dict(title=dict(text=_esc(p.z_title), side="right"),
                                                   len=0.9 / spec.rows, y=1 - (row - 0.5) / spec.rows,
                                                   yanchor="middle", thickness=12, exponentformat="power")),
                          **at)
        elif p.kind == "surface" and p.grid is not None:
            g = p.grid
            fig.add_trace(go.Surface(x=g.x, y=g.y, z=g.z, colorscale=g.colorscale, showscale=False,
                                     hovertemplate=p.hover or None, name=""), **at)
        elif p.kind == "mask" and p.mask is not None:
            m = p.mask
            # the screen shows at most ~250 samples per axis: thin the grid (the files keep every sample)
            sy, sx = (max(1, math.ceil(n / MAX_PLOTLY_SAMPLES)) for n in m.inside.shape)
            fig.add_trace(go.Heatmap(x=m.x[::sx], y=m.y[::sy], z=m.inside[::sy, ::sx].astype(np.uint8), zmin=0, zmax=1,
                                     showscale=False,
                                     colorscale=[[0.0, "rgba(0,0,0,0)"], [1.0, m.color]],
                                     hovertemplate=p.hover or None, name=_esc(m.name)), **at)
            # grey bands outside the scan
            if p.x_range is not None:
                for a, b in ((p.x_range[0], m.scan[0]), (m.scan[1], p.x_range[1])):
                    if b > a:
                        fig.add_shape(type="rect", x0=a, x1=b, y0=0, y1=1, yref=f"{_axis_ref(xy_index, 'y')} domain",
                                      xref=_axis_ref(xy_index, "x"), fillcolor=OUTSIDE_COLOR, line_width=0,
                                      layer="below")
            if p.y_range is not None:
                for a, b in ((p.y_range[0], m.scan[2]), (m.scan[3], p.y_range[1])):
                    if b > a:
                        fig.add_shape(type="rect", y0=a, y1=b, x0=0, x1=1, xref=f"{_axis_ref(xy_index, 'x')} domain",
                                      yref=_axis_ref(xy_index, "y"), fillcolor=OUTSIDE_COLOR, line_width=0,
                                      layer="below")
        for box in p.boxes:
            fig.add_shape(type="rect", x0=box.x0, x1=box.x1, y0=box.y0, y1=box.y1,
                          xref=_axis_ref(xy_index, "x"), yref=_axis_ref(xy_index, "y"),
                          line=dict(color=SATURATED_COLOR if box.saturated else BOX_COLOR,
                                    width=3 if box.saturated else 1.5, dash="dashdot" if box.saturated else "dash"))
        for note in p.notes:
            fig.add_annotation(text=_esc(note), x=0.5, y=0.02, xref=f"{_axis_ref(xy_index, 'x')} domain",
                               yref=f"{_axis_ref(xy_index, 'y')} domain", showarrow=False, yanchor="bottom",
                               font=dict(size=10, color=SATURATED_COLOR), bgcolor="rgba(255,255,255,0.8)")
        for mk in p.markers:
            sym = _PLOTLY_SYMBOL.get(mk.symbol, mk.symbol)
            show = legend_once(mk.name)
            if p.kind == "surface":
                if mk.z is not None:
                    fig.add_trace(go.Scatter3d(x=[mk.x], y=[mk.y], z=[mk.z], mode="markers", name=_esc(mk.name),
                                               legendgroup=_esc(mk.name), showlegend=show,
                                               hovertemplate=_esc(mk.name) + "<extra></extra>",
                                               marker=dict(size=6, color=mk.color,
                                                           symbol="circle-open" if mk.symbol == "circle" else "diamond",
                                                           line=dict(color="black", width=1))), **at)
                elif p.grid is not None:
                    zz = np.asarray(p.grid.z, float)
                    lo, hi = (float(np.nanmin(zz)), float(np.nanmax(zz))) if np.isfinite(zz).any() else (0.0, 1.0)
                    fig.add_trace(go.Scatter3d(x=[mk.x, mk.x], y=[mk.y, mk.y], z=[lo, hi], mode="lines",
                                               name=_esc(mk.name), legendgroup=_esc(mk.name), showlegend=show,
                                               line=dict(color=mk.color, width=6)), **at)
                continue
            if mk.vline:
                fig.add_shape(type="line", x0=mk.x, x1=mk.x, y0=0, y1=1, xref=_axis_ref(xy_index, "x"),
                              yref=f"{_axis_ref(xy_index, 'y')} domain",
                              line=dict(color=mk.color, width=1.5, dash="dash"))
            if mk.y is not None:
                fig.add_trace(go.Scatter(x=[mk.x], y=[mk.y], mode="markers", name=_esc(mk.name),
                                         legendgroup=_esc(mk.name), showlegend=show,
                                         marker=dict(size=13 if mk.symbol == "star" else 11, color=mk.color,
                                                     symbol=sym, line=dict(color="black" if mk.symbol != "circle"
                                                                           else mk.color, width=2 if
                                                                           mk.symbol == "circle" else 1)),
                                         hovertemplate=_esc(mk.name) + "<extra></extra>"), **at)
            elif mk.vline:  # a legend entry for the line alone
                fig.add_trace(go.Scatter(x=[mk.x], y=[None], mode="lines", name=_esc(mk.name), showlegend=show,
                                         line=dict(color=mk.color, dash="dash")), **at)
        if p.kind == "surface":
            scene = "scene" if i == 0 else f"scene{i + 1}"
            # a narrow panel: short titles, SI tick labels (2M, not 2x10^6, which got clipped), the camera close
            small = dict(title_font_size=11, tickfont_size=10)
            fig.layout[scene].update(xaxis=dict(title=_esc(_short_axis(p.x_title)), **small),
                                     yaxis=dict(title=_esc(_short_axis(p.y_title)), **small),
                                     zaxis=dict(title=_esc(_short_axis(p.z_title)), tickformat="~s", **small),
                                     camera=dict(eye=dict(x=1.7, y=-1.7, z=1.0), center=dict(x=0.05, y=0, z=-0.1)),
                                     aspectmode="manual", aspectratio=dict(x=1.0, y=1.0, z=0.7))
        else:
            compact = p.kind == "mask" and spec.cols > 1
            x_title = "" if compact and row < spec.rows else p.x_title
            fig.update_xaxes(title_text=_esc(x_title), row=row, col=col, showgrid=True, gridcolor="#E5E5E5",
                             zeroline=False, ticks="outside", mirror=True, showline=True, linecolor="#888888")
            fig.update_yaxes(title_text=_esc(p.y_title), row=row, col=col, showgrid=True, gridcolor="#E5E5E5",
                             zeroline=False, ticks="outside", mirror=True, showline=True, linecolor="#888888",
                             exponentformat="power")
            if not compact:  # at least five labelled ticks per axis, also in a narrow panel
                fig.update_xaxes(nticks=8, row=row, col=col)
                fig.update_yaxes(nticks=8, row=row, col=col)
            if compact:
                pm = p.mask
                ticks = [pm.scan[0], 0.0, pm.scan[1]] if pm is not None and pm.scan[0] < 0 < pm.scan[1] else None
                fig.update_xaxes(tickfont_size=9, nticks=4, title_standoff=2, tickvals=ticks, row=row, col=col,
                                 showticklabels=row == spec.rows)  # one shared angle scale per column
                fig.update_yaxes(tickfont_size=9, nticks=5, title_standoff=2, row=row, col=col)
            if p.x_range is not None:
                fig.update_xaxes(range=list(p.x_range), row=row, col=col)
            if p.y_range is not None:
                fig.update_yaxes(range=list(p.y_range), row=row, col=col)
            xy_index += 1
    # figure-level legend entries (orientation maps): dummy traces so plotly's legend shows them
    for e in spec.legend:
        if e.kind == "fill":
            tr = go.Scatter(x=[None], y=[None], mode="markers", name=_esc(e.label), showlegend=True,
                            marker=dict(symbol="square", size=14, color=e.color))
        else:
            tr = go.Scatter(x=[None], y=[None], mode="lines", name=_esc(e.label), showlegend=True,
                            line=dict(color=e.color, width=3 if e.kind == "saturated" else 1.5,
                                      dash="dashdot" if e.kind == "saturated" else "dash"))
        fig.add_trace(tr, row=1, col=1)
    if multi:
        fig.update_annotations(font_size=10 if spec.panels[0].kind == "mask" else 12)
    import textwrap

    title = _lines(spec.title)
    n_lines = spec.title.count("\n") + 1
    if spec.warnings:
        wrapped = [ln for w in spec.warnings for ln in textwrap.wrap("⚠ " + w, 62)]
        n_lines += len(wrapped)
        title += "<br><span style='font-size:11px;color:#CC0000'>" + "<br>".join(_esc(w) for w in wrapped) \
            + "</span>"
    fig.update_layout(
        title=dict(text=title, font=dict(size=13), x=0.01, xanchor="left", y=1.0, yanchor="top", yref="container",
                   pad=dict(t=24)),  # below plotly's tool bar
        font=dict(size=11), plot_bgcolor="white", paper_bgcolor="white",
        margin=dict(l=55, r=15, t=50 + 17 * n_lines + (25 if multi else 0), b=40),
        legend=dict(orientation="h", yanchor="top", y=-0.08 if spec.rows > 1 else -0.3, x=0, font=dict(size=11)),
        hoverlabel=dict(font_size=12), showlegend=True,
    )
    if any(p.kind == "surface" for p in spec.panels):
        # plotly clips a 3-D scene to its own rectangle: give the scenes the full width (no side
        # margins) and keep room for the y titles of the flat panels inside their domains instead
        fig.update_layout(margin=dict(l=4, r=4))
        for i, p in enumerate(spec.panels):
            if p.kind != "surface":
                fig.layout[_axis_ref(sum(q.kind != "surface" for q in spec.panels[:i]), "xaxis")].domain = \
                    (0.17, 0.8 if p.kind == "heatmap" else 0.98)
        fig.update_traces(colorbar=dict(x=0.83, xanchor="left"), selector=dict(type="heatmap"))
    return fig


# --------------------------------------------------------------------------------------------
# matplotlib (static export)


def _mpl_marker(symbol: str) -> str:
    return {"diamond": "D", "star": "*", "circle": "o"}.get(symbol, "o")


def to_matplotlib(spec: FigureSpec) -> Figure:
    """The static matplotlib figure of ``spec`` (same content as :func:`to_plotly`)."""
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib.figure import Figure
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch, Rectangle

    fig = Figure(figsize=spec.size, layout="constrained")
    if not spec.panels:
        ax = fig.add_subplot(111)
        ax.axis("off")
        ax.text(0.5, 0.5, spec.title, ha="center", va="center", fontsize=11, color="#555555", wrap=True)
        return fig
    axes: list[Any] = []
    for i, p in enumerate(spec.panels):
        proj = "3d" if p.kind == "surface" else None
        share = None
        if p.kind == "mask" and i % spec.cols:
            share = axes[i - i % spec.cols]
        axes.append(fig.add_subplot(spec.rows, spec.cols, i + 1, projection=proj, sharey=share))
    handles: list[Any] = []
    seen: set[str] = set()

    def add_handle(h: Any) -> None:
        if h.get_label() not in seen:
            seen.add(h.get_label())
            handles.append(h)

    fs = 9 if spec.cols > 1 else 10
    for ax, p in zip(axes, spec.panels):
        if p.kind == "xy":
            for s in p.series:
                (ln,) = ax.plot(s.x, s.y, "o-", color=s.color, lw=1.8, ms=4, label=s.name)
                add_handle(ln)
        elif p.kind == "heatmap" and p.grid is not None:
            g = p.grid
            x, y, z = np.asarray(g.x, float), np.asarray(g.y, float), np.asarray(g.z, float)
            uniform = all(v.size < 2 or np.allclose(np.diff(v), (v[-1] - v[0]) / (v.size - 1)) for v in (x, y))
            if uniform:  # imshow: extent half a cell beyond the first and last sample
                hx = (x[-1] - x[0]) / (x.size - 1) / 2 if x.size > 1 else 0.5
                hy = (y[-1] - y[0]) / (y.size - 1) / 2 if y.size > 1 else 0.5
                im = ax.imshow(z, origin="lower", aspect="auto", cmap=g.colorscale, interpolation="nearest",
                               extent=(x[0] - hx, x[-1] + hx, y[0] - hy, y[-1] + hy))
            else:  # cell edges midway between samples
                im = ax.pcolormesh(x, y, z, shading="nearest", cmap=g.colorscale)
            cb = fig.colorbar(im, ax=ax)
            cb.set_label(p.z_title)
        elif p.kind == "surface" and p.grid is not None:
            g = p.grid
            X, Y = np.meshgrid(np.asarray(g.x, float), np.asarray(g.y, float))
            Z = np.ma.masked_invalid(np.asarray(g.z, float))
            ax.plot_surface(X, Y, Z, cmap=g.colorscale, edgecolor="none", alpha=0.95)
            ax.set_zlabel(p.z_title.split(" - ")[0] + (" [" + p.z_title.rsplit("[", 1)[-1] if "[" in p.z_title
                                                       else ""), fontsize=fs - 1, labelpad=8)
            ax.view_init(elev=25, azim=-50)
        elif p.kind == "mask" and p.mask is not None:
            m = p.mask
            from matplotlib.colors import ListedColormap, to_rgba

            av, sv = np.asarray(m.x, float), np.asarray(m.y, float)
            if av.size and sv.size:
                ha = (av[1] - av[0]) / 2 if av.size > 1 else 0.5
                hs = (sv[1] - sv[0]) / 2 if sv.size > 1 else 0.5
                ax.imshow(m.inside.astype(np.uint8), origin="lower", aspect="auto", interpolation="nearest",
                          extent=(av[0] - ha, av[-1] + ha, sv[0] - hs, sv[-1] + hs), vmin=0, vmax=1,
                          cmap=ListedColormap([(0, 0, 0, 0), to_rgba(m.color, 1.0)]))
            if p.x_range is not None:
                ax.axvspan(p.x_range[0], m.scan[0], color=OUTSIDE_COLOR, lw=0, zorder=0)
                ax.axvspan(m.scan[1], p.x_range[1], color=OUTSIDE_COLOR, lw=0, zorder=0)
            if p.y_range is not None:
                ax.axhspan(p.y_range[0], m.scan[2], color=OUTSIDE_COLOR, lw=0, zorder=0)
                ax.axhspan(m.scan[3], p.y_range[1], color=OUTSIDE_COLOR, lw=0, zorder=0)
        for b in p.boxes:
            ax.add_patch(Rectangle((b.x0, b.y0), b.x1 - b.x0, b.y1 - b.y0, fill=False, zorder=3,
                                   ec=SATURATED_COLOR if b.saturated else BOX_COLOR,
                                   lw=2.4 if b.saturated else 1.2, ls="-." if b.saturated else "--"))
        for note in p.notes:
            ax.text(0.5, 0.03, note, transform=ax.transAxes, ha="center", va="bottom", fontsize=fs - 1,
                    color=SATURATED_COLOR, zorder=4, bbox=dict(fc="white", ec="none", alpha=0.8, pad=1.5))
        for mk in p.markers:
            mks = _mpl_marker(mk.symbol)
            if p.kind == "surface":
                if mk.z is not None:
                    face = "none" if mk.symbol == "circle" else mk.color
                    (h,) = ax.plot([mk.x], [mk.y], [mk.z], marker=mks, mfc=face, mec="black" if face != "none"
                                   else mk.color, mew=2.2 if face == "none" else 1.0,
                                   ms=14 if mk.symbol == "star" else 9, ls="", label=mk.name, zorder=5)
                else:
                    zz = np.asarray(p.grid.z, float) if p.grid is not None else np.zeros(1)
                    lo, hi = (np.nanmin(zz), np.nanmax(zz)) if np.isfinite(zz).any() else (0.0, 1.0)
                    (h,) = ax.plot([mk.x, mk.x], [mk.y, mk.y], [lo, hi], color=mk.color, lw=2.5, label=mk.name)
                add_handle(h)
                continue
            if mk.vline:
                ln = ax.axvline(mk.x, color=mk.color, ls="--", lw=1.3, label=mk.name)
                if mk.y is None:
                    add_handle(ln)
            if mk.y is not None:
                face = "none" if mk.symbol == "circle" else mk.color
                (h,) = ax.plot([mk.x], [mk.y], ls="", marker=mks, mfc=face, mec=mk.color if face == "none" else "black",
                               mew=2.2 if face == "none" else 1.0, ms=14 if mk.symbol == "star" else 9,
                               label=mk.name, zorder=5)
                add_handle(h)
        ax.set_xlabel(p.x_title, fontsize=fs)
        ax.set_ylabel(p.y_title, fontsize=fs)
        if len(spec.panels) > 1:
            ax.set_title(p.title, fontsize=fs)
        if p.kind != "surface":
            if p.x_range is not None:
                ax.set_xlim(*p.x_range)
            if p.y_range is not None:
                ax.set_ylim(*p.y_range)
            if p.kind == "xy":
                ax.grid(True, alpha=0.3)
                ax.ticklabel_format(axis="y", style="sci", scilimits=(-3, 5))
        ax.tick_params(labelsize=fs - 1)
    for e in spec.legend:
        if e.kind == "fill":
            handles.append(Patch(facecolor=e.color, edgecolor="none", label=e.label))
        else:
            sat = e.kind == "saturated"
            handles.append(Line2D([], [], color=e.color, lw=2.4 if sat else 1.2, ls="-." if sat else "--",
                                  label=e.label))
    if handles:
        fig.legend(handles=handles, loc="outside lower center", ncol=min(3, len(handles)), fontsize=fs,
                   frameon=False)
    import textwrap

    width = int(14 * spec.size[0])
    title = spec.title + "".join("\n" + "\n".join(textwrap.wrap("⚠ " + w, width)) for w in spec.warnings)
    fig.suptitle(title, fontsize=11)
    return fig


def export_format(path_or_name: str) -> str:
    """The export format of a file name by its suffix (``png``, ``svg`` or ``pdf``).

    Raises:
        ValueError: another suffix.
    """
    suffix = str(path_or_name).rsplit(".", 1)[-1].lower() if "." in str(path_or_name) else ""
    if suffix not in EXPORT_FORMATS:
        raise ValueError(f"a file name ending in {', '.join('.' + f for f in EXPORT_FORMATS)}")
    return suffix


def export(spec: FigureSpec, fmt: str = "png", dpi: int = EXPORT_DPI) -> bytes:
    """``spec`` as a static file: ``"png"`` (``dpi`` dots per inch, recorded in the file), ``"svg"`` or
    ``"pdf"``. The explorer's downloads and ``paraspace sweep --plot`` both call this."""
    if fmt not in EXPORT_FORMATS:
        raise ValueError(f"fmt = {fmt!r} is invalid: one of {', '.join(EXPORT_FORMATS)}")
    fig = to_matplotlib(spec)
    buf = io.BytesIO()
    meta = {"svg": {"Date": None}, "pdf": {"CreationDate": None}}.get(fmt)
    fig.savefig(buf, format=fmt, dpi=dpi, metadata=meta)
    return buf.getvalue()

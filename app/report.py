"""The design report: one self-contained HTML page for one design or a set of designs.

A report holds, per design: its parameters (those that differ across the set highlighted), a top
view of the mechanism at its home pose (base circle, carriage arcs and radial rails, platform),
the workspace shell in the paper's four Fig. 3 views (isometric, top, bottom, side), every measure
with its definition (:mod:`paraspace.app.glossary`) and the certified volume bracket, the
orientation maps of Fig. 3 e-g with TI_1 and TI_2, and the explorer link that restores it. For a
set, a table across the designs comes first.

The page needs nothing from the network: pictures are PNG ``data:`` URIs, the style is inline, and
every text that comes from the user (a name) is escaped. It is laid out for print (A4, one design
per page; the browser's "Print to PDF" gives the PDF). ``paraspace report`` writes it from the
command line; the explorer's Share tab offers the same page for the current and pinned designs.

Every figure comes from a function that the explorer or the CLI already uses
(:func:`kinematics.shell.workspace_shell`, :func:`app.figures.orientation_spec`); the shell views
are drawn with matplotlib from the same mesh.
"""

from __future__ import annotations

import base64
import dataclasses
import html
import io
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from paraspace.kinematics.design import PARAMS, Design
from paraspace.kinematics.progress import Cancelled

from . import figures
from .glossary import DEFINITIONS
from .numfmt import significant

if TYPE_CHECKING:  # pragma: no cover - types only
    from paraspace.kinematics.bracket import VolumeBracket
    from paraspace.kinematics.measures import WorkspaceMeasures
    from paraspace.kinematics.orientation import OrientationResult, OrientationSettings
    from paraspace.kinematics.workspace import WorkspaceResult, WorkspaceSettings

__all__ = ["ReportEntry", "compute_entry", "report_html", "shell_views_png", "mechanism_png", "MAX_DESIGNS"]

#: Most designs in one report (each costs a workspace, its measures and its orientation maps).
MAX_DESIGNS = 8
#: Faces of the shell drawn in the report's views (matplotlib draws every face).
VIEW_FACES = 6000
#: The paper's four Fig. 3 views: name -> (elevation, azimuth) in degrees.
VIEWS: dict[str, tuple[float, float]] = {"isometric": (25.0, -60.0), "top": (90.0, -90.0),
                                         "bottom": (-90.0, -90.0), "side (x-z)": (0.0, -90.0)}


@dataclasses.dataclass(frozen=True)
class ReportEntry:
    """One design of a report and what was computed for it."""

    name: str
    design: Design
    result: WorkspaceResult
    measures: WorkspaceMeasures
    bracket: VolumeBracket | None
    orientation: OrientationResult | None
    link: str = ""


def compute_entry(name: str, design: Design, settings: WorkspaceSettings,
                  orientation: OrientationSettings | None, *, link: str = "",
                  cancel: Any = None, say: Callable[[str], None] | None = None) -> ReportEntry:
    """Compute what the report shows of ``design`` (``orientation=None``: no orientation maps);
    ``say`` is told each step in words; :class:`~kinematics.progress.Cancelled` once ``cancel`` is set."""
    from paraspace.kinematics.bracket import bracket_of
    from paraspace.kinematics.measures import measure_workspace
    from paraspace.kinematics.orientation import orientation_workspace
    from paraspace.kinematics.workspace import compute_workspace

    def step(text: str) -> None:
        if cancel is not None and cancel.is_set():
            raise Cancelled()
        if say is not None:
            say(f"{name}: {text}")

    step("computing the workspace")
    res = compute_workspace(design, settings, cancel=cancel)
    step("measuring it")
    m = measure_workspace(res, cancel=cancel)
    br = None
    if settings.joints.min_distance == 0.0:
        step("certifying its volume")
        br = bracket_of(res, cancel=cancel)
    ori = None
    if orientation is not None:
        step("computing the orientation maps")
        ori = orientation_workspace(design, orientation, cancel=cancel)
    return ReportEntry(name, design, res, m, br, ori, link)


def _png(fig: Any) -> bytes:
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=110, bbox_inches="tight")
    return buf.getvalue()


def shell_views_png(result: WorkspaceResult) -> bytes:
    """The workspace shell of ``result`` in the four :data:`VIEWS` (a 2 x 2 PNG), coloured by
    height as in the explorer; an empty workspace gives a picture that says so."""
    from matplotlib.figure import Figure
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection

    from paraspace.kinematics.shell import workspace_shell

    fig = Figure(figsize=(8.0, 6.6))
    if result.voxels == 0:
        ax = fig.add_subplot(111)
        ax.axis("off")
        ax.text(0.5, 0.5, "empty workspace", ha="center", va="center", fontsize=14)
        return _png(fig)
    mesh = workspace_shell(result, max_faces=VIEW_FACES, color_by_z=True, reduction="remesh", volume_rtol=1e-2)
    tris = mesh.vertices[mesh.faces]
    visual: Any = mesh.visual
    colours = np.asarray(visual.vertex_colors, float)[mesh.faces].mean(axis=1) / 255.0
    lo, hi = mesh.vertices.min(axis=0), mesh.vertices.max(axis=0)
    for k, (title, (elev, azim)) in enumerate(VIEWS.items()):
        ax = fig.add_subplot(2, 2, k + 1, projection="3d")
        ax.add_collection3d(Poly3DCollection(tris, facecolors=colours, edgecolors="none", linewidths=0))
        ax.set_xlim(lo[0], hi[0])
        ax.set_ylim(lo[1], hi[1])
        ax.set_zlim(lo[2], hi[2])
        ax.set_box_aspect(tuple(np.maximum(hi - lo, 1e-9)))
        ax.view_init(elev=elev, azim=azim)
        # seen from below, the x axis (ticks and label) runs along the top edge: the title goes above it
        ax.set_title(title, fontsize=10, pad=22 if elev < 0 else 6)
        ax.tick_params(labelsize=6)
        # label the two axes the view shows; the one seen end-on has no readable ticks
        hidden = "z" if abs(elev) == 90.0 else ("y" if elev == 0.0 else "")
        for axis in "xyz":
            if axis == hidden:
                getattr(ax, f"set_{axis}ticks")([])
            else:
                getattr(ax, f"set_{axis}label")(axis, fontsize=8)
    fig.subplots_adjust(wspace=0.05, hspace=0.25)
    return _png(fig)


def mechanism_png(design: Design) -> bytes:
    """A top view of ``design`` at its home pose (:func:`mechanism_figure`) as a PNG."""
    return _png(mechanism_figure(design))


def mechanism_figure(design: Design) -> Any:
    """A top view of ``design`` at its home pose: the base circle, each carriage's arc and radial
    rail (its strokes), the U joints at zero carriage values and the platform's six joints; each
    chain named outside the middle of its arc, the legend below the axes."""
    from matplotlib.figure import Figure

    from paraspace.kinematics.geometry import base_points, carriage_rails, platform_points_local

    fig = Figure(figsize=(3.6, 3.6))
    ax = fig.add_subplot(111)
    t = np.linspace(0.0, 2.0 * np.pi, 181)
    ax.plot(design.r * np.cos(t), design.r * np.sin(t), color="#bbbbbb", lw=0.8, label="base circle r")
    rails = carriage_rails(design)
    for i in range(3):
        ax.plot(*rails["arcs"][i, :, :2].T, color="#0072B2", lw=3, label="arc stroke" if i == 0 else None)
        ax.plot(*rails["radials"][i, :, :2].T, color="#D55E00", lw=2, label="radial stroke" if i == 0 else None)
        mid = rails["arcs"][i, len(rails["arcs"][i]) // 2, :2] * 1.08
        ux, uy = mid / max(float(np.hypot(*mid)), 1e-9)  # the label stands outside its arc, away from it
        ax.annotate(f"chain {i + 1}", (float(mid[0]), float(mid[1])), fontsize=7,
                    ha="left" if ux > 0.35 else ("right" if ux < -0.35 else "center"),
                    va="bottom" if uy > 0.35 else ("top" if uy < -0.35 else "center"))
    base = base_points(design, np.zeros(3), np.zeros(3)).reshape(-1, 3)
    ax.plot(base[:, 0], base[:, 1], "ks", ms=3, label="U joints (d = 0, eta = 0)")
    plat = platform_points_local(design).reshape(-1, 3)
    plat = plat[np.argsort(np.arctan2(plat[:, 1], plat[:, 0]))]  # the hexagon's corners in turn
    ax.fill(plat[:, 0], plat[:, 1], color="#009E73", alpha=0.35, label="platform (radius a)")
    # room for the chain labels (outside their arcs' middles, which autoscaling ignores)
    lim = 1.5 * float(max(np.abs(rails["arcs"][:, :, :2]).max(), np.abs(plat[:, :2]).max()))
    ax.set_xlim(-lim, lim)
    ax.set_ylim(-lim, lim)
    ax.set_aspect("equal")
    ax.set_xlabel("x", fontsize=8)
    ax.set_ylabel("y", fontsize=8)
    ax.tick_params(labelsize=7)
    # below the axes: inside, it covered chain 3's rails and label
    ax.legend(fontsize=6, loc="upper center", bbox_to_anchor=(0.5, -0.14), ncol=2, frameon=False)
    ax.set_title("mechanism, top view", fontsize=9)
    return fig


def _img(png: bytes, alt: str, width: str = "100%") -> str:
    data = base64.b64encode(png).decode("ascii")
    return f'<img alt="{html.escape(alt)}" src="data:image/png;base64,{data}" style="width:{width}">'


def _n(v: float | None, digits: int = 4) -> str:
    return "-" if v is None or not np.isfinite(v) else significant(float(v), digits)


def _measure_rows(e: ReportEntry) -> list[tuple[str, str, str]]:
    """(name, value, definition) of every measure the report shows for ``e``."""
    m = e.measures
    rows = [("volume V", f"{_n(e.result.volume)} units³ (h = {e.result.grid.h:g})", DEFINITIONS["volume"])]
    if e.bracket is not None:
        rows.append(("certified bracket", f"{_n(e.bracket.volume_inner)} ≤ V ≤ {_n(e.bracket.volume_outer)} units³",
                     DEFINITIONS["bracket"]))
    rows += [
        ("boundary", ("complete" if m.boundary_complete else f"incomplete: {m.completeness_reason}"),
         DEFINITIONS["boundary"]),
        ("pieces", str(m.pieces), DEFINITIONS["pieces"]),
        ("fragments", f"{m.fragments} ({100 * m.fragment_volume_fraction:.2f} % of V)", DEFINITIONS["fragments"]),
        ("genus (stable)", str(m.stable_genus), DEFINITIONS["stable_genus"]),
        ("hollowness", _n(m.hollowness, 3), DEFINITIONS["hollowness"]),
        ("voids", f"{m.voids} ({100 * m.void_ratio:.2f} % of volume)", DEFINITIONS["voids"]),
        ("solidity", _n(m.solidity, 3), DEFINITIONS["solidity"]),
        ("footprint", _n(e.design.r + e.design.l_min + e.design.l_s), DEFINITIONS["footprint"]),
        ("raw voxel counts", f"genus {m.genus}, {m.components} components (change with h)",
         DEFINITIONS["components"]),
    ]
    if e.orientation is not None:
        sat = {x.index for x in figures.orientation_saturation(e.orientation)}
        for key in ("TI_1", "TI_2"):
            v = e.orientation.ti1 if key == "TI_1" else e.orientation.ti2
            rows.append((key, f"{'≥ ' if key in sat else ''}{_n(v)} deg·units (z0 = {e.orientation.settings.z0:g})",
                         DEFINITIONS[key]))
    return rows


def _comparison_table(entries: Sequence[ReportEntry]) -> str:
    """The table across the designs: parameters (differing ones highlighted) and the main measures."""
    head = "".join(f"<th>{html.escape(e.name)}</th>" for e in entries)
    body = []
    for key, spec in PARAMS.items():
        vals = [getattr(e.design, key) for e in entries]
        differ = len(set(vals)) > 1
        cls = ' class="differs"' if differ else ""
        body.append(f"<tr{cls}><th>{html.escape(spec.label)}</th>"
                    + "".join(f"<td>{significant(v, 4)}</td>" for v in vals) + "</tr>")
    names = ("volume V", "certified bracket", "boundary", "hollowness", "TI_1", "TI_2")
    rows: dict[str, list[str]] = {name: [] for name in names}
    for e in entries:
        got = {n: v for n, v, _ in _measure_rows(e)}
        for name in rows:
            rows[name].append(got.get(name, "-"))
    for name, vals in rows.items():
        body.append(f"<tr><th>{html.escape(name)}</th>" + "".join(f"<td>{html.escape(v)}</td>" for v in vals) + "</tr>")
    return (f'<table class="compare"><tr><th></th>{head}</tr>{"".join(body)}</table>'
            '<p class="note">Highlighted rows: the parameters that differ across the designs.</p>')


STYLE = """
body{font-family:system-ui,-apple-system,'Segoe UI',Roboto,sans-serif;color:#111;max-width:60em;margin:1.5em auto;
padding:0 1em;line-height:1.4}
h1{font-size:1.5em;margin-bottom:.2em}h2{font-size:1.25em;border-bottom:1px solid #ccc;padding-bottom:.2em}
table{border-collapse:collapse;margin:.6em 0;font-size:.92em}th,td{border:1px solid #ccc;padding:.25em .5em;
text-align:left;vertical-align:top}td.def{color:#444;font-size:.88em}tr.differs{background:#fff3c4}
.note{color:#555;font-size:.88em}.row{display:flex;gap:1em;align-items:flex-start}.row>div{flex:1}
a{word-break:break-all}
@media print{@page{size:A4;margin:14mm}body{margin:0;max-width:none}section.design{break-before:page}
a{color:#111}}
"""


def report_html(entries: Sequence[ReportEntry], *, title: str = "paraspace design report", version: str = "") -> str:
    """The report page of ``entries`` (see the module docstring)."""
    if not entries:
        raise ValueError("designs: a report needs at least 1 design")
    if len(entries) > MAX_DESIGNS:
        raise ValueError(f"designs: {len(entries)} given; valid range [1, {MAX_DESIGNS}]")
    parts = [f"<!doctype html><html lang='en'><head><meta charset='utf-8'><title>{html.escape(title)}</title>"
             f"<style>{STYLE}</style></head><body><h1>{html.escape(title)}</h1>",
             f"<p class='note'>3-(arc-P, P, 2-(UPS)) redundant parallel mechanism; lengths in the paper's units, "
             f"angles in degrees. Written by paraspace {html.escape(version)}; every picture and number below was "
             "computed for this page.</p>"]
    if len(entries) > 1:
        parts.append("<h2>The designs side by side</h2>" + _comparison_table(entries))
    for e in entries:
        parts.append(f"<section class='design'><h2>{html.escape(e.name)}</h2>")
        rows = "".join(f"<tr><th>{html.escape(spec.label)}</th><td>{significant(getattr(e.design, k), 4)}</td>"
                       f"<td class='def'>{html.escape(spec.description)}</td></tr>" for k, spec in PARAMS.items())
        rows += (f"<tr><th>eta range</th><td>{html.escape(e.design.eta_range)}</td>"
                 "<td class='def'>arc stroke centred on the chain or starting at zero</td></tr>")
        parts.append(f"<div class='row'><div><table><tr><th>parameter</th><th>value</th><th></th></tr>{rows}"
                     f"</table></div><div>{_img(mechanism_png(e.design), 'mechanism top view')}</div></div>")
        parts.append("<h3>Workspace (Fig. 3 views)</h3>" + _img(shell_views_png(e.result), "workspace shell views"))
        mrows = "".join(f"<tr><th>{html.escape(n)}</th><td>{html.escape(v)}</td><td class='def'>{html.escape(d)}</td>"
                        "</tr>" for n, v, d in _measure_rows(e))
        parts.append(f"<h3>Measures</h3><table><tr><th>measure</th><th>value</th><th>definition</th></tr>{mrows}</table>")
        if e.orientation is not None:
            png = figures.export(figures.orientation_spec(e.orientation), "png", dpi=110)
            parts.append("<h3>Orientation workspace (Fig. 3 e-g)</h3>" + _img(png, "orientation maps"))
            if {x.index for x in figures.orientation_saturation(e.orientation)}:
                parts.append(f"<p class='note'>{html.escape(figures.saturation_warning(e.orientation))}</p>")
        if e.link:
            parts.append(f"<p>Open in the explorer: <a href='{html.escape(e.link, quote=True)}'>"
                         f"{html.escape(e.link)}</a></p>")
        parts.append("</section>")
    parts.append("</body></html>")
    return "".join(parts)
